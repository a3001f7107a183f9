"""The command lines' parser: a request refused before any work is one line on stderr and exit
status 2 (argparse's convention), whether argparse refuses its syntax or the tool its values."""

from __future__ import annotations

import argparse

#: Exit status of a request refused before any work (argparse's own).
BAD_REQUEST = 2


class Parser(argparse.ArgumentParser):
    """An ArgumentParser whose refusal is one line, ``<prog>: error: <sentence>``, instead of
    the usage text and the sentence (``--help`` gives the usage)."""

    def error(self, message: str):
        self.exit(BAD_REQUEST, f"{self.prog}: error: {message}\n")
