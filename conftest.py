"""Shared pytest fixtures for every test path (graph-test harness: ``ros_graph``, ``scenario_file``), the fast
tier (graph and install tests are ``slow`` too, so ``-m "not slow"`` runs in a couple of minutes), and the
guard that keeps ``-m "not graph"`` free of node processes: a test without the ``graph`` mark runs with
``FSR_FORBID_NODES`` set, so any node it starts (directly, or in an ``fsr-fly`` graph) exits at once with an
error saying so, and the test fails."""

import pytest

from fsr_sim.ros.runtime import FORBID_NODES_ENV

pytest_plugins = ["harness.fixtures"]  # tests/harness (tests/ is on pytest's pythonpath: pyproject.toml)


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    for item in items:
        if item.get_closest_marker("graph") or item.get_closest_marker("install"):
            item.add_marker(pytest.mark.slow)


@pytest.fixture(autouse=True)
def _no_node_without_the_graph_mark(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> None:
    if not request.node.get_closest_marker("graph"):
        monkeypatch.setenv(FORBID_NODES_ENV, "1")
