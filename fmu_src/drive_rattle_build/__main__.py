"""``python -m drive_rattle_build``: the build's command line (``cli.main``)."""

import sys

from .cli import main

sys.exit(main())
