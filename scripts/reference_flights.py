"""Write (or check) the reference flights: every built-in scenario flown in one process and recorded, each
recorded field sampled every ``--every`` steps (and at the last step) into one ``.npz`` file.

    .venv/bin/python scripts/reference_flights.py --out tests/data/reference_flights.npz
    .venv/bin/python scripts/reference_flights.py --out tests/data/reference_flights.npz --only step_disturbance

``tests/flights/test_reference_flights.py`` flies the same list again and compares every field with the file
(<= 1e-9): a change of the models that moves any recorded number fails it. The file in the repository was
written by the commit before the compiled flight core (86fe002), so the core is held to the code it replaced;
the flights of the scenarios that name no ``controller.profile`` (octo_ground_effect, ceiling_approach,
step_disturbance, wind_rejection and their variants) were written again when their default became the flight
profile (reference feed-forward, gains designed for the vehicle), with the ``*_flight`` and ``*_onboard`` keys;
their compensated flights (``step_disturbance_compensated``, ``wind_rejection_compensated``) again when the flight
profile stopped turning ``R_d`` with the compensated estimate's rates.
``--only KEY ...`` flies those keys and keeps every other key of an existing ``--out`` file as it is.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

from fsr_sim.contract import RECORDER, SIM_STATUS, resolve, topic_named

# (key, scenario, --set values): every built-in scenario as shipped, and the variants its options open.
FLIGHTS: list[tuple[str, str, dict]] = [
    ("ex3_estimation", "ex3_estimation", {}),
    ("ex3_compensated_r3", "ex3_estimation", {"controller.compensation": "estimate", "estimator.r": 3}),
    ("ex4_geometric", "ex4_geometric", {}),
    ("ex4_rotors", "ex4_geometric", {"actuation": "rotors"}),
    ("ex4_yaw_gives_way", "ex4_geometric", {"actuation": "rotors", "trajectory.feasibility": "warn",
                                            "trajectory.waypoints.0": {
        "position": [3, -2, -4], "attitude_rpy_deg": [0, 0, 150], "duration": 4.0}}),  # as written: saturates
    ("ex5_voliro", "ex5_voliro", {}),
    ("ex5_min_peak_speed", "ex5_voliro", {"controller.secondary_objective.type": "min_peak_speed"}),
    ("ex5_compensated", "ex5_voliro", {"controller.compensation": "estimate"}),
    ("octo_ground_effect", "octo_ground_effect", {}),
    ("octo_multirotor_compensated", "octo_ground_effect", {"environment.ground.model": "multirotor",
                                                           "controller.compensation": "estimate"}),
    ("ceiling_approach", "ceiling_approach", {}),
    ("step_disturbance", "step_disturbance", {}),
    ("step_disturbance_compensated", "step_disturbance", {"controller.compensation": "estimate"}),
    ("wind_rejection", "wind_rejection", {}),
    ("wind_rejection_compensated", "wind_rejection", {"controller.compensation": "estimate", "estimator.r": 2}),
    # the flight profile on the exercises, and under onboard-like odometry with a 30 ms motor
    ("ex4_flight", "ex4_geometric", {"actuation": "rotors", "controller.profile": "flight"}),
    ("ex5_flight", "ex5_voliro", {"controller.profile": "flight"}),
    ("step_disturbance_onboard", "step_disturbance", {
        "plant.rotor_time_constant": 0.03, "sensors.odometry": {"rate_hz": 100, "delay_steps": 10, "position_std": 0.01,
                                                                "attitude_std_deg": 0.5, "velocity_std": 0.02,
                                                                "seed": 1}}),
]


def recorded_fields(path: Path) -> dict[str, np.ndarray]:
    """``{topic/field: values}`` of every numeric field of every topic with a header stamp (rows by stamp) that the
    flight's nodes publish (the viewer's topics the recording derives from them apart)."""
    from fsr_sim.recording.cdr_columns import stamped_columns
    from fsr_sim.recording.reader import open_recording

    recording = open_recording(path)
    fields = {}
    for topic in sorted(recording.topics):
        contract_topic = topic_named(topic)
        if topic == resolve(SIM_STATUS.name) or contract_topic is not None and contract_topic.publisher == RECORDER:
            continue
        stamps, columns = stamped_columns(recording, topic)
        fields[f"{topic}/stamp"] = stamps
        for name, values in columns.numbers.items():
            if not name.startswith("header."):
                fields[f"{topic}/{name}"] = values
    return fields


def sampled(fields: dict[str, np.ndarray], every: int) -> dict[str, np.ndarray]:
    out = {}
    for key, values in fields.items():
        rows = np.unique(np.r_[np.arange(0, len(values), every), len(values) - 1])
        out[key] = values[rows]
    return out


def fly(scenario: str, values: dict, folder: Path) -> dict[str, np.ndarray]:
    from fsr_bringup import simulate

    path = folder / "flight.mcap"
    simulate(scenario, set=values, record=path)
    return recorded_fields(path)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True, help="the .npz file to write")
    parser.add_argument("--every", type=int, default=250, help="sample every N steps (default 250)")
    parser.add_argument("--only", nargs="*", help="fly only these keys")
    args = parser.parse_args(argv)
    data = {}
    if args.only and args.out.exists():  # keep the keys not flown
        with np.load(args.out) as stored:
            data = {name: stored[name] for name in stored.files if name.split(":", 1)[0] not in args.only}
    with tempfile.TemporaryDirectory() as folder:
        for key, scenario, values in FLIGHTS:
            if args.only and key not in args.only:
                continue
            fields = sampled(fly(scenario, values, Path(folder)), args.every)
            data.update({f"{key}:{name}": value for name, value in fields.items()})
            print(f"{key}: {len(fields)} fields", file=sys.stderr)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(args.out, **data)
    print(f"wrote {args.out} ({args.out.stat().st_size / 1e3:.0f} kB)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
