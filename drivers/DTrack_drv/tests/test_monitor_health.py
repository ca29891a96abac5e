"""Driver health in the monitor (issue 16 item 3): the garbage scenario of the DTrack emulator
makes the driver count bad datagrams and lines, and the live view, the table and the ndjson
statistics show those counters (``Input.health()``)."""

from __future__ import annotations

import json
import shlex
import subprocess
import sys
from pathlib import Path

import pytest
from DTrack_drv.emulator import DTrackEmulator

from gadgetctl.cli.monitor_text import health_text
from gadgetctl.input.testing.commands import run_gadgetctl
from gadgetctl.input.testing.configs import configuration, free_udp_port

pytestmark = pytest.mark.timeout(120)


def tracker_configuration(tmp_path: Path) -> tuple[Path, int]:
    port = free_udp_port()
    path = tmp_path / "dtrack.jconf"
    path.write_text(
        configuration(
            "DTrack_drv",
            f'<dtrack name="DT" version="1"><receive_port>{port}</receive_port></dtrack>\n',
        )
    )
    return path, port


def monitor(path: Path, *args: str) -> subprocess.CompletedProcess:
    return run_gadgetctl("monitor", str(path), "DT", *args, timeout=90)


def test_the_table_and_the_ndjson_statistics_show_the_garbage_counted(tmp_path: Path) -> None:
    path, port = tracker_configuration(tmp_path)
    with DTrackEmulator(port, scenario="garbage", rate=100.0, seed=3):
        table = monitor(path, "--format", "table", "--duration", "1.5")
        records = monitor(path, "--format", "ndjson", "--duration", "1.5")
    assert table.returncode == 0, table.stderr[-2000:]
    row = [line for line in table.stdout.splitlines() if line.startswith("DT ")][-1]
    counted = {
        name: int(n)
        for name, n in (
            part.split()
            for part in row.split("health: ")[1].split(", ")
            if not part.startswith("last")
        )
    }
    assert counted["bad_datagrams"] > 0 and counted["bad_lines"] > 0
    assert records.returncode == 0, records.stderr[-2000:]
    stats = [json.loads(line) for line in records.stdout.splitlines() if '"type":"stats"' in line]
    assert len(stats) == 1
    health = json.dumps(stats[0])
    found = json.loads(health)
    device = next(v for k, v in _walk(found) if k == "DT")
    assert device["health"]["bad_datagrams"] > 0 and device["health"]["bad_lines"] > 0
    assert device["health"]["faults"] == 0 and device["health"]["reconnects"] == 0


def _walk(value):
    if isinstance(value, dict):
        for key, item in value.items():
            yield key, item
            yield from _walk(item)
    elif isinstance(value, list):
        for item in value:
            yield from _walk(item)


def test_the_live_view_shows_the_health_counters(tmp_path: Path) -> None:
    sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "tests"))
    from tmux_pane import Pane

    path, port = tracker_configuration(tmp_path)
    command = " ".join(
        shlex.quote(a)
        for a in (sys.executable, "-m", "gadgetctl", "monitor", str(path), "DT", "--no-mouse")
    )
    with (
        DTrackEmulator(port, scenario="garbage", rate=100.0, seed=3),
        Pane(command, cols=200, rows=30) as pane,
    ):
        found = pane.wait_for(
            r"^DT\s+dtrack\s+running.*health: bad_datagrams (\d+), bad_lines (\d+)"
        )
        assert int(found.group(1)) > 0 and int(found.group(2)) > 0
        pane.keys("q", literal=True)
        pane.wait_for(r"EXIT=0")


def test_health_text_names_trouble_only_and_the_last_fault():
    assert health_text({"datagrams": 10, "bad_datagrams": 0, "faults": 0, "dropped": 0}) == ""
    text = health_text(
        {
            "packets": 5,
            "skipped_bytes": 12,
            "reconnects": 1,
            "faults": 1,
            "last_fault": "no data for 2 s",
            "last_fault_at": 0.0,
        }
    )
    assert text.startswith(
        "skipped_bytes 12, reconnects 1, faults 1, last fault "
    ) and text.endswith("no data for 2 s")
