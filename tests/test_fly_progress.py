"""fsr-fly's progress: on a terminal in both modes (also with --quiet, which hides node logs only); in a CI log
or a pipe, a plain line every PLAIN_PROGRESS_EVERY_S of wall time."""

from __future__ import annotations

import os
import pty
import subprocess
import sys
from pathlib import Path

import pytest

from fsr_bringup.runner import flight as flight_module

FLY = str(Path(sys.executable).parent / "fsr-fly")


def run_on_a_terminal(argv: list[str], cwd: Path, timeout: float = 180.0) -> tuple[int, str]:
    """Run ``argv`` with its stdout and stderr on a pseudo-terminal; (exit code, everything it wrote)."""
    master, slave = pty.openpty()
    process = subprocess.Popen(argv, cwd=cwd, stdin=subprocess.DEVNULL, stdout=slave, stderr=slave,
                               env={**os.environ, "MPLBACKEND": "Agg"})
    os.close(slave)
    chunks = []
    try:
        while True:
            try:
                data = os.read(master, 65536)
            except OSError:  # the terminal closed: the process is gone
                break
            if not data:
                break
            chunks.append(data)
        return process.wait(timeout=timeout), b"".join(chunks).decode(errors="replace")
    finally:
        os.close(master)
        if process.poll() is None:
            process.kill()


def test_in_process_flight_shows_its_progress_on_a_terminal_even_quiet(tmp_path):
    code, out = run_on_a_terminal([FLY, "ex4_geometric", "--in-process", "--quiet", "--duration", "3",
                                   "--no-analysis", "--out", str(tmp_path / "a.mcap")], tmp_path)
    assert code == 0, out
    assert "t =   1.999 / 3.000 s   real-time factor" in out, out  # after each chunk of 1000 steps
    assert "\r\x1b[K" in out  # rewritten in place, and cleared at the end


@pytest.mark.graph
def test_graph_flight_shows_its_progress_on_a_terminal_even_quiet(tmp_path):
    code, out = run_on_a_terminal([FLY, "ex4_geometric", "--quiet", "--duration", "2", "--no-analysis",
                                   "--out", str(tmp_path / "g.mcap")], tmp_path)
    assert code == 0, out
    assert " / 2.000 s   real-time factor" in out and "[controller]" not in out, out


def test_off_a_terminal_a_plain_progress_line_every_period(monkeypatch, capsys):
    clock = [100.0]
    monkeypatch.setattr(flight_module.time, "monotonic", lambda: clock[0])
    console = flight_module.Console(quiet=True)
    assert not console.tty
    period = flight_module.PLAIN_PROGRESS_EVERY_S
    for step in range(1, 26):  # 25 s of wall time, a progress call every second
        clock[0] = 100.0 + step
        console.flight_progress(float(step), 50.0, float(step))
    lines = capsys.readouterr().out.splitlines()
    assert lines == [f"fsr-fly: t = {t:7.3f} / 50.000 s   real-time factor  1.00" for t in (period, 2 * period)]
