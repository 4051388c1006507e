"""Shared pytest fixtures for every test path (graph-test harness: ``ros_graph``, ``scenario_file``)."""

pytest_plugins = ["fsr_bringup.testing.fixtures"]
