"""Shared pytest fixtures for every test path (graph-test harness: ``ros_graph``, ``scenario_file``), the fast
tier (graph and install tests are ``slow`` too, so ``-m "not slow"`` runs in a couple of minutes), the
guard that keeps ``-m "not graph"`` free of node processes: a test without the ``graph`` mark runs with
``FSR_FORBID_NODES`` set, so any node it starts (directly, or in an ``fsr-fly`` graph) exits at once with an
error saying so, and the test fails; and, when the suite runs on several pytest-xdist workers (``-n 2``), the
lock that runs a test marked ``alone`` (it measures itself against the wall clock) while no other test runs."""

import os

import pytest
from _pytest.nodeid import coerce_node_id

from fsr_sim.ros.runtime import FORBID_NODES_ENV
from harness.alone import TestLock

pytest_plugins = ["harness.fixtures"]  # tests/harness (tests/ is on pytest's pythonpath: pyproject.toml)


@pytest.hookimpl(tryfirst=True)  # before pytest-xdist reads the xdist_group marks
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    for item in items:
        if item.get_closest_marker("graph") or item.get_closest_marker("install"):
            item.add_marker(pytest.mark.slow)
    if os.environ.get("PYTEST_XDIST_WORKER"):
        for_workers(items, getattr(config.option, "loadgroup", False))


def for_workers(items: list[pytest.Item], loadgroup: bool) -> None:
    """Under pytest-xdist (``--dist loadgroup``, pyproject.toml): the tests of a module with a module-scoped
    fixture (a flight, figures) are one group, run on one worker (the fixture made once); and the modules with
    slow tests come first, so that the end of the run is short tests that even out the workers. Every worker
    collects the same order (xdist checks)."""
    slow_modules = set()
    for item in items:
        fixtures = getattr(item, "_fixtureinfo", None)
        scopes = {d.scope for defs in (fixtures.name2fixturedefs.values() if fixtures else ()) for d in defs}
        if ("module" in scopes or "package" in scopes) and not item.get_closest_marker("xdist_group"):
            item.add_marker(pytest.mark.xdist_group(item.nodeid.split("::")[0]))
        if item.get_closest_marker("slow"):
            slow_modules.add(item.nodeid.split("::")[0])
    items.sort(key=lambda item: item.nodeid.split("::")[0] not in slow_modules)  # stable: modules stay whole
    if loadgroup:  # the group in the test's id, which the scheduler reads: what pytest-xdist 3.8 does itself by
        for item in items:  # setting Node._nodeid, which pytest 9 no longer reads (the id is Node._id)
            groups = sorted({str(mark.args[0]) for mark in item.iter_markers("xdist_group")})
            if groups and "@" not in item.nodeid.rpartition("]")[2]:
                item._id = coerce_node_id(f"{item.nodeid}@{'_'.join(groups)}")  # noqa: SLF001


@pytest.fixture(autouse=True)
def _no_node_without_the_graph_mark(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> None:
    if not request.node.get_closest_marker("graph"):
        monkeypatch.setenv(FORBID_NODES_ENV, "1")


@pytest.hookimpl(wrapper=True, tryfirst=True)  # outside pytest-timeout's: waiting for the lock is not timed
def pytest_runtest_protocol(item: pytest.Item, nextitem: pytest.Item | None) -> object:
    """Under pytest-xdist: every test holds the run's lock shared, a test marked ``alone`` holds it exclusively
    (it waits for the running tests to end, and none starts before it ends), through its set-up, call and
    teardown. Without xdist: nothing to do."""
    run = os.environ.get("PYTEST_XDIST_TESTRUNUID")
    if not run:
        return (yield)
    with TestLock(run, exclusive=item.get_closest_marker("alone") is not None):
        return (yield)
