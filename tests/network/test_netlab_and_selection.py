"""The pieces of a flight over several hosts without ROS: ``--nodes`` selection and the test network's cleanup."""

from __future__ import annotations

import subprocess
import sys

import pytest

from fsr_bringup.runner.remote import expected_node_paths, parse_node_selection
from harness.netns import NetLab, unavailable_reason

FLEET = ["recorder", "uav1/estimator", "uav1/controller", "uav1/simulator", "uav2/controller", "uav2/simulator"]


def test_roles_select_every_vehicle_and_process_names_one():
    assert parse_node_selection("controller", FLEET) == {"uav1/controller", "uav2/controller"}
    assert parse_node_selection("simulator, recorder", FLEET) == {"uav1/simulator", "uav2/simulator", "recorder"}
    assert parse_node_selection("/uav2/controller", FLEET) == {"uav2/controller"}
    with pytest.raises(ValueError, match="'estimator' is not a node of this run"):
        parse_node_selection("estimator", ["recorder", "simulator", "controller"])
    with pytest.raises(ValueError, match="at least one"):
        parse_node_selection(" , ", FLEET)


def test_expected_node_paths_use_ros_node_names():
    assert expected_node_paths(["recorder", "uav1/controller", "simulator"]) == {
        "/fsr_recorder": "recorder", "/uav1/controller": "uav1/controller", "/simulator": "simulator"}


def namespaces() -> set[str]:
    listed = subprocess.run(["ip", "netns", "list"], capture_output=True, text=True, check=True).stdout
    return {line.split()[0] for line in listed.splitlines() if line.strip()}


LISTEN = ("import socket, sys; s = socket.create_server(('{address}', 7777)); s.settimeout(10); print('ready', "
          "flush=True); c, _ = s.accept(); c.sendall(b'hello'); c.close()")
CONNECT = ("import socket, sys; c = socket.create_connection(('{address}', 7777), timeout={timeout}); "
           "sys.exit(0 if c.recv(5) == b'hello' else 1)")


def reachable(lab: NetLab, source: str, target: str, timeout: float) -> bool:
    """A TCP connection from host ``source`` to a listener on host ``target`` succeeds within ``timeout`` s."""
    address = lab.address(target)
    listener = subprocess.Popen(lab.command(target, [sys.executable, "-c", LISTEN.format(address=address)]),
                                stdout=subprocess.PIPE, text=True)
    try:
        assert listener.stdout.readline().strip() == "ready"
        connect = [sys.executable, "-c", CONNECT.format(address=address, timeout=timeout)]
        return subprocess.run(lab.command(source, connect), capture_output=True, timeout=30).returncode == 0
    finally:
        listener.kill()
        listener.wait(timeout=10)


def test_the_lab_links_its_hosts_only_and_is_removed_even_when_the_test_fails():
    reason = unavailable_reason()
    if reason is not None:
        print(f"skipping: {reason}")
        pytest.skip(reason)
    with pytest.raises(RuntimeError, match="inside the lab"):
        with NetLab(["a", "b"]) as lab:
            made = set(lab.hosts.values()) | {lab.switch}
            assert made <= namespaces()
            assert reachable(lab, "a", "b", timeout=5.0)
            routes = subprocess.run(lab.command("a", ["ip", "route"]), capture_output=True, text=True).stdout
            assert "default" not in routes and "224.0.0.0/4 dev eth0" in routes  # only the lab's links
            lab.set_link("b", up=False)
            assert not reachable(lab, "a", "b", timeout=1.0)  # the cable is out
            lab.set_link("b", up=True)
            raise RuntimeError("a failure inside the lab")
    # the lab's namespaces are gone, and none of this process's (others' may come and go: other test runs)
    assert not made & namespaces()
    assert not {name for name in namespaces() if name.startswith(f"{lab.tag}-")}
