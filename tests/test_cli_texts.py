"""What a new user reads: every command's --help is plain text ending with its exit codes, names close to a
built-in one get a suggestion, the figures the shipped scenarios mention exist, the licence is in the repo."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from fsr_bringup.analysis.figures import FIGURES
from fsr_sim.config.scenario import load_scenario
from fsr_sim.config.validation import ConfigError, builtin_config_dir
from fsr_sim.model.vehicle import load_vehicle

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent
COMMANDS = ("fsr-fly", "fsr-analyze", "fsr-record", "fsr-estimate", "fsr-vehicle", "fsr-compile", "fsr-sweep",
            "fsr-tune")


@pytest.mark.parametrize("command", COMMANDS)
def test_help_is_plain_text_and_ends_with_the_exit_codes(command):
    run = subprocess.run([str(BIN / command), "--help"], capture_output=True, text=True, timeout=60,
                         stdin=subprocess.DEVNULL)
    assert run.returncode == 0, run.stderr
    text = run.stdout
    assert "``" not in text and ":mod:" not in text, text  # no reStructuredText markup
    codes = text[text.index("\nexit codes:\n"):].splitlines()[2:]
    assert codes and all(re.match(r"^  \d+ +\S", line) for line in codes), codes
    assert codes[0].split()[0] == "0" and any(line.split()[0] == "2" for line in codes)


@pytest.mark.parametrize(("load", "typo", "meant"), [(load_scenario, "ex4_gemetric", "ex4_geometric"),
                                                      (load_vehicle, "octocoptr", "octocopter")])
def test_a_name_close_to_a_built_in_one_gets_a_suggestion(load, typo, meant):
    with pytest.raises(ConfigError, match=f"unknown .* '{typo}' \\(did you mean '{meant}'\\?\\) \\(built-in: "):
        load(typo)


def test_the_figures_the_built_in_scenarios_mention_are_drawn_by_the_analysis():
    mentioned = {name for path in builtin_config_dir("scenarios").glob("*.yaml")
                 for name in re.findall(r"(\w+)\.png", path.read_text())}
    assert mentioned and mentioned <= set(FIGURES), mentioned - set(FIGURES)


def test_the_licence_the_packages_declare_is_in_the_repository():
    declared = {re.search(r"<license>(.*)</license>", path.read_text()).group(1)
                for path in (ROOT / "ros_ws" / "src").glob("*/package.xml")}
    assert declared == {"Apache-2.0"}
    licence = (ROOT / "LICENSE").read_text()
    assert "Apache License" in licence and "Version 2.0, January 2004" in licence
