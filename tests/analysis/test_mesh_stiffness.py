"""The static mesh stiffness study (drive_rattle_cosim/mesh_stiffness.py): its block in
docs/model.md is a fresh run's, and its update replaces that block and nothing else."""

from __future__ import annotations

from pathlib import Path

import pytest

from drive_rattle_cosim import mesh_stiffness

MODEL_DOC = Path(__file__).resolve().parents[2] / "docs" / "model.md"


def test_the_documented_stiffness_tables_are_a_fresh_runs():
    text = MODEL_DOC.read_text(encoding="utf-8")
    assert mesh_stiffness.update(text, mesh_stiffness.report()) == text


def test_the_update_replaces_the_block_and_nothing_else():
    text = "before\n<!-- BEGIN mesh stiffness -->\nold\n<!-- END mesh stiffness -->\nafter\n"
    assert mesh_stiffness.update(text, "new") == (
        "before\n<!-- BEGIN mesh stiffness -->\nnew\n<!-- END mesh stiffness -->\nafter\n")
    with pytest.raises(ValueError, match="needs one block"):
        mesh_stiffness.update("no block here", "new")


def test_a_file_without_the_block_is_refused_in_one_line(tmp_path, capsys):
    doc = tmp_path / "doc.md"
    doc.write_text("no block here\n", encoding="utf-8")
    assert mesh_stiffness.main(["--angles", "1", "--update", str(doc)]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith("mesh_stiffness: ") and "\n" not in err
    assert doc.read_text(encoding="utf-8") == "no block here\n"
