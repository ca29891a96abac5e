"""`gadgetctl replay FILE.vrpn`: VRPN log files (reference section 11) summarised and replayed
through the pipeline, alone, with --config (vrpn elements route the senders) and --map."""

from __future__ import annotations

import json
import math
import struct
from pathlib import Path

import numpy as np
import pytest

from gadgetctl.vrpn import LogWriter, codecs

from conftest import REPO

pytestmark = pytest.mark.timeout(60)
T0 = 1_700_000_000.0
EXAMPLE = REPO / "drivers" / "VRPN_drv" / "example.jconf"


def quat(i: int) -> tuple[float, float, float, float]:
    return (0.0, 0.0, math.sin(0.01 * i), math.cos(0.01 * i))


def make_log(path: Path, ticks: int = 100) -> Path:
    with LogWriter(path) as log:
        for i in range(ticks):
            t = T0 + 0.01 * i
            for sensor in range(2):
                log.write(
                    "Tracker0",
                    codecs.TRACKER_POS_QUAT,
                    codecs.encode_pose(sensor, (0.01 * i, float(sensor), -0.5), quat(i)),
                    t,
                )
            if i % 10 == 0:
                log.write(
                    "Button0",
                    codecs.BUTTON_CHANGE,
                    codecs.encode_button_change(1, (i // 10) % 2),
                    t,
                )
            log.write(
                "Analog0", codecs.ANALOG_CHANNEL, codecs.encode_analog([math.sin(0.1 * i), 0.5]), t
            )
    return path


def records(text: str) -> list[dict]:
    return [json.loads(line) for line in text.splitlines() if line.strip()]


def test_summary(cli, tmp_path: Path) -> None:
    log = make_log(tmp_path / "session.vrpn")
    result = cli("replay", log, "--summary", "--format", "ndjson")
    assert result.exit_code == 0, result.stderr
    summary = json.loads(result.stdout)
    devices = {d["name"]: d for d in summary["devices"]}
    assert set(devices) == {"Tracker0", "Button0", "Analog0"}
    assert devices["Tracker0"]["samples"] == 200 and devices["Button0"]["samples"] == 10
    assert devices["Analog0"]["samples"] == 200
    assert summary["duration"] == pytest.approx(0.99)
    assert summary["end_reason"] == "end of the VRPN log"
    text = cli("replay", log, "--summary")
    assert "Tracker0: 100 updates, 200 samples" in text.stdout


def test_replay_delivers_the_logged_values(cli, tmp_path: Path) -> None:
    log = make_log(tmp_path / "session.vrpn", ticks=50)
    result = cli("replay", log, "--speed", "5", "--format", "ndjson")
    assert result.exit_code == 0, result.stderr
    samples = [r for r in records(result.stdout) if r["type"] == "sample"]
    poses = [r for r in samples if r["device"] == "Tracker0" and r["unit"] == 1]
    assert len(poses) == 50
    last = np.array(poses[-1]["value"])
    assert last[:3, 3] == pytest.approx([0.49, 1.0, -0.5], abs=1e-9)
    angle = 2 * 0.01 * 49  # the quaternion's rotation about z
    assert last[0, 0] == pytest.approx(math.cos(angle), abs=1e-9)
    assert last[1, 0] == pytest.approx(math.sin(angle), abs=1e-9)
    buttons = [r["value"] for r in samples if r["device"] == "Button0" and r["unit"] == 1]
    assert buttons == [0, 1, 0, 1, 0]
    analog = [r for r in samples if r["device"] == "Analog0" and r["unit"] == 0]
    assert analog[-1]["raw"] == pytest.approx(math.sin(4.9), abs=1e-12)
    assert analog[-1]["value"] == pytest.approx((math.sin(4.9) + 1) / 2, abs=1e-12)


@pytest.mark.parametrize(
    "maps", [[], ["--map", "Tracker0=Vrpn", "--map", "Button0=Vrpn", "--map", "Analog0=Vrpn"]]
)
def test_replay_against_a_configuration(cli, tmp_path: Path, maps: list[str]) -> None:
    log = make_log(tmp_path / "session.vrpn", ticks=40)
    result = cli(
        "replay",
        log,
        "--config",
        EXAMPLE,
        *maps,
        "--speed",
        "5",
        "--format",
        "ndjson",
        "--per-frame",
    )
    assert result.exit_code == 0, result.stderr
    recs = records(result.stdout)
    statuses = {r["name"]: r["state"] for r in recs if r["type"] == "status"}
    for name in ("Vrpn", "HeadProxy", "WandProxy", "VJHead", "VJWand", "VJButton0", "Analog0Proxy"):
        assert statuses[name] in ("running", "active"), (name, statuses[name])
    frames = [r for r in recs if r["type"] == "frame"]
    (wand,) = frames[-1]["devices"]["VJWand"]["values"]["position"].values()  # keyed by unit 1
    wand = np.array(wand)
    assert wand[:3, 3] == pytest.approx([0.39, 1.0, -0.5], abs=1e-9)  # the proxy and alias deliver
    presses = [
        f["devices"]["Button1Proxy"]["values"]["digital"]["1"]
        for f in frames
        if "Button1Proxy" in f["devices"]
    ]
    assert presses and set(presses) & {1, 2}  # ON or TOGGLE_ON: the logged press arrives


def test_damaged_logs(cli, tmp_path: Path) -> None:
    log = make_log(tmp_path / "session.vrpn", ticks=20)
    data = log.read_bytes()
    cut = tmp_path / "cut.vrpn"
    cut.write_bytes(data[:-7])
    result = cli("replay", cut, "--summary")
    assert result.exit_code == 0 and "ends inside a record" in result.stdout + result.stderr
    bad = tmp_path / "bad.vrpn"
    bad.write_bytes(data[:24] + struct.pack(">iiiiii", 3, 0, 0, 0, 2**31 - 1, 0) + b"x" * 64)
    result = cli("replay", bad, "--summary")
    assert "record length" in result.stdout + result.stderr
    assert "Traceback" not in result.stderr
    future = tmp_path / "future.vrpn"
    future.write_bytes(b"vrpn: ver. 08.00  0" + b"\0" * 5)
    result = cli("replay", future, "--summary")
    assert result.exit_code == 2 and "08.00" in result.stderr


#: A log written by the real VRPN C++ library (vrpn/vrpn 893c7496, 07.38): its own outgoing
#: log of the scripted Tracker0/Button0/Analog0/Dial0/Text0 session described in
#: drivers/VRPN_drv/tests/conformance/README.md (the server program logging what it sent).
REAL_LOG = REPO / "drivers" / "VRPN_drv" / "tests" / "conformance" / "vrpn0738_out.vrpn"


def test_replay_of_a_log_the_real_library_wrote(cli) -> None:
    result = cli("replay", REAL_LOG, "--format", "ndjson")
    assert result.exit_code == 0, result.stderr
    recs = records(result.stdout)
    samples = [r for r in recs if r["type"] == "sample"]
    # dials are analog units holding their accumulated rotation in revolutions
    dial = {r["unit"]: r["raw"] for r in samples if r["device"] == "Dial0"}
    assert dial == {0: pytest.approx(0.05), 1: 0.0, 2: pytest.approx(-0.125)}
    # the text message is a marker, 0.3 s after the first tracker tick
    (marker,) = [r for r in recs if r["type"] == "marker"]
    assert marker["name"] == "Text0: warning 3: capture done"
    # the button server's messages carry time 0: they take the time before them, so the
    # whole log spans 0.3 s (not 1.7e9 s from 1970)
    times = [r["timestamp"] for r in samples] + [marker["timestamp"]]
    assert max(times) - min(times) == pytest.approx(0.3, abs=1e-3)
    assert {r["unit"] for r in samples if r["device"] == "Button0"} == {0, 1, 2, 3}


def test_a_log_starting_at_time_0_replays_at_once(tmp_path: Path, cli) -> None:
    path = tmp_path / "zero.vrpn"
    with LogWriter(path) as log:
        for i in range(5):
            pose = codecs.encode_pose(0, (0.01 * i, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))
            log.write("Tracker0", codecs.TRACKER_POS_QUAT, pose, 0.0 if i == 0 else T0 + 0.01 * i)
    result = cli("replay", path, "--format", "ndjson")
    assert result.exit_code == 0, result.stderr
    assert "pause" not in result.stderr
    times = [r["timestamp"] for r in records(result.stdout) if r["type"] == "sample"]
    # (the time-0 pose shares the next one's time: the replay keeps one sample per instant)
    assert len(times) >= 4 and max(times) - min(times) == pytest.approx(0.03, abs=2e-3)
