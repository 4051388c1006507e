"""Pytest fixtures for graph tests (tests that start real ROS 2 node processes; mark them
``@pytest.mark.graph``), loaded for the whole suite by the repository's ``conftest.py`` (``pytest_plugins``;
``tests/`` is on pytest's ``pythonpath`` in ``pyproject.toml``, so ``harness`` imports from any test path).

* ``ros_graph``: a :class:`harness.graph.GraphHarness` — a leased ROS domain (TEST_RANGE), the
  ``env`` for child processes, ``start(name, argv)``, an rclpy test node in its own Context with
  ``publisher``/``subscribe``/``collect``/``wait_for_subscribers``/``run_controller``; everything it
  started is stopped at teardown, whatever the test did.
* ``scenario_file(base=None, filename="scenario.yaml", **overrides) -> Path``: a small scenario YAML in the
  test's ``tmp_path`` (:func:`harness.graph.scenario_file`).
"""

from __future__ import annotations

import pytest

from harness.graph import GraphHarness
from harness.graph import scenario_file as write_scenario


@pytest.fixture
def ros_graph(tmp_path):
    harness = GraphHarness(tmp_path)
    try:
        yield harness
    finally:
        harness.close()


@pytest.fixture
def scenario_file(tmp_path):
    def make(base=None, filename="scenario.yaml", **overrides):
        return write_scenario(tmp_path, base, filename, **overrides)

    return make
