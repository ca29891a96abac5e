"""doctor's report reads well (issue 25 item 12): a configuration's report lists the plug-ins
its devices use, not all of them; a VRPN server that does not answer is said once; counts
agree with their nouns."""

from __future__ import annotations

import socket
import sys

import pytest

from conftest import REPO

sys.path.insert(0, str(REPO / "drivers"))
from VRPN_drv.emulator import VrpnEmulator

pytestmark = pytest.mark.timeout(60)


def plugin_lines(text: str) -> list[str]:
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("Driver plug-ins"))
    end = next(i for i, line in enumerate(lines) if i > start and not line.startswith("    "))
    return lines[start + 1 : end]


def test_a_configuration_lists_the_plug_ins_it_uses(cli):
    result = cli("doctor", REPO / "drivers" / "DTrack_drv" / "example.jconf")
    shown = plugin_lines(result.stdout)
    assert shown[0].split()[:2] == ["ok", "DTrack_drv"]
    assert len(shown) == 2
    assert "other plug-ins found and loading, unused by the configuration" in shown[1]
    assert "PinchGlove_drv" not in result.stdout


def test_a_configuration_of_built_in_devices_lists_none(cli):
    result = cli("doctor", REPO / "examples" / "waveform.jconf")
    (line,) = plugin_lines(result.stdout)
    assert "plug-ins found and loading, unused by the configuration" in line
    assert "other" not in line


def test_the_overview_lists_every_plug_in(cli):
    result = cli("doctor")
    shown = plugin_lines(result.stdout)
    assert len(shown) >= 20 and any("PinchGlove_drv" in line for line in shown)


def test_no_vrpn_server_is_said_once(cli):
    with socket.socket() as closed:  # bound, never listening: a connection is refused
        closed.bind(("127.0.0.1", 0))
        location = f"tcp://127.0.0.1:{closed.getsockname()[1]}"
        result = cli("doctor", f"vrpn:Tracker0@{location}", "--probe", "--timeout", "2")
    assert result.exit_code == 1
    problem = next(line for line in result.stdout.splitlines() if "PROBLEM" in line)
    assert problem.endswith(f"no VRPN server answers at {location}: Connection refused")
    assert problem.count(location) == 2  # the device's name and the place, not a third time


def test_one_sensor_is_singular(cli):
    with VrpnEmulator(0, scenario="idle", rate=50, sensors=1, buttons=1, channels=2) as emu:
        result = cli("doctor", f"vrpn:Tracker0@{emu.address}", "--probe", "--timeout", "5")
    assert result.exit_code == 0, result.stdout
    assert "(reports show 1 sensor)" in result.stdout, result.stdout
