"""The face suite's raw driver (tests/faces/raw_fmi.py) under the name the adversarial tools
import it by: they run as scripts and child processes with this folder on sys.path."""

import sys
from pathlib import Path

if not __package__:  # a script's import: the driver's package from the checkout's root
    sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from tests.faces.raw_fmi import *  # noqa: F403
from tests.faces.raw_fmi import _MODELS  # noqa: F401
