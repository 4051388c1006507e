"""docs/vehicles.md documents every key of the vehicle file, and its hexacopter flies as written there."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from fsr_bringup.runner.in_process_flight import fly_in_process
from fsr_sim.config.scenario import load_scenario
from fsr_sim.config.validation import ConfigError
from fsr_sim.config.vehicle_file import vehicle_from_mapping
from fsr_sim.model.so3 import rotation_from_euler_zyx, rotation_from_quaternion

DOC = Path(__file__).resolve().parents[1] / "docs" / "vehicles.md"
TEXT = DOC.read_text()
BLOCKS = dict(re.findall(r"^```yaml (\S+)\n(.*?)^```$", TEXT, flags=re.M | re.S))
DOCUMENTED = set(re.findall(r"^\| `(\w+)` \|", TEXT, flags=re.M))


def known_keys(data: dict, where: str) -> set[str]:
    """The keys the parser knows at ``where`` ("" the top level, else a section), from its refusal of one more."""
    data = {**data, **({"zz_unknown": 1} if not where else {})}
    if where == "layout":
        data["layout"] = {**data["layout"], "zz_unknown": 1}
    elif where == "rotors":
        data = {k: v for k, v in data.items() if k != "layout"}
        data["rotors"] = [{"position": [0.3 * np.cos(a), 0.3 * np.sin(a), 0.0], "spin": s, "axis": [0, 0, -1],
                           "tilt_axis": [np.cos(a), np.sin(a), 0], **({"zz_unknown": 1} if i == 0 else {})}
                          for i, (a, s) in enumerate(zip(np.arange(4) * np.pi / 2, (1, -1, 1, -1), strict=True))]
    with pytest.raises(ConfigError, match="zz_unknown: unknown key") as error:
        vehicle_from_mapping(data)
    return set(re.search(r"\(known here: (.*)\)", str(error.value)).group(1).split(", "))


@pytest.mark.parametrize("where", ["", "layout", "rotors"])
def test_every_key_of_the_vehicle_file_is_documented(where):
    import yaml

    data = yaml.safe_load(BLOCKS["hexacopter.yaml"])
    known = known_keys(data, where) | ({"layout", "rotors"} if not where else set())
    assert known and known <= DOCUMENTED, sorted(known - DOCUMENTED)


def test_the_hexacopter_flies_as_written(tmp_path):
    for name, text in BLOCKS.items():
        (tmp_path / name).write_text(text)
    run = fly_in_process(load_scenario(tmp_path / "hover_hexacopter.yaml"))
    assert run.end_reason == "finished" and not run.failures, run.reason
    assert np.linalg.norm(run.state[-1, :3] - (0.5, 0.0, -2.0)) < 1e-3
    attitude = rotation_from_quaternion(run.state[-1, 6:10])
    assert np.linalg.norm(attitude - rotation_from_euler_zyx(np.deg2rad((0.0, 0.0, 30.0)))) < 1e-3
    assert run.saturation["count"] == 0
