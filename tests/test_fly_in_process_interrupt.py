"""Ctrl-C (or SIGTERM) on ``fsr-fly --in-process``: exit 130 with one line, a closed recording of what was
flown, and its analysis saying where the flight was interrupted."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from fsr_sim.recording.reader import open_recording

FLY = str(Path(sys.executable).parent / "fsr-fly")


@pytest.mark.slow  # seconds of subprocesses, figures or flights: not for the fast tier
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_interrupted_in_process_flight_exits_130_with_a_closed_recording_and_its_analysis(tmp_path, signum):
    out = tmp_path / "run.mcap"
    # A long flight (the compiled loop flies 30 s in well under a second): the signal arrives mid-flight.
    process = subprocess.Popen([FLY, "ex4_geometric", "--in-process", "--duration", "300", "--out", str(out)],
                               cwd=tmp_path,
                               env={**os.environ, "MPLBACKEND": "Agg"}, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        deadline = time.monotonic() + 60.0
        while not (out.is_file() and out.stat().st_size > 1_000_000):  # recorded steps reach the file: flying
            assert process.poll() is None, process.communicate()
            assert time.monotonic() < deadline, "the flight did not start"
            time.sleep(0.05)
        process.send_signal(signum)
        stdout, stderr = process.communicate(timeout=120)
    finally:
        process.kill()
    assert process.returncode == 130, stdout + stderr
    assert "Traceback" not in stderr
    assert stderr.strip().splitlines() == [f"fsr-fly: ERROR: flight interrupted (received {signum.name})"]
    recording = open_recording(out)
    assert not recording.truncated
    status = json.loads(recording.messages("sim_status")[-1][1].data)
    assert status["state"] == "stopped" and 0 < status["steps"] < 300_000
    assert recording.count("odom") == status["steps"] + 1 == recording.count("wrench_cmd")
    summary = (tmp_path / "run" / "summary.md").read_text()
    assert f"interrupted at t = {status['sim_time']:.3f} s" in summary
