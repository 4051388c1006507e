"""Shared pytest fixtures for every test path (graph-test harness: ``ros_graph``, ``scenario_file``), and the
fast tier: graph and install tests are ``slow`` too, so ``-m "not slow"`` runs in a couple of minutes."""

import pytest

pytest_plugins = ["fsr_bringup.testing.fixtures"]


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    for item in items:
        if item.get_closest_marker("graph") or item.get_closest_marker("install"):
            item.add_marker(pytest.mark.slow)
