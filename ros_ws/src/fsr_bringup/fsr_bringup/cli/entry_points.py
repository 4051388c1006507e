"""The console scripts that draw figures, ``fsr-fly`` and ``fsr-analyze``: the figures' fork server is started
before anything heavy is imported, and the process ends without the interpreter's teardown (:func:`end_process`).
Their ``main`` functions stay plain functions that return an exit code (tests and scripts call them)."""

from __future__ import annotations

import atexit
import os
import sys
import threading
from typing import NoReturn

from fsr_bringup.analysis.figure_jobs import prepare_workers
from fsr_bringup.analysis.figure_options import NO_ANALYSIS

HELP = frozenset(("-h", "--help"))


def end_process(code: int) -> NoReturn:
    """Exit with ``code`` once the exit handlers have run and the output is flushed, skipping the interpreter's
    teardown: freeing every module's objects one by one (numba's, LLVM's, matplotlib's) took 0.3 s after a flight
    with its figures, in a process about to end. With another thread still running, the normal exit (it joins
    the thread)."""
    if threading.active_count() > 1:
        sys.exit(code)
    atexit._run_exitfuncs()  # what the normal exit runs too: logging's flush, multiprocessing's clean-up
    exit_now(code)


def exit_now(code: int) -> NoReturn:
    """Flush the standard streams and end the process with ``code`` at once: no more exit handlers, no teardown."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed pipe (fsr-fly ... | head) or stream: nothing more to say
            pass
    os._exit(code)


def fly() -> NoReturn:
    """``fsr-fly``: :func:`fsr_bringup.cli.fly_cli.main`, with the figures' fork server started first (unless the
    arguments say :data:`NO_ANALYSIS` or ask for help: a guess from the words before they are parsed, ``main``
    decides; a wrong guess costs an idle process until the command ends)."""
    arguments = sys.argv[1:]
    if NO_ANALYSIS not in arguments and not HELP.intersection(arguments):
        prepare_workers()
    from fsr_bringup.cli.fly_cli import main

    end_process(main())


def analyze() -> NoReturn:
    """``fsr-analyze``: :func:`fsr_bringup.cli.analyze_cli.main` (it starts the fork server itself, before it
    reads the recordings)."""
    from fsr_bringup.cli.analyze_cli import main

    end_process(main())
