"""The README's commands and code are what CI and users run."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")


def shell_blocks():
    return re.findall(r"```sh\n(.*?)```", README, flags=re.S)


def test_ci_runs_the_readme_test_command():
    test_cmd = next(b.strip() for b in shell_blocks() if "pytest" in b)
    assert test_cmd in (ROOT / ".ci" / "run").read_text()


def test_readme_main_command_runs_the_paper_scenario():
    main_cmd = next(b.strip() for b in shell_blocks() if "paper_scenario" in b)
    assert "examples/paper_scenario.py" in main_cmd and "pip install" in main_cmd


def test_readme_python_blocks_run():
    for block in re.findall(r"```python\n(.*?)```", README, flags=re.S):
        exec(compile(block, "README.md", "exec"), {})
