"""Command-line parsing shared by every fsr console script: argument errors are one line, exit code 2."""

from __future__ import annotations

import argparse
from typing import NoReturn

from fsr_sim.contract import EXIT_CONFIG_ERROR


class ArgumentParser(argparse.ArgumentParser):
    """``argparse.ArgumentParser`` whose errors are one line naming the argument, not the full usage.

    ``fsr-fly ex4_geometric --duration abc`` prints
    ``fsr-fly: error: argument --duration: invalid float value: 'abc' (see fsr-fly --help)`` and exits 2.
    """

    def error(self, message: str) -> NoReturn:
        one_line = " ".join(message.split())
        self.exit(EXIT_CONFIG_ERROR, f"{self.prog}: error: {one_line} (see {self.prog} --help)\n")
