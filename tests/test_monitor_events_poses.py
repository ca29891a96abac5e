"""`--format events` (changes only, one line each) and `--pose matrix|quaternion|euler`, and
the replay summary's per-axis ranges and sparklines, through the command line."""

from __future__ import annotations

import json
import math
import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from LinuxJoydev_drv.emulator import JS_EVENT_AXIS, JoydevEmulator

from gadgetctl.monitor.poses import (
    euler_xyz_degrees_batch,
    matrix_from_pose,
    pose_values,
    quaternions_wxyz,
)
from gadgetctl.monitor.recording import Recorder, read_recording
from gadgetctl.monitor.records import SampleRecord
from gadgetctl.monitor.sparkline import BARS, MID
from gadgetctl.monitor.units import (
    euler_xyz_degrees,
    quaternion_wxyz,
    rotation_from_euler_xyz_degrees,
)

from conftest import REPO, write

WAVEFORM = REPO / "examples" / "waveform.jconf"
LINE = re.compile(r"^(-?\d+\.\d{6})  (.+?)(?:\[(\d+)\])?  (\w+)  (.*)$")

pytestmark = pytest.mark.timeout(90)


def gadgetctl(*args: str | Path, timeout: float = 60) -> subprocess.CompletedProcess:
    env = {**os.environ, "NO_COLOR": "1"}
    env.pop("GADGETCTL_DEBUG", None)
    return subprocess.run(
        [sys.executable, "-m", "gadgetctl", *map(str, args)],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=timeout,
        env=env,
        stdin=subprocess.DEVNULL,
    )


def popen(*args: str | Path) -> subprocess.Popen:
    env = {**os.environ, "NO_COLOR": "1"}
    env.pop("GADGETCTL_DEBUG", None)
    return subprocess.Popen(
        [sys.executable, "-m", "gadgetctl", *map(str, args)],
        cwd=REPO,
        env=env,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def parse(text: str) -> list[tuple[float, str, int | None, str, str]]:
    lines = []
    for line in text.splitlines():
        match = LINE.match(line)
        assert match, f"not an event line: {line!r}"
        time, name, unit, kind, value = match.groups()
        lines.append((float(time), name, None if unit is None else int(unit), kind, value))
    return lines


def joystick_config(directory: Path, port: str, extra: str = "") -> Path:
    """A configuration of one linux_joydev device, Stick, reading ``port``."""
    return write(
        directory / "stick.jconf",
        f"""<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="stick">
<elements>
<input_manager name="IM" version="2"><driver>LinuxJoydev_drv</driver></input_manager>
<linux_joydev name="Stick" version="1"><port_name>{port}</port_name>{extra}</linux_joydev>
</elements>
</configuration>
""",
    )


def position_of(value: str) -> tuple[np.ndarray, np.ndarray]:
    """(x y z, rot x y z) of an events line's position text (Euler form)."""
    numbers = re.fullmatch(r"x (\S+) y (\S+) z (\S+) m  rot (\S+) (\S+) (\S+) deg", value)
    assert numbers, value
    values = [float(v) for v in numbers.groups()]
    return np.array(values[:3]), np.array(values[3:])


# --------------------------------------------------------------------------- poses (library)


def test_batch_conversions_agree_with_the_single_ones_and_read_back():
    rng = np.random.default_rng(7)
    matrices = np.tile(np.eye(4), (200, 1, 1))
    for i in range(200):
        angles = rng.uniform(-180, 180, 3)
        angles[1] = rng.uniform(-89, 89)
        matrices[i, :3, :3] = rotation_from_euler_xyz_degrees(*angles)
        matrices[i, :3, 3] = rng.uniform(-2, 2, 3)
    matrices[0, :3, :3] = rotation_from_euler_xyz_degrees(30, 90, 0)  # gimbal lock
    matrices[1, :3, :3] = np.diag([1.0, -1.0, -1.0])  # w = 0: a half turn
    eulers = euler_xyz_degrees_batch(matrices)
    quaternions = quaternions_wxyz(matrices)
    for m, e, q in zip(matrices, eulers, quaternions, strict=True):
        assert e == pytest.approx(euler_xyz_degrees(m), abs=1e-9)
        assert q == pytest.approx(quaternion_wxyz(m), abs=1e-9) or q == pytest.approx(
            -quaternion_wxyz(m), abs=1e-9
        )
        assert np.linalg.norm(q) == pytest.approx(1.0) and q[0] >= 0
    for pose in ("matrix", "quaternion", "euler"):
        values = json.loads(json.dumps(pose_values(matrices, pose)))
        back = np.stack([matrix_from_pose(v) for v in values])
        assert back == pytest.approx(matrices, abs=1e-9), pose
    one = pose_values(matrices[5], "quaternion")[0]
    assert set(one) == {"position", "quaternion_wxyz"} and one["position"] == pytest.approx(
        matrices[5, :3, 3]
    )
    assert set(pose_values(matrices[5], "euler")[0]) == {"position", "euler_xyz_degrees"}


# --------------------------------------------------------------------------- --format events


def test_events_report_changes_only_beyond_the_thresholds():
    result = gadgetctl(
        "monitor",
        WAVEFORM,
        "Waveform Sticks",
        "Waveform Tracker",
        "--duration",
        "2.6",
        "--format",
        "events",
        "--dead-band",
        "0.1",
    )
    assert result.returncode == 0, result.stderr
    assert "Traceback" not in result.stderr
    lines = parse(result.stdout)
    kinds = {kind for _, _, _, kind, _ in lines}
    assert {"digital", "analog", "position", "command", "string", "hat"} <= kinds
    last: dict[tuple[str, int | None, str], object] = {}
    for _, name, unit, kind, value in lines:
        key = (name, unit, kind)
        if kind == "digital":
            assert value in ("pressed", "released")
            assert last.get(key) != value, f"{key}: {value} twice in a row"
            last[key] = value
        elif kind == "analog":
            normal, raw = re.fullmatch(r"(\d\.\d{4}) raw (\S+)", value).groups()
            assert -1.0 <= float(raw) <= 1.0  # the device's own range (min -1, max 1)
            if key in last:
                assert abs(float(normal) - last[key]) > 0.1 - 1e-4, (
                    f"{key}: moved within the dead band"
                )
            last[key] = float(normal)
        elif kind == "position":
            where, turn = position_of(value)
            if key in last:
                before, turned = last[key]
                moved = np.linalg.norm(where - before)
                assert moved > 0.01 - 2e-4 or np.abs(turn - turned).max() > 1.0 - 0.1, (
                    f"{key}: too small a change"
                )
            last[key] = (where, turn)
        elif kind == "command":
            assert value == "1" and name == "Waveform Tracker" and unit == 0
        elif kind == "string":
            assert value == '"event 1"'
    # the circle (radius 0.5 m, period 4 s, 1.6 m up after the filter) is seen at its height
    circle = [
        position_of(v)[0]
        for _, n, u, k, v in lines
        if (n, u, k) == ("Waveform Tracker", 0, "position")
    ]
    assert len(circle) > 20
    assert all(abs(math.hypot(p[0], p[2]) - 0.5) < 1e-3 and abs(p[1] - 1.6) < 1e-3 for p in circle)
    # the buttons square waves (1 s and 2.5 s periods) change, in time order
    assert sum(1 for _, n, u, k, _ in lines if (n, u, k) == ("Waveform Sticks", 0, "digital")) >= 2
    times = [t for t, *_ in lines]
    assert times[0] >= 0


def test_events_are_the_recorded_samples_by_the_documented_rule(tmp_path):
    """The events of a run follow, sample for sample, from its recording: a 1 kHz noise
    channel and a square wave against the dead band, buttons at every change."""
    path = tmp_path / "run.ndjson"
    result = gadgetctl(
        "monitor",
        WAVEFORM,
        "Waveform Noise",
        "Waveform Sticks",
        "--duration",
        "1.5",
        "--format",
        "events",
        "--record",
        path,
        "--dead-band",
        "0.05",
    )
    assert result.returncode == 0, result.stderr
    seen: dict[tuple[str, int, str], list[str]] = {}
    for _, name, unit, kind, value in parse(result.stdout):
        seen.setdefault((name, unit, kind), []).append(value)
    expected: dict[tuple[str, int, str], list[str]] = {}
    last: dict[tuple[str, int, str], float] = {}
    samples = sorted(
        (r for r in read_recording(path).records if isinstance(r, SampleRecord)),
        key=lambda r: r.timestamp,
    )
    for record in samples:
        key = (record.device, record.unit, record.kind)
        if key not in last:
            last[key] = record.value
            continue
        if record.kind == "digital" and record.value != last[key]:
            expected.setdefault(key, []).append("pressed" if record.value else "released")
            last[key] = record.value
        elif record.kind == "analog" and abs(record.value - last[key]) > 0.05:
            raw = record.raw
            text = str(int(raw)) if float(raw).is_integer() else f"{raw:.6g}"
            expected.setdefault(key, []).append(f"{record.value:.4f} raw {text}")
            last[key] = record.value
    assert len(expected[("Waveform Noise", 0, "analog")]) > 500
    assert seen == expected


def test_position_events_are_the_recorded_poses_by_the_documented_rule(tmp_path):
    """A pose is reported when it moved more than --pose-threshold meters, or turned more
    than --angle-threshold degrees, from the pose last reported: checked against the
    recorded matrices with plain arithmetic (the events scan them a block at a time)."""
    path = tmp_path / "run.ndjson"
    result = gadgetctl(
        "monitor",
        WAVEFORM,
        "Waveform Tracker",
        "--duration",
        "1.5",
        "--format",
        "events",
        "--pose",
        "matrix",
        "--record",
        path,
        "--pose-threshold",
        "0.02",
        "--angle-threshold",
        "4.2",  # (the spin turns 0.5 degrees a sample: 4 would be a rounding's toss)
    )
    assert result.returncode == 0, result.stderr
    seen: dict[int, list[float]] = {}
    for time, _, unit, kind, _ in parse(result.stdout):
        if kind == "position":
            seen.setdefault(unit, []).append(time)
    header = read_recording(path)
    records = sorted(
        (r for r in header.records if isinstance(r, SampleRecord) and r.kind == "position"),
        key=lambda r: r.timestamp,
    )
    origin = min(r.timestamp for r in records)
    expected: dict[int, list[float]] = {}
    last: dict[int, list[list[float]]] = {}
    for record in records:
        pose = record.value
        before = last.get(record.unit)
        if before is None:
            last[record.unit] = pose
            continue
        moved = math.dist([row[3] for row in pose[:3]], [row[3] for row in before[:3]])
        trace = sum(before[i][j] * pose[i][j] for i in range(3) for j in range(3))
        turned = math.degrees(math.acos(max(-1.0, min(1.0, (trace - 1.0) / 2.0))))
        if moved > 0.02 or turned > 4.2:
            expected.setdefault(record.unit, []).append(record.timestamp)
            last[record.unit] = pose
    assert sum(map(len, expected.values())) > 30
    assert set(seen) == set(expected)
    for unit, times in expected.items():  # the same samples (times on another origin)
        shift = seen[unit][0] - times[0]
        assert seen[unit] == pytest.approx([t + shift for t in times], abs=2e-6)
    assert origin <= min(expected[0])


def test_events_thresholds_are_options():
    result = gadgetctl(
        "monitor",
        WAVEFORM,
        "Waveform Tracker",
        "--duration",
        "1.5",
        "--format",
        "events",
        "--pose-threshold",
        "0.2",
        "--angle-threshold",
        "45",
        "--units",
        "centimeters",
    )
    assert result.returncode == 0, result.stderr
    lines = [line for line in parse(result.stdout) if line[3] == "position"]
    assert lines, result.stdout
    previous: dict[int, np.ndarray] = {}
    for _, _, unit, _, value in lines:
        numbers = re.fullmatch(r"x (\S+) y (\S+) z (\S+) cm  rot (\S+) (\S+) (\S+) deg", value)
        assert numbers, value
        where = np.array([float(v) for v in numbers.groups()[:3]]) / 100.0
        turn = np.array([float(v) for v in numbers.groups()[3:]])
        if unit in previous:
            before, turned = previous[unit]
            assert (
                np.linalg.norm(where - before) > 0.2 - 1e-3
                or np.abs(turn - turned).max() > 45 - 0.1
            )
        previous[unit] = (where, turn)
    bad = gadgetctl(
        "monitor", WAVEFORM, "--format", "events", "--dead-band", "-1", "--duration", "0"
    )
    assert bad.returncode == 2 and "--dead-band" in bad.stderr and "Traceback" not in bad.stderr


def test_events_of_a_replay_are_exact_with_raw_integers(tmp_path):
    """A recorded joystick: a button pressed and released, an axis over -32767..32767 whose
    small steps stay within the dead band; the replay's events say exactly that."""
    path = tmp_path / "stick.ndjson"
    axis = [-32767, -32767, -15450, -15400, -15000, 0, 32767]
    buttons = [0, 0, 1, 1, 1, 0, 0]
    records = []
    for i, (a, b) in enumerate(zip(axis, buttons, strict=True)):
        t = 100.0 + i * 0.05
        records.append(SampleRecord("Stick", "analog", 0, t, (a + 32767) / 65534, a))
        records.append(SampleRecord("Stick", "digital", 0, t, b, b))
    elements = {
        "Stick": {
            "element": "device",
            "type": "linux_joydev",
            "kinds": ["analog", "digital"],
            "units": {"analog": 1, "digital": 1},
            "min": -32767.0,
            "max": 32767.0,
        }
    }
    with Recorder(path, {"devices": ["Stick"], "elements": elements}) as recorder:
        recorder.write_samples(records)
    result = gadgetctl("replay", path, "--format", "events", "--speed", "4")
    assert result.returncode == 0, result.stderr
    lines = [(name, unit, kind, value) for _, name, unit, kind, value in parse(result.stdout)]
    assert lines == [
        ("Stick", 0, "analog", "0.2642 raw -15450"),
        ("Stick", 0, "digital", "pressed"),
        ("Stick", 0, "analog", "0.5000 raw 0"),
        ("Stick", 0, "digital", "released"),
        ("Stick", 0, "analog", "1.0000 raw 32767"),
    ]
    times = [t for t, *_ in parse(result.stdout)]
    assert times[1] - times[0] == pytest.approx(0.0, abs=1e-6)
    assert times[2] - times[0] == pytest.approx(0.15 / 4, abs=1e-6)  # recorded spacing, at 4x speed


def test_events_of_a_replayed_tracker_and_voice_are_exact(tmp_path):
    """Moves below the thresholds are left out; commands and strings are reported from the
    first one on, and only when they change."""
    path = tmp_path / "head.ndjson"
    poses = [
        ((0.0, 1.5, 0.0), 0.0),
        ((0.005, 1.5, 0.0), 0.0),
        ((0.02, 1.5, 0.0), 0.0),
        ((0.02, 1.5, 0.0), 0.5),
        ((0.02, 1.5, 0.0), 2.0),
    ]
    records = []
    for i, (where, turn) in enumerate(poses):
        m = np.eye(4)
        m[:3, :3] = rotation_from_euler_xyz_degrees(0.0, 0.0, turn)
        m[:3, 3] = where
        records.append(SampleRecord("Head", "position", 0, 10.0 + i * 0.05, m.tolist(), None))
    for i, (text, number) in enumerate([("hello", 3), ("hello", 3), ("bye", 4)]):
        records.append(SampleRecord("Voice", "string", 0, 10.01 + i * 0.05, text, text))
        records.append(SampleRecord("Voice", "command", 0, 10.01 + i * 0.05, number, number))
    with Recorder(path, {"devices": ["Head", "Voice"]}) as recorder:
        recorder.write_samples(records)
    result = gadgetctl("replay", path, "--format", "events", "--speed", "4")
    assert result.returncode == 0, result.stderr
    lines = parse(result.stdout)
    head = [
        value
        for _, name, unit, kind, value in lines
        if (name, unit, kind) == ("Head", 0, "position")
    ]
    assert head == [
        "x +0.0200 y +1.5000 z +0.0000 m  rot +0.0 +0.0 +0.0 deg",
        "x +0.0200 y +1.5000 z +0.0000 m  rot +0.0 +0.0 +2.0 deg",
    ]
    voice = [(kind, value) for _, name, _, kind, value in lines if name == "Voice"]
    assert [v for v in voice if v[0] == "string"] == [("string", '"hello"'), ("string", '"bye"')]
    assert [v for v in voice if v[0] == "command"] == [("command", "3"), ("command", "4")]
    assert len(lines) == 6
    quaternion = gadgetctl(
        "replay", path, "Head", "--format", "events", "--speed", "4", "--pose", "quaternion"
    )
    assert [value for *_, value in parse(quaternion.stdout)][-1] == (
        "x +0.0200 y +1.5000 z +0.0000 m  q +0.9998 +0.0000 +0.0000 +0.0175"
    )


def test_events_say_when_a_device_faults_and_comes_back(tmp_path):
    with JoydevEmulator(
        directory=tmp_path,
        scenario="disconnect",
        rate=100.0,
        buttons=2,
        axes=2,
        disconnect_after=20,
    ) as emulator:
        config = joystick_config(tmp_path, emulator.address)
        process = popen("monitor", config, "--format", "events", "--no-check")
        try:
            states = []
            for line in process.stdout:  # until the device was lost and is running again
                _, name, unit, kind, value = parse(line)[0]
                if kind == "status":
                    assert name == "Stick" and unit is None
                    states.append(value.split(":")[0])
                    lost = [
                        i for i, state in enumerate(states) if state in ("faulted", "reconnecting")
                    ]
                    if lost and "running" in states[lost[0] :]:
                        break
            process.send_signal(signal.SIGINT)
            _, err = process.communicate(timeout=30)
        finally:
            if process.poll() is None:
                process.kill()
                process.communicate()
    assert "faulted" in states and states[-1] == "running", states  # a fault between frames too
    assert process.returncode in (0, 1) and "Traceback" not in err


def test_events_and_table_show_a_joysticks_raw_integers(tmp_path):
    with JoydevEmulator(
        directory=tmp_path, scenario="motion", rate=100.0, buttons=2, axes=2
    ) as emulator:
        config = joystick_config(
            tmp_path, emulator.address, "<min>-32767.0</min><max>32767.0</max>"
        )
        events = gadgetctl(
            "monitor", config, "--format", "events", "--duration", "1.5", "--dead-band", "0"
        )
        table = gadgetctl(
            "monitor", config, "--format", "table", "--duration", "1", "--interval", "10"
        )
        sent = {(number, value) for _, value, kind, number in emulator.sent if kind & JS_EVENT_AXIS}
    assert events.returncode == 0, events.stderr
    axes = [(unit, value) for _, _, unit, kind, value in parse(events.stdout) if kind == "analog"]
    assert len(axes) > 10, events.stdout
    for unit, value in axes:
        raw = re.fullmatch(r"\d\.\d{4} raw (-?\d+)", value)
        assert raw, value  # an integer, never -1.545e+04
        assert (unit, int(raw.group(1))) in sent
    assert table.returncode == 0, table.stderr
    raws = re.findall(r"\(raw ([^)]*)\)", table.stdout)
    assert raws and all(re.fullmatch(r"-?\d+", r) for r in raws), table.stdout


def test_events_end_quietly_when_the_reader_goes_away():
    process = popen("monitor", WAVEFORM, "--format", "events", "--duration", "60")
    try:
        first = [process.stdout.readline() for _ in range(3)]
        assert all(LINE.match(line.rstrip("\n")) for line in first), first
        process.stdout.close()  # as `| head -3` does
        assert process.wait(timeout=30) == 0
        assert "Traceback" not in process.stderr.read()
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
        process.stderr.close()


def test_events_with_record_end_cleanly_on_ctrl_c(tmp_path):
    path = tmp_path / "run.ndjson"
    process = popen("monitor", WAVEFORM, "Waveform Sticks", "--format", "events", "--record", path)
    try:
        line = process.stdout.readline()  # running and writing
        assert LINE.match(line.rstrip("\n")), line
        process.send_signal(signal.SIGINT)
        out, err = process.communicate(timeout=30)
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate()
    assert process.returncode == 0, err
    assert "Traceback" not in err
    parse(out)
    records = list(read_recording(path).records)
    assert records[-1].reason == "interrupted"
    assert any(isinstance(r, SampleRecord) and r.device == "Waveform Sticks" for r in records)


def test_record_to_stdout_and_events_conflict():
    result = gadgetctl(
        "monitor", WAVEFORM, "--format", "events", "--record", "-", "--duration", "0"
    )
    assert result.returncode == 2 and "--format events" in result.stderr


# --------------------------------------------------------------------------- --pose


def test_ndjson_poses_quaternion_and_euler(tmp_path):
    quaternion = gadgetctl(
        "monitor",
        WAVEFORM,
        "Waveform Tracker",
        "--duration",
        "0.5",
        "--format",
        "ndjson",
        "--pose",
        "quaternion",
    )
    assert quaternion.returncode == 0, quaternion.stderr
    recs = [json.loads(line) for line in quaternion.stdout.splitlines()]
    assert recs[0]["info"]["pose"] == "quaternion"
    spins = 0
    for rec in recs:
        if rec["type"] != "sample" or rec["kind"] != "position":
            continue
        value = rec["value"]
        assert set(value) == {"position", "quaternion_wxyz"}
        w, x, y, z = value["quaternion_wxyz"]
        assert math.isclose(w * w + x * x + y * y + z * z, 1.0, rel_tol=1e-9) and w >= 0
        if rec["unit"] == 0:  # the circle does not turn
            assert (w, x, y, z) == pytest.approx((1, 0, 0, 0))
            assert math.hypot(value["position"][0], value["position"][2]) == pytest.approx(0.5)
        if rec["unit"] == 1:  # the spin turns about y only
            assert (x, z) == pytest.approx((0, 0), abs=1e-12)
            spins += 1
    assert spins > 10
    path = tmp_path / "euler.ndjson"
    path.write_text(
        gadgetctl(
            "monitor",
            WAVEFORM,
            "Waveform Tracker",
            "--duration",
            "0.5",
            "--format",
            "ndjson",
            "--pose",
            "euler",
            "--per-frame",
        ).stdout
    )
    frames = [r for r in map(json.loads, path.read_text().splitlines()) if r["type"] == "frame"]
    # frames before the tracker's first sample carry no position (a loaded machine has some)
    poses = [
        value
        for frame in frames
        for value in frame["devices"]["Waveform Tracker"]["values"].get("position", {}).values()
    ]
    assert poses
    assert all(set(value) == {"position", "euler_xyz_degrees"} for value in poses)
    default = gadgetctl(
        "monitor", WAVEFORM, "Waveform Tracker", "--duration", "0.3", "--format", "ndjson"
    )
    sample = next(
        r
        for r in map(json.loads, default.stdout.splitlines())
        if r["type"] == "sample" and r["kind"] == "position"
    )
    assert np.asarray(sample["value"]).shape == (4, 4)  # matrices stay the default


def test_table_poses():
    euler = gadgetctl(
        "monitor",
        WAVEFORM,
        "Waveform Tracker",
        "--duration",
        "0.3",
        "--format",
        "table",
        "--pose",
        "euler",
    )
    quaternion = gadgetctl(
        "monitor",
        WAVEFORM,
        "Waveform Tracker",
        "--duration",
        "0.3",
        "--format",
        "table",
        "--pose",
        "quaternion",
    )
    matrix = gadgetctl(
        "monitor",
        WAVEFORM,
        "Waveform Tracker",
        "--duration",
        "0.3",
        "--format",
        "table",
        "--pose",
        "matrix",
    )
    assert euler.returncode == quaternion.returncode == matrix.returncode == 0
    # x and z of the circle take either sign: where on it the last sample is depends on how
    # long the run took to start (x was -0.3 after a slow start under load)
    assert re.search(
        r"0: x [+-]0\.\d{4} y \+1\.6000 z [+-]0\.\d{4} m  rot \+0\.0 \+0\.0 \+0\.0 deg",
        euler.stdout,
    )
    assert re.search(
        r"0: x [+-]0\.\d{4} y \+1\.6000 z [+-]0\.\d{4} m  q \+1\.0000 \+0\.0000 \+0\.0000 \+0\.0000",
        quaternion.stdout,
    )
    assert re.search(r"0: m \+1\.0000 \+0\.0000 \+0\.0000 [+-]0\.\d{4} ", matrix.stdout)


# --------------------------------------------------------------------------- replay --summary


def write_circle(path: Path, pose: str = "matrix") -> None:
    """Two turns of a circle of radius 0.5 m at 1.6 m height, facing its way round."""
    records = []
    for i in range(400):
        angle = 2 * math.pi * i / 200
        m = np.eye(4)
        m[:3, :3] = rotation_from_euler_xyz_degrees(0.0, math.degrees(angle) % 360 - 180, 0.0)
        m[:3, 3] = (0.5 * math.cos(angle), 1.6, 0.5 * math.sin(angle))
        value = pose_values(m, pose)[0]
        records.append(SampleRecord("Tracker", "position", 0, 50.0 + i / 100, value, value))
    with Recorder(path, {"devices": ["Tracker"]}) as recorder:
        recorder.write_samples(records)


@pytest.mark.parametrize("pose", ["matrix", "quaternion"])
def test_a_circle_does_not_look_flat_in_the_summary(tmp_path, pose):
    path = tmp_path / "circle.ndjson"
    write_circle(path, pose)
    text = gadgetctl("replay", path, "--summary")
    assert text.returncode == 0, text.stderr
    axes = dict(re.findall(r"^      ([xyz]) (\S+ m  \S+)$", text.stdout, re.MULTILINE))
    assert set(axes) == {"x", "y", "z"}, text.stdout
    for axis in "xz":
        span, line = axes[axis].split(" m  ")
        assert span == "-0.500..+0.500"
        assert BARS[0] in line and BARS[-1] in line and len(set(line)) >= 6, line
    span, line = axes["y"].split(" m  ")
    assert span == "+1.600..+1.600" and set(line) == {MID}
    assert "rotation (Euler XYZ, degrees) x" in text.stdout and "turned up to 180.0" in text.stdout
    summary = json.loads(gadgetctl("replay", path, "--summary", "--format", "ndjson").stdout)
    unit = summary["devices"][0]["units"][0]
    assert unit["translation_min"] == pytest.approx([-0.5, 1.6, -0.5], abs=1e-3)
    assert unit["translation_max"] == pytest.approx([0.5, 1.6, 0.5], abs=1e-3)
    assert unit["rotation_min_degrees"][1] == pytest.approx(-90, abs=2)
    assert unit["rotation_max_degrees"][1] == pytest.approx(90, abs=2)
    assert set(unit["sparklines"]) == {"x", "y", "z"} and unit["turn_degrees"] == pytest.approx(
        180, abs=2
    )


# --------------------------------------------------------------------------- the documentation


def _text_block(after: str) -> list[str]:
    text = (REPO / "docs" / "monitor.md").read_text(encoding="utf-8")
    start = text.index("```text\n", text.index(after)) + len("```text\n")
    return text[start : text.index("```", start)].splitlines()


def test_the_documented_event_lines_have_the_line_shape():
    lines = _text_block("#### Changes only")
    kinds = {kind for _, _, _, kind, _ in parse("\n".join(lines))}
    assert kinds == {
        "digital",
        "analog",
        "position",
        "hat",
        "command",
        "string",
        "key",
        "status",
        "marker",
    }


def test_the_documented_circle_summary_is_what_replay_prints(tmp_path):
    path = tmp_path / "circle.ndjson"
    write_circle(path)
    result = gadgetctl("replay", path, "--summary")
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines()[2:] == _text_block("a tracker moving on a")
