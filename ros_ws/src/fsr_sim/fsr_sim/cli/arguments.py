"""Command-line parsing shared by every fsr console script: argument errors are one line, exit code 2."""

from __future__ import annotations

import argparse
import shlex
import sys
import textwrap
from collections.abc import Callable
from typing import Any, NoReturn

from fsr_sim.contract import EXIT_CONFIG_ERROR


def plain_description(doc: str) -> str:
    """What a command does, from the first paragraph of its module docstring, as plain text: the
    ``` ``fsr-fly SCENARIO``: ``` lead (``--help`` shows the usage above it) and reST markup dropped."""
    first = " ".join(doc.strip().split("\n\n")[0].split())
    if first.startswith("``") and "``: " in first:
        first = first.split("``: ", 1)[1]
    first = first.replace("``", "").replace(":mod:", "").replace("`", "")
    return textwrap.fill(first[:1].upper() + first[1:], 100)


def command_line(prog: str, argv: list[str] | None) -> str:
    """The command ``prog`` with its arguments ``argv`` (None: this process's), quoted as a shell would take it."""
    return " ".join(shlex.quote(word) for word in [prog, *(sys.argv[1:] if argv is None else argv)])


def argument_type(parse: Callable[[str], Any]) -> Callable[[str], Any]:
    """``parse`` as an argparse ``type=``: its ValueError's message becomes the argument's error (argparse
    would otherwise print only "invalid <name> value")."""
    def checked(text: str) -> Any:
        try:
            return parse(text)
        except ValueError as error:
            raise argparse.ArgumentTypeError(str(error)) from None

    checked.__name__ = parse.__name__
    return checked


def exit_codes_text(meanings: dict[int, str]) -> str:
    """The ``exit codes:`` lines of a command's ``--help`` (code -> what it means for this command)."""
    return "exit codes:\n" + "\n".join(f"  {code:<4}{meaning}" for code, meaning in meanings.items())


class ArgumentParser(argparse.ArgumentParser):
    """``argparse.ArgumentParser`` whose errors are one line naming the argument, not the full usage.

    ``fsr-fly ex4_geometric --duration abc`` prints
    ``fsr-fly: error: argument --duration: invalid float value: 'abc' (see fsr-fly --help)`` and exits 2.
    ``doc`` (the command's module docstring) gives the description (:func:`plain_description`) and
    ``exit_codes`` (code -> meaning) the end of the help.
    """

    def __init__(self, *args: object, doc: str | None = None, exit_codes: dict[int, str] | None = None,
                 **kwargs: object) -> None:
        if doc is not None:
            kwargs.setdefault("description", plain_description(doc))
        if exit_codes is not None:
            epilog = kwargs.get("epilog")
            kwargs["epilog"] = (f"{epilog}\n" if epilog else "") + exit_codes_text(exit_codes)
            kwargs.setdefault("formatter_class", argparse.RawDescriptionHelpFormatter)
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> NoReturn:
        one_line = " ".join(message.split())
        self.exit(EXIT_CONFIG_ERROR, f"{self.prog}: error: {one_line} (see {self.prog} --help)\n")
