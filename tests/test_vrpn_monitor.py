"""`gadgetctl monitor vrpn:Device@host`: watching VRPN devices with no configuration, against
the VRPN driver's emulator (gadgetctl's VRPN server) on loopback."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from conftest import REPO

sys.path.insert(0, str(REPO / "drivers"))
from VRPN_drv.emulator import VrpnEmulator, sensor_pose
from VRPN_drv.standalone import pose_matrix

pytestmark = pytest.mark.timeout(60)


def records(text: str) -> list[dict]:
    return [json.loads(line) for line in text.splitlines() if line.strip()]


def test_watch_tracker_and_buttons_without_a_configuration(cli, tmp_path: Path) -> None:
    record = tmp_path / "watch.ndjson"
    with VrpnEmulator(0, scenario="idle", rate=100, sensors=3, buttons=5, channels=2) as emu:
        result = cli(
            "monitor",
            f"vrpn:Tracker0@{emu.address}",
            f"vrpn:Button0@tcp://{emu.address}",
            "--duration",
            "1",
            "--format",
            "ndjson",
            "--record",
            record,
        )
    assert result.exit_code == 0, result.stderr
    recs = records(result.stdout)
    elements = recs[0]["info"]["elements"]
    tracker, buttons = f"Tracker0@{emu.address}", f"Button0@tcp://{emu.address}"
    # The layout comes from the server: 3 sensors, 5 buttons, nothing else.
    assert elements[tracker]["units"] == {"position": 3}
    assert elements[buttons]["units"] == {"digital": 5}
    samples = [r for r in recs if r["type"] == "sample"]
    poses = [r for r in samples if r["device"] == tracker and r["kind"] == "position"]
    assert poses
    for unit in range(3):
        position, quat = sensor_pose(0, unit, False)
        last = [r for r in poses if r["unit"] == unit][-1]
        np.testing.assert_allclose(np.array(last["value"]), pose_matrix(position, quat), atol=1e-9)
    assert [r for r in samples if r["device"] == buttons and r["kind"] == "digital"]
    statuses = {r["name"]: r["state"] for r in recs if r["type"] == "status"}
    assert statuses[tracker] == statuses[buttons] == "running"
    # The server's timestamps are kept: arrival minus source time, least and mean above it.
    (stats,) = [r for r in recs if r["type"] == "stats"]
    clock = stats["devices"][tracker]["source_clock"]
    assert clock["samples"] > 10 and abs(clock["offset"]) < 1.0 and clock["latency"] >= 0.0
    # The recording replays like any other.
    summary = cli("replay", record, "--summary")
    assert summary.exit_code == 0, summary.stderr
    assert tracker in summary.stdout


def test_a_wrong_device_name_lists_the_announced_ones(cli) -> None:
    with VrpnEmulator(0, scenario="idle", rate=50) as emu:
        result = cli("monitor", f"vrpn:Trackr0@{emu.address}", "--duration", "0.2")
    assert result.exit_code == 2
    assert "has no device 'Trackr0'; it announces: Analog0, Button0, Tracker0" in result.stderr
    assert "Traceback" not in result.stderr


def test_no_server_and_bad_names_are_usage_errors(cli) -> None:
    import socket

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as holder:  # a port nobody serves
        holder.bind(("127.0.0.1", 0))
        port = holder.getsockname()[1]
        result = cli("monitor", f"vrpn:Tracker0@tcp://127.0.0.1:{port}", "--duration", "0.2")
    assert result.exit_code == 2
    assert f"cannot connect to tcp://127.0.0.1:{port}: Connection refused" in result.stderr
    bad = cli("monitor", "vrpn:Tracker0", "--duration", "0.2")
    assert bad.exit_code == 2 and "Device@host" in bad.stderr


def _replay_capture(conn, _n: int) -> None:
    """Send what the real VRPN C++ library sent (drivers/VRPN_drv/tests/conformance, see its
    README), then keep the connection open until the client leaves."""
    conn.sendall((REPO / "drivers/VRPN_drv/tests/conformance/vrpn0738_tcp.bin").read_bytes())
    conn.settimeout(10)
    while conn.recv(65536):
        pass


def test_watch_a_dial_of_the_real_vrpn_library(cli) -> None:
    from vrpn_peers import RawServer

    with RawServer(_replay_capture) as server:
        name = f"Dial0@tcp://127.0.0.1:{server.port}"
        result = cli("monitor", f"vrpn:{name}", "--duration", "0.5", "--format", "ndjson")
    assert result.exit_code == 0, result.stderr
    recs = records(result.stdout)
    assert recs[0]["info"]["elements"][name]["units"] == {"analog": 3}
    values = {}
    for r in recs:
        if r["type"] == "sample" and r["device"] == name and r["kind"] == "analog":
            values[r["unit"]] = r.get("raw", r["value"])
    # dial 0 turned by +0.05 and dial 2 by -0.125 revolutions, dial 1 not at all
    assert values[0] == pytest.approx(0.05) and values[2] == pytest.approx(-0.125)


def _replay_capture_repeating_its_text(conn, _n: int) -> None:
    """The real library's capture (see :func:`_replay_capture`), then its last message (the
    1056-byte text message of Text0) again every 50 ms until the client leaves."""
    import select

    capture = (REPO / "drivers/VRPN_drv/tests/conformance/vrpn0738_tcp.bin").read_bytes()
    text = capture[-1056:]
    conn.sendall(capture)
    while True:
        readable, _, _ = select.select([conn], [], [], 0.05)
        if readable and not conn.recv(65536):
            return
        conn.sendall(text)


def test_watch_a_text_sender_of_the_real_vrpn_library(cli) -> None:
    from vrpn_peers import RawServer

    with RawServer(_replay_capture_repeating_its_text) as server:
        name = f"Text0@tcp://127.0.0.1:{server.port}"
        result = cli(
            "monitor", f"vrpn:{name}", "--duration", "0.5", "--format", "ndjson", "--stats"
        )
    assert result.exit_code == 0, result.stderr
    recs = records(result.stdout)
    assert recs[0]["info"]["elements"][name]["units"] == {}
    (stats,) = [r for r in recs if r["type"] == "stats"]
    health = stats["devices"][name]["health"]
    assert health["text_messages"] >= 1
    assert health["last_text"] == "warning 3 from Text0: capture done"
