"""Drawing the figures (:mod:`fsr_bringup.analysis.figures`) in worker processes while the caller goes on.

A light module: it imports neither matplotlib nor the analysis (those only inside the functions that need them),
so that a command starts the fork server first thing (:func:`prepare_workers`: it imports the figures' modules,
about a second, while the command reads its scenario and flies). The calling process pays for matplotlib only
when it draws a figure itself (one core, or a figure registered at run time from outside fsr's modules,
docs/extending.md). The flights' arrays reach the workers through shared memory (:class:`SharedJob`).
"""

from __future__ import annotations

import io
import multiprocessing
import os
import pickle
import signal
import sys
import weakref
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace
from multiprocessing.shared_memory import SharedMemory
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from fsr_bringup.analysis.figure_options import FORMATS, FigureOptions
from fsr_sim.contract import WRENCH_CMD

if TYPE_CHECKING:
    from fsr_bringup.analysis.effective import EffectiveWrench
    from fsr_bringup.analysis.load import RecordedFlight

FIGURES_MODULE = "fsr_bringup.analysis.figures"
WORKER_MODULES = ["fsr_bringup.analysis.figure_server"]  # imported once by the fork server (the figures, warm)
MOST_WORKERS = 8  # about the figures a flight has: a worker more would only receive the job
# The order the workers draw the figures in, the slowest first (0.25-0.3 s each on a 30 s flight, the last two
# 0.07-0.1 s; measured on ex3, ex4, ex5 and the octocopter), so that the workers end together: in the registry's
# order one of two workers idled 0.13-0.18 s at the end of ex4's figures. Figures not named here come last.
SLOWEST_FIRST = ("external_wrench", "pose", "path", WRENCH_CMD.name, "errors", "rotors", "speed", "thrust_ratio",
                 "mass")


@dataclass
class Run:
    """One flight to draw: its label in legends, the decoded recording and its effective truth."""

    label: str
    flight: RecordedFlight
    effective: EffectiveWrench | None = None

    @classmethod
    def of(cls, flight: RecordedFlight, label: str | None = None) -> Run:
        from fsr_bringup.analysis.effective import effective_wrench

        return cls(label or flight.scenario_name, flight, effective_wrench(flight))


Job = tuple[list[Run], Path, FigureOptions]
_JOB: Job | None = None  # the figures' input, in a worker: set at its start
_JOB_MEMORY: SharedMemory | None = None


def _light(run: Run) -> Run:
    """``run`` with its flight's recording reduced to its name (what is sent to a worker process)."""
    from fsr_bringup.analysis.load import RecordingName

    recording = run.flight.recording
    name = RecordingName(getattr(recording, "path", None), bool(getattr(recording, "truncated", False)))
    return replace(run, flight=replace(run.flight, recording=name))


class SharedJob:
    """A job's arrays in one block of shared memory, the rest pickled (``head``, pickle protocol 5 with the arrays
    out of band): each worker maps the arrays instead of receiving its own copy through a pipe (31 MB for a 30 s
    flight, 0.18 s of the caller's time for two workers). :meth:`release` frees the block."""

    def __init__(self, job: Job) -> None:
        buffers: list[pickle.PickleBuffer] = []
        head = io.BytesIO()
        _ArraysOutOfBand(head, protocol=5, buffer_callback=buffers.append).dump(job)
        self.head = head.getvalue()
        raw = [buffer.raw() for buffer in buffers]
        self.memory = SharedMemory(create=True, size=max(1, sum(view.nbytes for view in raw)))
        self.spans: list[tuple[int, int]] = []
        offset = 0
        for view in raw:
            self.memory.buf[offset:offset + view.nbytes] = view
            self.spans.append((offset, view.nbytes))
            offset += view.nbytes
        self.release = weakref.finalize(self, _free, self.memory)  # also if the job is dropped unfinished

    def start_arguments(self) -> tuple[str, bytes, list[tuple[int, int]]]:
        return self.memory.name, self.head, self.spans


class _ArraysOutOfBand(pickle.Pickler):
    """Every array out of band, strided views too (numpy pickles those in band: the effective truth's columns of
    one table were 5 MB of ``head``), as a contiguous copy."""

    def reducer_override(self, obj: object) -> object:
        if isinstance(obj, np.ndarray) and not obj.flags.forc and not obj.dtype.hasobject:
            return np.ascontiguousarray(obj).__reduce_ex__(5)
        return NotImplemented


def _free(memory: SharedMemory) -> None:
    memory.close()
    memory.unlink()


def _start_worker(name: str, head: bytes, spans: list[tuple[int, int]]) -> None:
    """A worker's start: the job, its arrays read-only views of the shared block (a figure cannot change what
    the others draw)."""
    global _JOB, _JOB_MEMORY
    _JOB_MEMORY = SharedMemory(name=name)  # kept: the job's arrays are views of it
    _JOB = pickle.loads(head, buffers=[_JOB_MEMORY.buf[start:start + size].toreadonly() for start, size in spans])


def _figure_names() -> list[str]:
    """The figures a worker draws, in the registry's order."""
    from fsr_bringup.analysis.figures import FIGURES

    return list(FIGURES)


def _draw_in_worker(name: str) -> tuple[list[Path], list[str]]:
    from fsr_bringup.analysis.figures import draw_and_save

    return draw_and_save(name, *_JOB)


@contextmanager
def _main_left_out() -> Iterator[None]:
    """While the fork server and the workers start: the caller's ``__main__`` is not run again in them (a started -
    not forked - worker imports the main script or module first, which would fly a user's script, unguarded by
    ``if __name__ == "__main__"``, once more per worker; they need nothing of it), and they ignore SIGINT from
    their start (an ignored signal stays ignored across exec: a Ctrl-C at the terminal, which reaches the whole
    process group, leaves no traceback of theirs; the pool ends them)."""
    main = sys.modules.get("__main__")
    saved = {name: main.__dict__[name] for name in ("__file__", "__spec__") if name in main.__dict__} if main else {}
    if main is not None:
        main.__dict__.pop("__file__", None)
        main.__spec__ = None
    try:
        handler = signal.signal(signal.SIGINT, signal.SIG_IGN)
    except ValueError:  # not the main thread: signals are the main thread's business
        handler = None
    try:
        yield
    finally:
        if handler is not None:
            signal.signal(signal.SIGINT, handler)
        if main is not None:
            main.__dict__.pop("__spec__", None)
            main.__dict__.update(saved)


def prepare_workers() -> None:
    """Start the fork server now (it imports the figures' modules, about a second) so that it is ready when the
    figures are drawn: ``fsr-fly`` calls this first, ``fsr-analyze`` before reading the recordings."""
    if _worker_context() is not None and "forkserver" in multiprocessing.get_all_start_methods():
        from multiprocessing import forkserver

        with _main_left_out():
            forkserver.ensure_running()


def _worker_context() -> multiprocessing.context.BaseContext | None:
    """Workers started by a fork server (it imports the figures' modules once; its children fork from it, a
    single-threaded process: no fork of this one, whatever threads it runs), else spawned; None where neither
    exists."""
    methods = multiprocessing.get_all_start_methods()
    if "forkserver" in methods:
        context = multiprocessing.get_context("forkserver")
        context.set_forkserver_preload(WORKER_MODULES)
        return context
    return multiprocessing.get_context("spawn") if "spawn" in methods else None


def _registered_here() -> dict | None:
    """The figure registry of this process where it imported the figures (and may have registered its own), else
    None: then the built-in figures are all there is, and a worker names them."""
    figures = sys.modules.get(FIGURES_MODULE)
    return None if figures is None else figures.FIGURES


class FigureJob:
    """Figures being drawn: :meth:`result` waits for them. With more than one core they are drawn by worker
    processes (one figure each, the slowest first, at most one worker per core; started by a fork server,
    :func:`_worker_context`: this process, which may run threads, is never forked) while the caller goes on (the
    analysis computes its metrics meanwhile); otherwise here, one after the other, when :meth:`result` is called.

    A figure whose function does not come from fsr's own modules (registered at run time, docs/extending.md) is
    drawn here: a worker imports the figures afresh and would not know it."""

    def __init__(self, runs: list[Run], out_dir: Path, options: FigureOptions) -> None:
        self.job = (runs, out_dir, options)
        self.pool = self.pending = None
        self.names: list[str] = []
        self.remote: list[str] = []
        workers = min(MOST_WORKERS, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else 1)
        context = _worker_context() if workers > 1 else None
        if context is None:
            return
        self.shared = SharedJob(([_light(run) for run in runs], out_dir, options))
        with _main_left_out():
            self.pool = context.Pool(workers, initializer=_start_worker, initargs=self.shared.start_arguments())
        registry = _registered_here()
        if registry is None:
            self.names = self.remote = self.pool.apply(_figure_names)
        else:
            self.names = list(registry)
            self.remote = [name for name in registry
                           if getattr(registry[name], "__module__", "").startswith("fsr_bringup.")]
        self.remote = sorted(self.remote, key=drawing_rank)
        self.pending = self.pool.map_async(_draw_in_worker, self.remote, chunksize=1)

    def result(self) -> tuple[list[Path], list[str]]:
        """(written files, notes for skipped figures), in the registry's order."""
        if self.pool is None:
            from fsr_bringup.analysis.figures import FIGURES, draw_and_save

            results = [draw_and_save(name, *self.job) for name in FIGURES]
        else:
            try:
                local = {}
                if len(self.remote) < len(self.names):
                    from fsr_bringup.analysis.figures import draw_and_save

                    local = {name: draw_and_save(name, *self.job) for name in self.names if name not in self.remote}
                drawn = dict(zip(self.remote, self.pending.get(), strict=True))
            finally:
                self.pool.close()
                self.pool.join()
                self.shared.release()
            results = [drawn[name] if name in drawn else local[name] for name in self.names]
        written = [path for paths, _ in results for path in paths]
        return written, [note for _, notes in results for note in notes]


def drawing_rank(name: str) -> int:
    """Where figure ``name`` comes in :data:`SLOWEST_FIRST` (after all of it if it is not there)."""
    return SLOWEST_FIRST.index(name) if name in SLOWEST_FIRST else len(SLOWEST_FIRST)


def start_figures(runs: list[Run] | RecordedFlight, out_dir: Path, options: FigureOptions | None = None) -> FigureJob:
    """Start drawing every figure the runs allow into ``out_dir`` (:class:`FigureJob`)."""
    if not isinstance(runs, list | tuple):  # one flight
        runs = [Run.of(runs)]
    options = options or FigureOptions()
    unknown = [f for f in options.formats if f not in FORMATS]
    if unknown:
        raise ValueError(f"figure format(s) {', '.join(unknown)} not supported (use {', '.join(FORMATS)})")
    out_dir.mkdir(parents=True, exist_ok=True)
    return FigureJob(runs, out_dir, options)


def make_figures(runs: list[Run] | RecordedFlight, out_dir: Path, options: FigureOptions | None = None
                 ) -> tuple[list[Path], list[str]]:
    """Draw every figure the runs allow into ``out_dir``; returns (written files, notes for skipped ones)."""
    return start_figures(runs, out_dir, options).result()
