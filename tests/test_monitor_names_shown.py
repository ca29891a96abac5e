"""What `monitor` shows under a name (issue 25 items 8 and 9): `--format events` gives a
selected alias's or proxy's own value under its name, as the application reading it sees it,
not its device's units; and `monitor vrpn:...` titles the live view with what was typed, not
an internal scratch file."""

from __future__ import annotations

import re
import shlex
import sys

import pytest
from tmux_pane import Pane

from conftest import REPO

sys.path.insert(0, str(REPO / "drivers"))
from VRPN_drv.emulator import VrpnEmulator

pytestmark = pytest.mark.timeout(60)

WAVEFORM = REPO / "examples" / "waveform.jconf"
LINE = re.compile(r"^\d+\.\d{6}  (.+?)  (\w+)  (.*)$")


def event_lines(text: str) -> list[tuple[str, str, str]]:
    found = []
    for line in text.splitlines():
        match = LINE.match(line)
        assert match, line
        found.append(match.groups())
    return found


def test_events_of_an_alias_are_its_own_value(cli):
    result = cli("monitor", WAVEFORM, "VJHead", "--format", "events", "--duration", "0.6")
    assert result.exit_code == 0, result.stderr
    events = event_lines(result.stdout)
    assert events, "the head spins: its pose changes"
    assert {(name, kind) for name, kind, _ in events} == {("VJHead", "position")}


def test_events_of_an_analog_proxy_are_normalised_with_the_raw_reading(cli):
    result = cli("monitor", WAVEFORM, "Stick X Proxy", "--format", "events", "--duration", "0.6")
    assert result.exit_code == 0, result.stderr
    events = event_lines(result.stdout)
    assert events and {name for name, _, _ in events} == {"Stick X Proxy"}
    for _, kind, value in events:
        assert kind == "analog"
        normal, raw = re.fullmatch(r"(\S+) raw (\S+)", value).groups()
        assert 0.0 <= float(normal) <= 1.0 and -1.0 <= float(raw) <= 1.0


def test_without_names_events_stay_those_of_the_devices(cli):
    result = cli("monitor", WAVEFORM, "--format", "events", "--duration", "0.3")
    names = {name for name, _, _ in event_lines(result.stdout)}
    assert names and all(re.fullmatch(r"Waveform \w+\[\d+\]", name) for name in names), names


def test_the_title_of_a_vrpn_watch_is_what_was_typed():
    with VrpnEmulator(0, scenario="idle", rate=50, sensors=1) as emu:
        target = f"vrpn:Tracker0@{emu.address}"
        command = " ".join(
            shlex.quote(str(a)) for a in (sys.executable, "-m", "gadgetctl", "monitor", target)
        )
        with Pane(command, cols=120, rows=30) as pane:
            title = pane.line(r"^gadgetctl monitor ")
            assert target in title
            assert "gadgetctl-vrpn-" not in title and ".jconf" not in title
            pane.keys("q", literal=True)
            pane.wait_for(r"EXIT=\d")
