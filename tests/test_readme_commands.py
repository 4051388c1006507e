"""Every command in the fenced ``bash`` blocks of README.md and docs/*.md runs and succeeds.

The commands are read from the documents (a new or changed command is tested without touching this file) and
run with ``bash -c`` in a scratch folder that links the repository's ``.venv``, ``scripts``,
``requirements.txt``, ``ros_ws``, ``examples`` and ``benchmarks``, so relative paths work and outputs
(``runs/...``) stay out of the work tree. ``my_flight.yaml`` is docs/scenarios.md's YAML example. Changes to
the commands as written, to keep the run short:

* every ``fsr-fly`` flight gets ``--duration 0.5`` appended (argparse: the last ``--duration`` wins);
* ``benchmarks/control_comparison.py`` (docs/control.md's comparison, thousands of flights) gets
  ``--seeds 1 --duration 0.5`` appended: one seed of every law, condition and flight, 0.5 s each;
* the by-hand block (``export ROS_DOMAIN_ID=42`` and one node per line) runs as one scripted graph: the
  nodes are started together in a leased ROS domain instead of 42 (localhost discovery), the simulator
  line gets ``-p duration:=0.5``, and every node must end by itself (exit 0) with a complete recording;
* the companion-computer block (``python3 -m venv companion``, the ``pip install``, one node) runs as
  written in its own folder with a copy of ``ros_ws`` (pip builds a local folder in place; ``PIP_COMPILE=0``:
  the installed modules are not byte-compiled, only their cache files are left out); the node runs
  with ``NUMBA_DISABLE_JIT=1`` (not compiling a core of its own) and flies 0.5 s against the repository's
  simulator in a leased ROS domain;
* ``bash scripts/setup.sh && .venv/bin/python -m pytest -n 2`` is not run: it is this test suite (CI runs it
  as ``.ci/run``), running it here would recurse.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest
import yaml

from fsr_bringup.runner.domains import TEST_RANGE, acquire_domain
from fsr_sim.config.scenario import load_scenario
from fsr_sim.recording.reader import open_recording

pytestmark = pytest.mark.slow  # every command of the README, many flights

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
DOCUMENTS = (README, *sorted((ROOT / "docs").glob("*.md")))
LINKED = (".venv", "scripts", "requirements.txt", "ros_ws", "examples", "benchmarks")
SHORT_FLIGHT = " --duration 0.5"
COMPARISON = "benchmarks/control_comparison.py"
SHORT_COMPARISON = " --seeds 1 --duration 0.5"
SUITE_ITSELF = "python -m pytest"
BY_HAND_MARK = "export ROS_DOMAIN_ID="
COMPANION_MARK = "python3 -m venv companion"


def fenced_blocks(text: str, language: str) -> list[str]:
    return re.findall(rf"^```{language}\n(.*?)^```", text, flags=re.S | re.M)


def commands(block: str) -> list[str]:
    """One string per command: continuation lines joined, comment lines and trailing comments dropped."""
    joined = re.sub(r"\\\n\s*", " ", block)
    found = []
    for line in joined.splitlines():
        line = re.split(r"\s+#\s", line.strip(), maxsplit=1)[0].strip()
        if line and not line.startswith("#"):
            found.append(line)
    return found


TEXTS = [document.read_text(encoding="utf-8") for document in DOCUMENTS]
BLOCKS = [commands(block) for text in TEXTS for block in fenced_blocks(text, "bash")]
MY_FLIGHT = [block for text in TEXTS for block in fenced_blocks(text, "yaml") if "name: my_flight" in block]
BY_HAND = next(block for block in BLOCKS if block and block[0].startswith(BY_HAND_MARK))
COMPANION = next(block for block in BLOCKS if block and block[0] == COMPANION_MARK)
SINGLE = [c for block in BLOCKS if block is not BY_HAND and block is not COMPANION for c in block
          if SUITE_ITSELF not in c]


def test_the_readme_has_the_commands_this_test_expects():
    every = [c for block in BLOCKS for c in block]
    assert every[0] == "bash scripts/setup.sh && .venv/bin/fsr-fly ex3_estimation --out runs/ex3_estimation.mcap"
    assert every[1] == "bash scripts/setup.sh && .venv/bin/python -m pytest -n 2"
    assert len(SINGLE) >= 10 and len(BY_HAND) == 5 and len(COMPANION) == 3
    assert len(MY_FLIGHT) == 1
    readme = TEXTS[0]  # what a new user needs, the rest in docs/ (linked from it)
    assert len(readme.splitlines()) <= 250 and "SPEC" not in readme and "issue " not in readme
    assert all(f"(docs/{page.name})" in readme for page in DOCUMENTS[1:]), "a docs page the README does not link"


@pytest.fixture(scope="session")  # (this module's only; not module-scoped: conftest.py groups those for xdist)
def workdir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("readme")
    for name in LINKED:
        (path / name).symlink_to(ROOT / name)
    (path / "my_flight.yaml").write_text(MY_FLIGHT[0], encoding="utf-8")
    return path


def as_run(command: str) -> str:
    if COMPARISON in command:
        return command + SHORT_COMPARISON
    return command + SHORT_FLIGHT if "fsr-fly" in command else command


def test_my_flight_yaml_example_is_a_valid_scenario(workdir):
    from fsr_control.config.controller_config import controller_config
    from fsr_estimation.config.estimator_config import estimator_config
    from fsr_sim.config.scenario import simulation_config

    scenario = load_scenario(workdir / "my_flight.yaml")
    assert scenario.name == "my_flight"
    simulation_config(scenario), controller_config(scenario), estimator_config(scenario)  # every key valid


def recordings(command: str) -> set[str]:
    """The recordings (``runs/....mcap``) a command writes or reads."""
    return set(re.findall(r"runs/\S+?\.mcap", command))


def chains(single: list[str]) -> list:
    """``single`` as parameters; commands linked by a recording (one writes what another reads, also through a
    third) share an xdist group, so that pytest-xdist runs them on one worker (one scratch folder), in order."""
    group = list(range(len(single)))

    def root(i: int) -> int:
        while group[i] != i:
            i = group[i]
        return i

    for i, command in enumerate(single):
        for j in range(i):
            if recordings(command) & recordings(single[j]):
                group[root(i)] = root(j)
    linked = {root(i) for i in range(len(single)) for j in range(len(single)) if i != j and root(i) == root(j)}
    return [pytest.param(command, marks=pytest.mark.xdist_group(f"readme-{root(i)}")) if root(i) in linked
            else command for i, command in enumerate(single)]


@pytest.mark.graph  # fsr-fly flies node graphs
@pytest.mark.parametrize("command", chains(SINGLE))
def test_readme_command_runs(workdir, command):
    env = {k: v for k, v in os.environ.items() if k not in ("ROS_DOMAIN_ID", "PYTHONPATH")}
    result = subprocess.run(["bash", "-c", as_run(command)], cwd=workdir, env=env, capture_output=True,
                            text=True, timeout=180, stdin=subprocess.DEVNULL)
    assert result.returncode == 0, f"$ {as_run(command)}\n{result.stdout[-3000:]}\n{result.stderr[-3000:]}"
    out = re.search(r"--out (\S+\.mcap)", command)
    if out:
        recording = open_recording(workdir / out.group(1))
        assert not recording.truncated and recording.count("/odom") >= 500
        assert (workdir / out.group(1)).with_suffix("").joinpath("metrics.json").is_file()


def run_together(lines: list[str], cwd: Path, env: dict[str, str], timeout: float) -> dict[str, str]:
    """Start every command line at once; each must end by itself (no signal) with exit 0. {line: output}."""
    processes = []
    try:
        for line in lines:
            processes.append((line, subprocess.Popen(
                ["bash", "-c", f"exec {line}"], cwd=cwd, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                stderr=subprocess.STDOUT, text=True, start_new_session=True,
            )))
        outputs = {}
        for line, process in processes:
            outputs[line], _ = process.communicate(timeout=timeout)
            assert process.returncode == 0, f"$ {line}\n{outputs[line][-3000:]}"
        return outputs
    finally:
        for _, process in processes:
            if process.poll() is None:
                process.kill()
                process.wait(5)


@pytest.mark.graph
def test_readme_by_hand_nodes_run_together_and_end_by_themselves(workdir):
    assert BY_HAND[0] == "export ROS_DOMAIN_ID=42"
    lines = BY_HAND[1:]
    recording = workdir / re.search(r"--out (\S+)", next(line for line in lines if "fsr-record" in line)).group(1)
    recording.parent.mkdir(parents=True, exist_ok=True)
    with acquire_domain(TEST_RANGE) as lease:
        env = {k: v for k, v in os.environ.items() if k not in ("ROS_LOCALHOST_ONLY", "PYTHONPATH")}
        env.update(ROS_DOMAIN_ID=str(lease.domain_id), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
        run_together([line + " -p duration:=0.5" if "simulator" in line.split()[0] else line for line in lines],
                     workdir, env, timeout=90)
    result = open_recording(recording)
    assert not result.truncated
    assert len({t for t, _ in result.raw("/odom")}) == 501 and result.count("/wrench_estimate") == 501
    assert yaml.safe_load(result.scenario_yaml)["name"] == "ex4_geometric"


@pytest.mark.graph
@pytest.mark.timeout(600)
def test_readme_companion_install_flies_its_controller_against_the_simulator(tmp_path):
    make_venv, install, node = COMPANION
    assert "pip install" in install and node.startswith("companion/bin/controller --ros-args -p scenario:=")
    shutil.copytree(ROOT / "ros_ws", tmp_path / "ros_ws",
                    ignore=shutil.ignore_patterns("build", "install", "log", "*.egg-info", "__pycache__"))
    env = {k: v for k, v in os.environ.items() if k not in ("ROS_LOCALHOST_ONLY", "PYTHONPATH", "VIRTUAL_ENV")}
    env["FSR_NUMBA_CACHE_BASE"] = str(tmp_path / "cache")  # its own core (no fsr_bringup): its own cache
    # pip installs without byte-compiling the 3500 modules it installs (pip's --no-compile; a third of the
    # install's time): what is installed is the same, the node compiles the modules it imports as it starts
    env["PIP_COMPILE"] = "0"
    for command in (make_venv, install):
        result = subprocess.run(["bash", "-c", command], cwd=tmp_path, env=env, capture_output=True, text=True,
                                timeout=600, stdin=subprocess.DEVNULL)
        assert result.returncode == 0, f"$ {command}\n{result.stdout[-3000:]}\n{result.stderr[-3000:]}"
    listed = subprocess.run([str(tmp_path / "companion" / "bin" / "python"), "-m", "pip", "list", "--format=freeze"],
                            capture_output=True, text=True, timeout=120).stdout.lower()
    installed = {re.split(r"==| @ ", line)[0].replace("_", "-") for line in listed.splitlines()}
    assert {"fsr-sim", "fsr-control", "fsr-estimation"} <= installed and "fsr-bringup" not in installed, listed
    assert not installed & {"mcap", "mcap-ros2-support", "matplotlib"}, listed
    scenario = node.split("scenario:=")[1].split()[0]
    simulator = f"{ROOT}/.venv/bin/simulator --ros-args -p scenario:={scenario} -p wait_for_subscribers:=1 " \
                "-p duration:=0.5 -p startup_timeout:=300"  # while the companion compiles its core
    with acquire_domain(TEST_RANGE) as lease:
        env.update(ROS_DOMAIN_ID=str(lease.domain_id), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
        # the companion's node runs its core's source uncompiled (NUMBA_DISABLE_JIT: the same results, without
        # compiling a core no other test uses; the compiled path is what the install test checks)
        outputs = run_together([f"env NUMBA_DISABLE_JIT=1 {node}", simulator], tmp_path, env, timeout=300)
        outputs[node] = outputs.pop(f"env NUMBA_DISABLE_JIT=1 {node}")
    assert "finished: reached the scenario duration 0.5 s (500 steps" in outputs[simulator], outputs[simulator]
    assert "501 odom answered" in outputs[node], outputs[node]
