"""Where the studies find the committed files and the built FMUs, in either layout:

* a **source checkout** (a clone, or an editable install of one): ``regression/`` and
  ``dist/`` at the repository root;
* an **installed wheel**: the references are package data (``drive_rattle_cosim/
  references/``, mapped there by ``[tool.setuptools.package-dir]`` in pyproject.toml) and the
  FMUs are looked for in ``./dist`` of the working directory (where ``drive-rattle-build``
  writes them by default).
"""

from __future__ import annotations

from pathlib import Path

_PACKAGE = Path(__file__).resolve().parent
#: The repository root of a source checkout (meaningless in an installed wheel).
ROOT = _PACKAGE.parents[1]
#: True in a source checkout, False in an installed wheel.
CHECKOUT = (ROOT / "pyproject.toml").is_file() and (ROOT / "fmu_src" / "rattle_model").is_dir()
#: The committed regression references, a folder per model.
REFERENCES = ROOT / "regression" if CHECKOUT else _PACKAGE / "references"
#: The build's default output folder: the FMUs the studies run by default.
DIST = ROOT / "dist" if CHECKOUT else Path("dist")
