"""Every built-in scenario (and the variants its options open) records the numbers it recorded before the
compiled flight core: ``tests/data/reference_flights.npz`` was written by ``scripts/reference_flights.py`` on the
commit before it (86fe002), every recorded field sampled every 250 steps and at the end.

Every field must agree to 1e-9, in its unit. Rotor speeds are compared as the squared speeds the thrust is
made of (``w |w|``, to 1e-9 of the flight's largest): a rotor held at a speed limit of 0 rad/s by the priority
allocation has ``u_w`` = 0 up to rounding (1e-9 (rad/s)^2), and its speed ``sqrt(u_w)`` turns any reordering
of that rounding into 1e-5 rad/s, with no effect on the flight (its thrust is ``c_f u_w``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).parents[2]
sys.path.insert(0, str(ROOT / "scripts"))
import reference_flights  # noqa: E402

REFERENCE = np.load(ROOT / "tests" / "data" / "reference_flights.npz")
TOLERANCE = 1e-9


@pytest.mark.parametrize(("key", "scenario", "values"), reference_flights.FLIGHTS, ids=[f[0] for f in
                                                                                          reference_flights.FLIGHTS])
def test_flight_records_the_numbers_of_the_code_before_the_compiled_core(tmp_path, key, scenario, values):
    fields = reference_flights.sampled(reference_flights.fly(scenario, values, tmp_path), 250)
    expected = {name.split(":", 1)[1]: REFERENCE[name] for name in REFERENCE.files if name.startswith(key + ":")}
    new_topics = {name for name in fields.keys() - expected.keys() if name.startswith("/odom_truth/")}
    assert fields.keys() - new_topics == expected.keys()  # odom_truth (the true state beside a noisy odom) is newer
    for name, reference in expected.items():
        value = fields[name]
        assert value.shape == reference.shape, name
        if name.startswith("/rotor_state/"):  # its first message is the first command now (the rotors spin from
            value, reference = value[1:], reference[1:]  # the start), zero before: the flight is the same
        if name == "/rotor_cmd/velocity":
            scale = np.max(np.abs(reference)) ** 2
            np.testing.assert_allclose(value * np.abs(value), reference * np.abs(reference), rtol=0,
                                       atol=TOLERANCE * scale, err_msg=name)
        else:
            np.testing.assert_allclose(value, reference, rtol=0, atol=TOLERANCE, err_msg=name)
