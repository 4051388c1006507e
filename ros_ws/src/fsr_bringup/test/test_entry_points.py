"""The console scripts' start and end: the calling process of an analysis never imports matplotlib (its figures are
drawn by workers of a fork server started first), and :func:`end_process` ends without the interpreter's teardown
but after the exit handlers, with the output flushed and the code given."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from fsr_bringup.analysis.figure_jobs import FIGURES_MODULE


def run_python(code: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], cwd=cwd, capture_output=True, text=True,
                          timeout=120)


@pytest.mark.skipif(len(os.sched_getaffinity(0)) < 2, reason="one core: the figures are drawn in this process")
def test_an_in_process_flight_with_its_analysis_does_not_import_matplotlib_here(tmp_path: Path) -> None:
    done = run_python(f"""
        import sys
        from fsr_bringup.cli.fly_cli import main
        code = main(["ex4_geometric", "--in-process", "--duration", "1", "--out", "runs/a.mcap"])
        assert code == 0, code
        print(sorted(m for m in sys.modules if m.split(".")[0] == "matplotlib" or m == "{FIGURES_MODULE}"))
        """, tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[-1] == "[]"
    assert (tmp_path / "runs" / "a" / "pose.png").stat().st_size > 0  # drawn, by the workers


def test_end_process_runs_the_exit_handlers_flushes_and_exits_with_the_code(tmp_path: Path) -> None:
    done = run_python("""
        import atexit
        import sys
        from pathlib import Path
        from fsr_bringup.cli.entry_points import end_process
        atexit.register(lambda: Path("handler_ran").write_text("yes"))
        sys.stdout.write("unflushed output")
        end_process(3)
        """, tmp_path)
    assert done.returncode == 3
    assert done.stdout == "unflushed output"
    assert (tmp_path / "handler_ran").read_text() == "yes"


def test_end_process_exits_normally_while_another_thread_runs(tmp_path: Path) -> None:
    done = run_python("""
        import threading
        import time
        from pathlib import Path
        from fsr_bringup.cli.entry_points import end_process
        def late_writer():
            time.sleep(0.5)  # still running when end_process is called: a normal exit waits for it
            Path("thread_finished").write_text("yes")
        threading.Thread(target=late_writer).start()
        end_process(4)
        """, tmp_path)
    assert done.returncode == 4
    assert (tmp_path / "thread_finished").read_text() == "yes"


def test_the_fork_servers_warm_up_draws_in_memory_only(tmp_path: Path, monkeypatch) -> None:
    """The figure the fork server draws to fill matplotlib's caches is written nowhere."""
    from fsr_bringup.analysis.figures import warm_up

    monkeypatch.chdir(tmp_path)
    warm_up()
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("arguments", "started"), [
    (["ex4_geometric", "--in-process"], True),
    (["ex4_geometric", "--in-process", "--no-analysis"], False),
    (["--help"], False),
])
def test_fsr_fly_starts_the_figures_fork_server_first_unless_told_there_is_no_analysis(
        arguments: list[str], started: bool, monkeypatch) -> None:
    from fsr_bringup.cli import entry_points, fly_cli

    calls = []
    monkeypatch.setattr(entry_points, "prepare_workers", lambda: calls.append("prepare"))
    monkeypatch.setattr(fly_cli, "main", lambda: 0)
    monkeypatch.setattr(entry_points, "end_process", lambda code: calls.append(code))
    monkeypatch.setattr(sys, "argv", ["fsr-fly", *arguments])
    entry_points.fly()
    assert calls == (["prepare", 0] if started else [0])
