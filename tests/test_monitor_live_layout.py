"""The responsive live view (issue 16 item 1), in real terminals of three sizes (tmux): names,
states, rates and values stay readable at 80x24, statistics appear as room allows, a resize
re-lays the view out, and v switches between the compact and the detailed layout.
"""

from __future__ import annotations

import re
import shlex
import sys

import pytest
from tmux_pane import Pane

from conftest import REPO

pytestmark = pytest.mark.timeout(90)

WAVEFORM = REPO / "examples" / "waveform.jconf"
ALL_DEVICES = REPO / "examples" / "all_devices.jconf"
SHOWN = ("Waveform", "Wave Position Proxy", "Wave Analog Proxy", "Sim Head", "Head Proxy")
DEVICE_ROW = r"^Waveform\s+.*running\s+\d+\.\d Hz.*$"
POSITION_VALUE = r"x [+-]\d\.\d{3} y [+-]\d\.\d{3} z [+-]\d\.\d{3} m"


def command(*extra: str) -> str:
    return " ".join(
        shlex.quote(str(a))
        for a in (
            sys.executable,
            "-m",
            "gadgetctl",
            "monitor",
            ALL_DEVICES,
            *SHOWN,
            "--no-mouse",
            *extra,
        )
    )


def readable(pane: Pane) -> dict[str, str]:
    """The lines of the shown elements, checked for what must be readable at any width."""
    rows = {
        "device": pane.line(r"^Waveform\s+.*running\s+\d+\.\d Hz"),
        "device position": pane.line(rf"^\s+position 0\s+{POSITION_VALUE}"),
        "device analog": pane.line(r"^\s+analog 0\s.*[01]\.\d{3}"),
        "position proxy": pane.line(rf"^\s+Wave Position Proxy\s.*active\s+{POSITION_VALUE}"),
        "analog proxy": pane.line(r"^\s+Wave Analog Proxy\s.*active\s.*\d\.\d{3}"),
        "sim proxy": pane.line(r"^\s+Head Proxy\s.*active\s+x \+0\.000 y \+1\.800 z \+0\.000 m"),
    }
    return rows


@pytest.mark.parametrize(("cols", "rows"), [(80, 24), (120, 40), (200, 50)])
def test_names_states_and_values_are_readable_at_each_size(cols, rows):
    with Pane(command(), cols=cols, rows=rows) as pane:
        pane.wait_for(r"q quit  p pause")
        lines = readable(pane)
        device = lines["device"]
        assert "dropped 0" in device and "age" in device
        if cols >= 200:  # everything fits: type, per-frame count and the interval statistics
            assert all(
                word in device for word in ("waveform_device", "/frame", "jitter", "p99", "max gap")
            )
            assert "position_proxy → Waveform[0]" in lines["position proxy"]  # the target too
            assert "rot" in lines["position proxy"]
        if cols <= 80:  # the least important columns gave way to the values
            assert "max gap" not in device and "jitter" not in device
            assert "position_proxy" not in lines["position proxy"]
        pane.keys("q", literal=True)
        pane.wait_for(r"EXIT=0")


def test_a_resize_re_lays_the_view_out():
    with Pane(command(), cols=200, rows=50) as pane:
        assert "max gap" in pane.line(DEVICE_ROW)
        pane.resize(80, 24)
        pane.wait_for(r"^Waveform\s+running\s+\d+\.\d Hz\s+dropped \d+\s+age")  # the type left too
        readable(pane)
        pane.resize(120, 40)
        pane.wait_for(r"^Waveform\s+waveform_device\s+running\s+\d+\.\d Hz")
        readable(pane)
        pane.keys("q", literal=True)
        pane.wait_for(r"EXIT=0")


def test_v_switches_between_the_compact_and_the_detailed_layout():
    with Pane(command(), cols=200, rows=50) as pane:
        assert "waveform_device" in pane.line(DEVICE_ROW)
        pane.keys("v", literal=True)
        pane.wait_for(r"compact layout \(v switches\)")
        compact = pane.wait_for(
            r"^Waveform\s+running\s+\d+\.\d Hz\s+dropped \d+\s+age\s+\S+ ms\s*$"
        ).group(0)
        assert "jitter" not in compact
        readable(pane)
        pane.keys("v", literal=True)
        pane.wait_for(r"^Waveform\s+waveform_device\s+running.*max gap")
        pane.keys("q", literal=True)
        pane.wait_for(r"EXIT=0")


def test_quitting_the_live_view_prints_a_summary_with_the_recording(tmp_path):
    path = tmp_path / "run.ndjson"
    shown = " ".join(
        shlex.quote(str(a))
        for a in (
            sys.executable,
            "-m",
            "gadgetctl",
            "monitor",
            WAVEFORM,
            "Waveform Noise",
            "--record",
            path,
        )
    )
    with Pane(shown, cols=160, rows=40) as pane:
        pane.wait_for(r"^Waveform Noise\s+waveform_device\s+running")
        pane.keys("m", literal=True)
        pane.wait_for(r"marker name")
        pane.keys("here", "Enter")
        pane.wait_for(r"marker 'here' written to the recording")
        pane.keys("q", literal=True)
        pane.wait_for(r"EXIT=0")
        screen = pane.screen()
    assert "q quit" not in screen  # the live view is gone, the summary stays
    assert "frames: " in screen and "statistics:" in screen
    row = next(line for line in screen.splitlines() if line.startswith("Waveform Noise"))
    assert "running" in row and int(row.split()[3]) > 0  # samples
    found = re.search(r"recording: (\S+): (\d+) samples, 1 marker$", screen, re.MULTILINE)
    assert found and found.group(1) == str(path)
    records = path.read_text().splitlines()
    assert int(found.group(2)) == sum('"type":"sample"' in line for line in records) > 0
