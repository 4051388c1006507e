"""The packages work when installed for real, not only as the editable installs of ``scripts/setup.sh``.

* A normal (non-editable) ``pip install`` of the four packages into a scratch virtual environment: every
  console script starts, built-in scenarios, vehicles, fleets and the DDS profile are shipped, and a short
  flight is flown in-process and as a node graph with the compiled core's cache that ``scripts/setup.sh``
  filled (the installed copy shares it: the cache is keyed by the sources' content, not their path; a flight
  that compiles on the spot into an empty cache is what ``fsr-compile`` in ``scripts/setup.sh`` does on every
  fresh machine, CI's included, and costs minutes here, so it is not repeated). To stay fast and
  offline the scratch environment borrows the third-party dependencies (rclpy, numpy, ...) from the
  repository's ``.venv`` through a ``.pth`` file; the fsr packages themselves come from the scratch
  environment's own site-packages (checked).
* ``colcon build`` of ``ros_ws`` into a temporary folder (what a ROS 2 user does): the
  ``install/<pkg>/lib/<pkg>/<exe>`` scripts start.

Skipped, with the reason, where pip or colcon is missing (both are in requirements.txt, so CI runs them).
"""

from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
import sys
import sysconfig
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from fsr_bringup.runner.domains import TEST_RANGE, acquire_domain
from fsr_sim.recording.reader import open_recording

pytestmark = pytest.mark.install

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("fsr_sim", "fsr_control", "fsr_estimation", "fsr_bringup")
HELP_SCRIPTS = {  # console script -> package
    "fsr-fly": "fsr_bringup", "fsr-record": "fsr_bringup", "fsr-analyze": "fsr_bringup",
    "fsr-vehicle": "fsr_bringup", "fsr-estimate": "fsr_estimation",
}
NODE_SCRIPTS = {"simulator": "fsr_sim", "controller": "fsr_control", "estimator": "fsr_estimation"}


def run(argv: list[str], env: dict[str, str] | None = None, timeout: float = 120.0,
        cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run(argv, env=env, capture_output=True, text=True, timeout=timeout, cwd=cwd,
                          stdin=subprocess.DEVNULL)


def ros_env(domain_id: int, **extra: str) -> dict[str, str]:
    env = {**os.environ, "ROS_DOMAIN_ID": str(domain_id), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST", **extra}
    env.pop("ROS_LOCALHOST_ONLY", None)
    env.pop("PYTHONPATH", None)
    return env


def run_at_once(commands: dict[str, list[str]], env: dict[str, str],
                timeout: float = 120.0) -> dict[str, subprocess.CompletedProcess]:
    """``run`` for every command, all started at once (each is mostly its own imports: one core's work)."""
    processes = {name: subprocess.Popen(argv, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                        stdin=subprocess.DEVNULL) for name, argv in commands.items()}
    try:
        results = {}
        for name, process in processes.items():
            stdout, stderr = process.communicate(timeout=timeout)
            results[name] = subprocess.CompletedProcess(process.args, process.returncode, stdout, stderr)
        return results
    finally:
        for process in processes.values():
            if process.poll() is None:
                process.kill()
                process.wait()


def check_scripts_start(script: Callable[[str], Path], env: dict[str, str]) -> None:
    """``--help`` of each command-line tool exits 0; each node refuses an unknown scenario with exit 2."""
    helps = run_at_once({name: [str(script(name)), "--help"] for name in HELP_SCRIPTS}, env)
    refusals = run_at_once({name: [str(script(name)), "--ros-args", "-p", "scenario:=no_such_scenario"]
                            for name in NODE_SCRIPTS}, env)
    for name, result in helps.items():
        assert result.returncode == 0 and "usage:" in result.stdout, f"{name} --help:\n{result.stderr}"
    for name, result in refusals.items():
        assert result.returncode == 2, f"{name}: exit {result.returncode}\n{result.stdout}{result.stderr}"
        assert "unknown scenario 'no_such_scenario'" in result.stderr, result.stderr


def source_files(package: str) -> tuple[set[str], set[str]]:
    """(Python modules, data files) of a package's source tree, relative to its ``ros_ws/src/<package>``."""
    base = ROOT / "ros_ws" / "src" / package
    files = {str(f.relative_to(base)) for f in (base / package).rglob("*")
             if f.is_file() and "__pycache__" not in f.parts}
    return {f for f in files if f.endswith(".py")}, {f for f in files if not f.endswith((".py", ".pyc"))}


def test_every_python_folder_of_every_package_is_a_package():
    """``find_packages`` skips a folder without ``__init__.py``: its modules would be missing when installed."""
    for package in PACKAGES:
        modules, _ = source_files(package)
        folders = {str(Path(m).parent) for m in modules}
        missing = sorted(f for f in folders if f"{f}/__init__.py" not in modules)
        assert not missing, f"{package}: no __init__.py in {missing}"


@pytest.fixture
def domain():
    with acquire_domain(TEST_RANGE) as lease:
        yield lease.domain_id


@pytest.mark.graph  # it flies a node graph from the installed copy
def test_non_editable_install_runs_every_command(tmp_path, domain):
    if importlib.util.find_spec("pip") is None:
        pytest.skip("pip is not available in this environment (needed to install the packages)")
    start = time.monotonic()
    scratch = tmp_path / "venv"
    base_python = getattr(sys, "_base_executable", sys.executable)
    subprocess.run([base_python, "-m", "venv", "--without-pip", str(scratch)], check=True, timeout=120)
    python = scratch / "bin" / "python"
    site = Path(run([str(python), "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"]).stdout.strip())
    # Third-party dependencies from the repository's environment (its .pth files run: ROS library paths).
    (site / "_fsr_test_dependencies.pth").write_text(
        f"import site; site.addsitedir({sysconfig.get_path('purelib')!r})\n", encoding="utf-8"
    )
    sources = tmp_path / "src"  # pip builds a local folder in place (build/): a copy keeps the tree clean
    for package in PACKAGES:
        shutil.copytree(ROOT / "ros_ws" / "src" / package, sources / package,
                        ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
    install = run(
        [str(python), "-m", "pip", "install", "--quiet", "--no-deps", "--no-build-isolation", "--no-index",
         "--ignore-installed", "--disable-pip-version-check", *(str(sources / p) for p in PACKAGES)],
        timeout=300, cwd=tmp_path,
    )
    assert install.returncode == 0, install.stdout + install.stderr
    env = ros_env(domain)
    where = run([str(python), "-c", "import fsr_sim, fsr_control, fsr_estimation, fsr_bringup.cli.fly_cli as m; "
                 "print(m.__file__)"], env)
    assert where.returncode == 0, where.stderr
    assert Path(where.stdout.strip()).is_relative_to(site), f"fsr_bringup came from {where.stdout}"
    for package in PACKAGES:  # every module and data file (scenarios, vehicles, fleets, DDS profile) shipped
        modules, data = source_files(package)
        missing = sorted(f for f in modules | data if not (site / f).is_file())
        assert not missing, f"{package}: not installed: {missing}"
    for package in PACKAGES:  # the ament index knows the package (data_files), as a ROS install expects
        assert (scratch / "share" / "ament_index" / "resource_index" / "packages" / package).is_file()
        assert (scratch / "share" / package / "package.xml").is_file()

    check_scripts_start(lambda name: scratch / "bin" / name, env)
    vehicle = run([str(scratch / "bin" / "fsr-vehicle"), "octocopter", "--json"], env)
    assert vehicle.returncode == 0 and '"contact_height"' in vehicle.stdout, vehicle.stderr
    fleet = run([str(scratch / "bin" / "fsr-fly"), "three_vehicles", "--in-process"], env, cwd=tmp_path)
    assert fleet.returncode == 2 and "--in-process flies one vehicle" in fleet.stderr, fleet.stderr  # fleet found
    out = tmp_path / "runs" / "warm.mcap"
    flight = run([str(scratch / "bin" / "fsr-fly"), "ex4_geometric", "--in-process", "--duration", "0.5",
                  "--out", str(out), "--quiet"], {**env, "NUMBA_DEBUG_CACHE": "1"}, cwd=tmp_path, timeout=600)
    assert flight.returncode == 0, flight.stdout + flight.stderr
    assert "[cache] data saved" not in flight.stdout, "the installed copy compiled instead of loading setup.sh's cache"
    assert open_recording(out).count("odom") == 501 and (tmp_path / "runs" / "warm" / "metrics.json").is_file()
    graph = run([str(scratch / "bin" / "fsr-fly"), "ex4_geometric", "--duration", "0.2", "--no-analysis", "--out",
                 str(tmp_path / "runs" / "graph.mcap")], env, cwd=tmp_path, timeout=300)
    assert graph.returncode == 0, graph.stdout + graph.stderr
    assert open_recording(tmp_path / "runs" / "graph.mcap").count("odom") == 201
    print(f"\nnon-editable install test: {time.monotonic() - start:.1f} s")


def test_colcon_build_installs_runnable_scripts(tmp_path, domain):
    colcon = Path(sys.executable).parent / "colcon"
    if not colcon.is_file():
        colcon = Path(shutil.which("colcon") or "")
        if not colcon.is_file():
            pytest.skip("colcon is not installed (pip install colcon-common-extensions, see requirements.txt)")
    start = time.monotonic()
    build = run([str(colcon), "--log-base", str(tmp_path / "log"), "build",
                 "--base-paths", str(ROOT / "ros_ws" / "src"), "--build-base", str(tmp_path / "build"),
                 "--install-base", str(tmp_path / "install")], timeout=300, cwd=tmp_path)
    assert build.returncode == 0, build.stdout + build.stderr
    assert "4 packages finished" in build.stdout, build.stdout
    install = tmp_path / "install"
    setup = install / "setup.bash"
    env = ros_env(domain)

    def script(name: str) -> Path:
        package = HELP_SCRIPTS.get(name) or NODE_SCRIPTS[name]
        return install / package / "lib" / package / name

    sourced = run(["bash", "-c", f"source {setup} && env"], env)
    assert sourced.returncode == 0, sourced.stderr
    env = dict(line.split("=", 1) for line in sourced.stdout.splitlines() if "=" in line)
    where = run([sys.executable, "-c", "import fsr_bringup.cli.fly_cli as m; print(m.__file__)"], env)
    assert Path(where.stdout.strip()).is_relative_to(install), f"fsr_bringup came from {where.stdout}{where.stderr}"
    check_scripts_start(script, env)
    print(f"\ncolcon build test: {time.monotonic() - start:.1f} s")
