"""Foxglove's own JavaScript packages (pinned in package-lock.json), installed once per test session with npm into
a temporary folder with the scripts that use them: the MCAP decoders (read_mcap.cjs) and the WebSocket client
(live_client.cjs). Needs node and npm (and the package registry) on the machine."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent


@pytest.fixture(scope="session")
def decoders(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder with the pinned packages installed (``npm ci``) and the scripts."""
    npm = shutil.which("npm")
    assert npm and shutil.which("node"), "node and npm are needed to run Foxglove's decoders and client"
    folder = tmp_path_factory.mktemp("foxglove")
    for path in (HERE / "package.json", HERE / "package-lock.json", *HERE.glob("*.cjs")):
        shutil.copy(path, folder / path.name)
    run = subprocess.run([npm, "ci", "--no-audit", "--no-fund", "--loglevel=error"], cwd=folder, capture_output=True,
                         text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    return folder
