"""The flight contract (fsr_sim.contract) is the one place of every topic name, frame id, joint name, status key
and exit code: the topic table of docs/architecture.md is generated from it, and no other source file spells them
out."""

from __future__ import annotations

import ast
import re
from dataclasses import fields
from pathlib import Path

import pytest

from fsr_sim import contract

ROOT = Path(__file__).resolve().parents[1]
CONTRACT_FILE = ROOT / "ros_ws/src/fsr_sim/fsr_sim/contract.py"
TOPIC_NAMES = {topic.name for topic in contract.TOPICS}
FRAMES = (contract.WORLD_FRAME, contract.BODY_FRAME)
STATES = {contract.RUNNING, *contract.FINAL_STATES}
STATUS_KEYS = {field.name for field in fields(contract.SimStatus)} - {"steps"}  # "steps" is also every count's key
JOINT = re.compile(rf"({contract.ROTOR}|{contract.TILT})_\d*")


def source_files() -> list[Path]:
    """Every Python file of the packages, the test harness, benchmarks and scripts, test files and the contract
    apart."""
    files = [*ROOT.glob("ros_ws/src/*/*/**/*.py"), *ROOT.glob("tests/harness/**/*.py"),
             *ROOT.glob("benchmarks/**/*.py"), *ROOT.glob("scripts/**/*.py")]
    return sorted(path for path in files if path != CONTRACT_FILE and "test" not in path.relative_to(ROOT).parts
                  and not path.name.startswith("test_") and path.name != "conftest.py")


def docstrings(tree: ast.AST) -> set[int]:
    """ids of the docstring constants (prose may name topics and frames)."""
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant):
                found.add(id(first.value))
    return found


def contract_literals(tree: ast.AST) -> list[tuple[int, str]]:
    """(line, what) of each contract literal written out in ``tree``."""
    skip = docstrings(tree)
    keyed: set[int] = set()  # constants used as a dict key, a subscript or a .get() key
    for node in ast.walk(tree):
        if isinstance(node, ast.Dict):
            keyed.update(id(key) for key in node.keys if key is not None)
        elif isinstance(node, ast.Subscript):
            keyed.add(id(node.slice))
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "get" \
                and node.args:
            keyed.add(id(node.args[0]))
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in skip:
            text = node.value
            if text in TOPIC_NAMES or text.lstrip("/") in TOPIC_NAMES and text.startswith("/"):
                found.append((node.lineno, f"topic name {text!r}"))
            elif any(frame in text for frame in FRAMES):
                found.append((node.lineno, f"frame id in {text!r}"))
            elif JOINT.fullmatch(text):
                found.append((node.lineno, f"joint name {text!r}"))
            elif text in STATES and id(node) not in keyed:  # a state is a value ("diverged" may key a result)
                found.append((node.lineno, f"sim_status state {text!r}"))
            elif text in STATUS_KEYS and id(node) in keyed:
                found.append((node.lineno, f"sim_status key {text!r}"))
        elif isinstance(node, ast.Call) and _exit_call(node) and node.args and _exit_code(node.args[0]):
            found.append((node.lineno, f"exit code {node.args[0].value}"))
        elif isinstance(node, ast.Assign) and _exit_code(node.value) and any(
                isinstance(target, ast.Name) and target.id.startswith("EXIT_") for target in node.targets):
            found.append((node.lineno, "exit code constant"))
        elif isinstance(node, ast.FunctionDef) and node.name == "main":
            found += [(ret.lineno, f"exit code {ret.value.value}") for ret in ast.walk(node)
                      if isinstance(ret, ast.Return) and ret.value is not None and _exit_code(ret.value)]
    return found


def _exit_call(node: ast.Call) -> bool:
    func = node.func
    name = func.attr if isinstance(func, ast.Attribute) else func.id if isinstance(func, ast.Name) else ""
    return name in ("exit", "_exit", "SystemExit")


def _exit_code(node: ast.AST) -> bool:
    """A non-zero int literal (0 is success everywhere)."""
    return isinstance(node, ast.Constant) and type(node.value) is int and node.value != 0


NOT_A_TOPIC = "# not a topic name"  # a line's marker: a word that is also a topic's name (a config value)


def test_no_contract_literal_outside_the_contract():
    offences = []
    for path in source_files():
        text = path.read_text()
        lines = text.splitlines()
        offences += [f"{path.relative_to(ROOT)}:{line}: {what}" for line, what in contract_literals(ast.parse(text))
                     if not (what.startswith("topic name") and NOT_A_TOPIC in lines[line - 1])]
    assert not offences, "use fsr_sim.contract instead of:\n" + "\n".join(offences)


@pytest.mark.parametrize("snippet, expected", [
    ("x = 'odom'", "topic name 'odom'"),
    ("x = f'{ns}/sim_status'", "topic name '/sim_status'"),
    ("msg.header.frame_id = 'base_link_frd'", "frame id"),
    ("names = [f'rotor_{i + 1}' for i in range(4)]", "joint name 'rotor_'"),
    ("if status['state'] == 'finished': pass", "sim_status state 'finished'"),
    ("value = status.get('sim_time')", "sim_status key 'sim_time'"),
    ("sys.exit(2)", "exit code 2"),
    ("EXIT_USAGE = 2", "exit code constant"),
    ("def main():\n    return 2", "exit code 2"),
])
def test_the_literal_check_finds_each_kind(snippet: str, expected: str):
    """The check above can fail: each kind of literal it looks for is found in a snippet."""
    assert any(expected in what for _, what in contract_literals(ast.parse(snippet)))


def test_the_documented_topic_table_is_the_contracts():
    readme = (ROOT / "docs" / "architecture.md").read_text()
    table = contract.topic_table()
    assert table in readme, ("docs/architecture.md's topic table differs from fsr_sim.contract: paste "
                             "`python -m fsr_sim.contract`")
    assert {f"| `{name}` |" for name in TOPIC_NAMES} <= {line[: line.index("` |") + 3] for line in table.splitlines()
                                                         if line.startswith("| `")}


def test_status_round_trips_and_refuses_what_is_not_one():
    status = contract.SimStatus(contract.FINISHED, "done", 1.25, 1250, 3, 1, 2, 0.5)
    assert contract.SimStatus.from_json(status.to_json()) == status and status.final
    assert status.stamp_ns == 1_250_000_000
    assert contract.SimStatus.from_json("not json") is None
    assert contract.SimStatus.from_json('{"state": "stopped"}') is None  # no sim_time: not a status
    assert contract.SimStatus.from_json('[1, 2]') is None


def test_joint_names_parse_back():
    names = contract.joint_names(3, tilting=True)
    assert [contract.parse_joint(name) for name in names] == [
        (contract.ROTOR, 0), (contract.ROTOR, 1), (contract.ROTOR, 2), (contract.TILT, 0), (contract.TILT, 1),
        (contract.TILT, 2)]
    assert contract.parse_joint("rotor_0") is None and contract.parse_joint("arm_1") is None


def test_resolve_puts_relative_names_under_the_namespace():
    assert contract.resolve(contract.ODOM.name, "/uav1/") == "/uav1/odom"
    assert contract.resolve(contract.ODOM.name, "") == contract.resolve(contract.ODOM.name, "/") == "/odom"
    assert contract.resolve(contract.CLOCK.name, "/uav1") == "/clock"
