"""fsr-sweep on a Dask cluster: a scheduler and two workers on loopback give the local table; a worker killed
mid-sweep loses no flight and counts none twice; the same across two network namespaces.

Every process is started here (``dask scheduler`` / ``dask worker`` of this environment, on 127.0.0.1 or the
lab's addresses only, no dashboard, scratch space in the test's folder) and killed at the end; the tests wait for
events (the scheduler file, the workers registered, a batch's result), each with a deadline.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from fsr_bringup import sweep
from harness.netns import NetLab, unavailable_reason

pytestmark = pytest.mark.slow
DASK = str(Path(sys.executable).with_name("dask"))
DEADLINE_S = 60.0
GRID = {"plant.mass": [1.1, 1.15, 1.2, 1.25, 1.3, 1.35], "estimator.c0": [5.0, 20.0]}
SAMPLE = {"trajectory.waypoints.0.position.2": "uniform:-4.5:-3.5"}


def wait_for(condition, what: str, processes: list[subprocess.Popen], deadline_s: float = DEADLINE_S) -> None:  # noqa: ANN001
    end = time.monotonic() + deadline_s
    while not condition():
        for process in processes:
            if process.poll() is not None:
                raise AssertionError(f"{what}: {process.args[0]} exited with {process.returncode}")
        if time.monotonic() > end:
            raise AssertionError(f"{what}: not within {deadline_s:g} s")
        time.sleep(0.05)  # polling an event (a file, the scheduler's worker list), not timing the test


def registered_workers(address: str) -> int:
    from distributed import Client

    with Client(address, timeout=10, set_as_default=False) as client:
        return len(client.scheduler_info()["workers"])


@contextmanager
def cluster(folder: Path, host: str = "127.0.0.1", workers: int = 2, wrap=lambda role, argv: argv  # noqa: ANN001
            ) -> Iterator[tuple[str, list[subprocess.Popen]]]:
    """A scheduler and ``workers`` single-thread workers without nannies (a killed worker stays dead)."""
    folder.mkdir(parents=True, exist_ok=True)
    scheduler_file = folder / "scheduler.json"
    env = {**os.environ, "DASK_TEMPORARY_DIRECTORY": str(folder)}
    started: list[subprocess.Popen] = []
    try:
        started.append(subprocess.Popen(wrap("scheduler", [
            DASK, "scheduler", "--host", host, "--port", "0", "--no-dashboard", "--scheduler-file",
            str(scheduler_file)]), cwd=folder, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        wait_for(lambda: scheduler_file.exists() and scheduler_file.stat().st_size > 0, "the scheduler", started)
        address = json.loads(scheduler_file.read_text())["address"]
        for i in range(workers):
            started.append(subprocess.Popen(wrap(f"worker{i + 1}", [
                DASK, "worker", address, "--nthreads", "1", "--no-nanny", "--no-dashboard", "--host", host,
                "--local-directory", str(folder / f"worker{i + 1}")]), cwd=folder, env=env,
                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        yield address, started
    finally:
        for process in started:
            process.kill()
        for process in started:
            process.wait(timeout=30)


def local_table():
    return sweep("ex4_geometric", grid=GRID, sample=SAMPLE, n=2, seed=3, duration=0.5, workers=1)


def test_a_sweep_on_a_loopback_cluster_gives_the_local_table(tmp_path):
    with cluster(tmp_path / "dask") as (address, started):
        wait_for(lambda: registered_workers(address) == 2, "two workers registered", started)
        remote = sweep("ex4_geometric", grid=GRID, sample=SAMPLE, n=2, seed=3, duration=0.5, cluster=address)
    assert remote.attrs["workers"] == 2
    assert remote.equals(local_table())


def test_a_worker_killed_mid_sweep_loses_no_flight_and_counts_none_twice(tmp_path):
    with cluster(tmp_path / "dask") as (address, started):
        wait_for(lambda: registered_workers(address) == 2, "two workers registered", started)
        victim = started[1]
        done_when_killed = []

        def kill_after_the_first_batch(done: int, total: int, _wall: float) -> None:
            if not done_when_killed and done > 1:  # flight 0 is flown locally; a batch came back
                victim.send_signal(signal.SIGKILL)
                victim.wait(timeout=30)
                done_when_killed.append(done)

        remote = sweep("ex4_geometric", grid=GRID, sample=SAMPLE, n=2, seed=3, duration=0.5, cluster=address,
                       progress=kill_after_the_first_batch)
    assert done_when_killed and done_when_killed[0] < len(remote)  # killed with flights still to come
    assert victim.returncode == -signal.SIGKILL
    assert list(remote.index) == list(range(24))
    assert remote.equals(local_table())


def test_a_sweep_across_two_network_namespaces_gives_the_local_table(tmp_path):
    reason = unavailable_reason()
    if reason is not None:
        pytest.skip(reason)
    with NetLab(["a", "b"]) as lab:
        hosts = {"scheduler": "a", "worker1": "a", "worker2": "b"}
        with cluster(tmp_path / "dask", host=lab.address("a"), workers=1,
                     wrap=lambda role, argv: lab.command(hosts[role], argv)) as (address, started):
            # the second worker on host b, listening on b's address
            started.append(lab.popen("b", [DASK, "worker", address, "--nthreads", "1", "--no-nanny",
                                           "--no-dashboard", "--host", lab.address("b"), "--local-directory",
                                           str(tmp_path / "dask" / "worker2")],
                                     cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
            out = tmp_path / "remote"
            client = lab.command("b", [sys.executable, "-m", "fsr_bringup.cli.sweep_cli", "ex4_geometric",
                                       "--grid", "plant.mass=1.1,1.15,1.2,1.25,1.3,1.35",
                                       "--grid", "estimator.c0=5.0,20.0", "--sample",
                                       "trajectory.waypoints.0.position.2=uniform:-4.5:-3.5", "--n", "2", "--seed", "3",
                                       "--duration", "0.5", "--cluster", address, "--out", str(out)])
            check = [sys.executable, "-c", f"from fsr_bringup.sweeps.run import cluster_workers; import sys; "
                                           f"sys.exit(0 if cluster_workers({address!r}) == 2 else 1)"]
            wait_for(lambda: subprocess.run(lab.command("b", check), capture_output=True).returncode == 0,
                     "two workers registered", started)
            result = subprocess.run(client, capture_output=True, text=True, cwd=tmp_path, timeout=240)
        assert result.returncode == 0, result.stderr
    import pandas as pd

    remote = pd.read_csv(out / "results.csv", index_col="flight")
    local_out = tmp_path / "local.csv"
    local_table().to_csv(local_out)
    pd.testing.assert_frame_equal(remote, pd.read_csv(local_out, index_col="flight"))


def test_a_study_on_a_loopback_cluster_gives_the_local_trials(tmp_path):
    from fsr_bringup import tune

    kwargs = dict(params={"controller.gains.k_p": "log:5:40,same,100", "controller.gains.k_v": "log:5:40,same,100"},
                  seeds=2, budget=16, method="cma", seed=5, duration=1.0, holdout=2)
    local = tune("step_disturbance", workers=2, **kwargs)
    with cluster(tmp_path / "dask") as (address, started):
        wait_for(lambda: registered_workers(address) == 2, "two workers registered", started)
        remote = tune("step_disturbance", cluster=address, **kwargs)
    assert remote.trials.equals(local.trials)
    assert remote.best_trial == local.best_trial and remote.best_values == local.best_values
    assert remote.validation["best"].objective == local.validation["best"].objective
