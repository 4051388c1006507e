"""A value that is likely a slip of units (fsr_sim.config.plausibility) is said by simulate() (a UserWarning) and by
fsr-fly (a warning line before the flight)."""

from __future__ import annotations

import pytest


@pytest.mark.slow  # seconds of subprocesses, figures or flights: not for the fast tier
def test_simulate_and_fsr_fly_say_it(tmp_path):
    import subprocess
    import sys

    from fsr_bringup import simulate

    with pytest.warns(UserWarning, match="rotor_time_constant 30 s"):
        simulate("step_disturbance", set={"plant.rotor_time_constant": 30}, duration=0.01)
    result = subprocess.run([sys.executable, "-m", "fsr_bringup.cli.fly_cli", "step_disturbance", "--in-process",
                             "--duration", "0.01", "--set", "plant.mass=1200", "--no-analysis", "--quiet",
                             "--out", str(tmp_path / "run.mcap")], capture_output=True, text=True, timeout=120)
    assert "fsr-fly: step_disturbance: warning: plant.mass 1200 kg is 1e+03 times" in result.stdout, result.stdout
