"""Evidence behind docs/network.md, "Who may join": the Fast DDS of the pip wheels has no DDS Security.

With ``ROS_SECURITY_ENABLE=true`` and an enclave (rcl only checks that its six files exist), rmw_fastrtps
asks Fast DDS for the builtin authentication/access-control plugins and node creation fails with "This Fast
DDS version doesn't have the security libraries". The library carries none of the plugins' identifiers
either. If a future wheel has DDS Security, these tests fail: then offer a secured mode instead.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from fsr_bringup.runner.domains import TEST_RANGE, acquire_domain

pytestmark = pytest.mark.graph

ENCLAVE_FILES = ("identity_ca.cert.pem", "cert.pem", "key.pem", "permissions_ca.cert.pem", "governance.p7s",
                 "permissions.p7s")
MAKE_NODE = "import rclpy; rclpy.init(); rclpy.create_node('fsr_security_probe'); print('node created')"


def fast_dds_library() -> Path:
    prefix = Path(sys.executable).resolve().parent.parent
    candidates = sorted(Path(sys.prefix).glob("lib/libfastrtps.so.*")) + sorted(prefix.glob("lib/libfastrtps.so.*"))
    if not candidates:
        pytest.skip(f"libfastrtps not found under {sys.prefix}/lib")
    return candidates[0]


def test_the_fast_dds_library_has_no_security_plugins():
    data = fast_dds_library().read_bytes()
    assert b"RTPSParticipantImpl" in data or b"eprosima" in data  # it is the library we think it is
    for plugin in (b"PKI-DH", b"DDS:Auth", b"DDS:Access", b"AES-GCM-GMAC", b"dds.sec.auth"):
        assert plugin not in data, plugin


def test_ros_security_enable_is_refused_by_the_middleware(tmp_path):
    enclave = tmp_path / "keystore" / "enclaves" / "fsr"
    enclave.mkdir(parents=True)
    for name in ENCLAVE_FILES:
        (enclave / name).write_text("placeholder: rcl checks only that the file exists\n")
    env = {**os.environ, "ROS_SECURITY_ENABLE": "true", "ROS_SECURITY_STRATEGY": "Enforce",
           "ROS_SECURITY_KEYSTORE": str(tmp_path / "keystore"), "ROS_SECURITY_ENCLAVE_OVERRIDE": "/fsr",
           "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    with acquire_domain(TEST_RANGE) as lease:
        env["ROS_DOMAIN_ID"] = str(lease.domain_id)
        run = subprocess.run([sys.executable, "-c", MAKE_NODE], env=env, capture_output=True, text=True, timeout=60)
    assert run.returncode != 0 and "node created" not in run.stdout
    assert "doesn't have the security libraries" in run.stderr, run.stderr
