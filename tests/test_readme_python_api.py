"""The README's "Python API" snippet runs as written (in a scratch working directory)."""

import os
import re
from pathlib import Path

import numpy as np

README = Path(__file__).resolve().parents[1] / "README.md"


def python_api_snippet() -> str:
    section = README.read_text(encoding="utf-8").split("## Python API", 1)[1]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


def test_readme_python_api_snippet_runs(tmp_path, capsys):
    namespace: dict = {}
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        exec(compile(python_api_snippet(), str(README), "exec"), namespace)  # noqa: S102 - the README's own code
    finally:
        os.chdir(cwd)
    plant, run = namespace["plant"], namespace["run"]
    np.testing.assert_allclose(plant.state.position, [0.0, 0.0, -1.0], atol=1e-12)  # hover: weight = thrust
    assert run.time.shape == (10001,) and run.end_reason == "finished"
    assert run.estimate_force_body.shape == (10001, 3)
    from fsr_sim.recording.reader import open_recording

    recording = open_recording(tmp_path / "runs" / "ex4.mcap")
    assert recording.count("odom") == 10001 and not recording.truncated
    odom = np.array([[m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.position.z]
                     for _, m in recording.messages("odom")])
    np.testing.assert_array_equal(odom, run.position)  # the recording is the run
