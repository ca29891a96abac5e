"""The trackd driver against its emulator over real System V shared memory, and the segment
decoders against segments a test builds itself."""

from __future__ import annotations

import itertools
import json
import os
import re
import selectors
import signal
import struct
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest
from Trackd_drv.emulator import (
    CONTROLLER_KEY,
    SENSOR_KEY,
    TrackdEmulator,
    sensor_pose,
    valuator_value,
)
from Trackd_drv.standalone import (
    CONTROLLER_HEADER,
    MAX_UNITS,
    SENSOR,
    TRACKER_HEADER,
    BadSegment,
    SensorReading,
    TrackdDisconnected,
    TrackdSegment,
    decode_controller,
    decode_tracker,
    encode_controller,
    encode_tracker,
    read_controller,
    read_tracker,
    sensor_matrix,
    tracker_poses,
)

from gadgetctl.doctor import Status
from gadgetctl.input import DigitalState
from gadgetctl.input.testing import frames_until, wait_until
from gadgetctl.input.testing.commands import monitor_ndjson, run_gadgetctl
from gadgetctl.input.testing.configs import alias, configuration, corpus_copy, proxy
from gadgetctl.input.testing.fixtures import managers_fixture

pytestmark = pytest.mark.timeout(60)

REPO = Path(__file__).resolve().parents[3]
FEET = 0.3048
PRESSED = (DigitalState.ON, DigitalState.TOGGLE_ON)
SHM_TABLE = Path("/proc/sysvipc/shm")
_counter = itertools.count()


def segment_keys() -> set[int]:
    """The keys of every System V shared-memory segment (``ipcs -m``), private ones left out."""
    lines = SHM_TABLE.read_text().splitlines()[1:]
    return {int(line.split()[0]) for line in lines if line.split() and int(line.split()[0]) != 0}


# the keys this test may create: those fresh_key hands out and the emulator's defaults. Only
# they are checked, so that a segment another process makes meanwhile (a second test run on
# the machine) is not taken for ours.
_issued: set[int] = set()


@pytest.fixture(autouse=True)
def no_segment_left_behind() -> Iterator[None]:
    _issued.clear()
    _issued.update((SENSOR_KEY, CONTROLLER_KEY))
    before = segment_keys()
    yield
    left = (segment_keys() - before) & _issued
    assert not left, f"shared-memory segments left behind: {sorted(left)}"


@pytest.fixture
def fresh_key() -> Callable[[], int]:
    """A key no segment uses now (per process and call, so parallel runs do not meet)."""

    def make() -> int:
        taken = segment_keys()
        while True:
            key = 0x47000000 + ((os.getpid() & 0xFFFF) << 8) + (next(_counter) & 0xFF)
            if key not in taken:
                _issued.add(key)
                return key

    return make


# -- the layout, without shared memory ----------------------------------------------------------


def test_a_tracker_segment_decodes_to_its_sensors() -> None:
    poses = [sensor_pose(7, i) for i in range(16)]
    state = decode_tracker(encode_tracker(poses, (3, 250)))
    assert state.timestamp == (3, 250) and len(state.sensors) == 16
    for pose, sensor in zip(poses, state.sensors, strict=True):
        assert (
            sensor.x,
            sensor.y,
            sensor.z,
            sensor.azim,
            sensor.elev,
            sensor.roll,
        ) == pytest.approx(pose, abs=1e-4)


def test_a_controller_segment_decodes_to_buttons_and_valuators() -> None:
    state = decode_controller(encode_controller([0, 1, 0, 7], [-1.0, 0.25, 1.0]))
    assert state.buttons == (0, 1, 0, 7) and state.valuators == (-1.0, 0.25, 1.0)


@pytest.mark.parametrize("claimed", [3, 1000, MAX_UNITS + 1, 0xFFFFFFFF])
def test_a_header_claiming_more_sensors_than_the_segment_holds_is_a_bad_segment(
    claimed: int,
) -> None:
    with pytest.raises(BadSegment, match="sensors"):
        decode_tracker(encode_tracker([(0.0,) * 6] * 2, claimed=claimed))


def test_controller_counts_and_offsets_outside_the_segment_are_bad_segments() -> None:
    with pytest.raises(BadSegment, match="buttons"):
        decode_controller(encode_controller([1, 0], [0.5], claimed_buttons=4))
    with pytest.raises(BadSegment, match="shorter"):
        decode_controller(b"\0" * 8)
    data = bytearray(encode_controller([1], [0.5]))
    data[8:12] = (10_000).to_bytes(4, sys.byteorder)  # valuator offset far beyond the end
    with pytest.raises(BadSegment, match="valuators"):
        decode_controller(bytes(data))


def test_the_sensor_matrix_is_yaw_pitch_roll_about_y_x_z_with_the_stored_translation() -> None:
    m = sensor_matrix(SensorReading(1.0, 2.0, 3.0, 90.0, 0.0, 0.0, 1, 0))
    np.testing.assert_allclose(m[:3, 3], (1.0, 2.0, 3.0))
    np.testing.assert_allclose(m[:3, :3] @ (1, 0, 0), (0, 0, -1), atol=1e-12)  # azim: about +Y
    m = sensor_matrix(SensorReading(0, 0, 0, 0.0, 90.0, 0.0, 1, 0))
    np.testing.assert_allclose(m[:3, :3] @ (0, 1, 0), (0, 0, 1), atol=1e-12)  # elev: about +X
    m = sensor_matrix(SensorReading(0, 0, 0, 0.0, 0.0, 90.0, 1, 0))
    np.testing.assert_allclose(m[:3, :3] @ (1, 0, 0), (0, 1, 0), atol=1e-12)  # roll: about +Z
    m = sensor_matrix(SensorReading(0, 0, 0, 30.0, 20.0, 10.0, 1, 0))
    ry, rx, rz = (
        sensor_matrix(SensorReading(0, 0, 0, *a, 1, 0))[:3, :3]
        for a in ((30.0, 0, 0), (0, 20.0, 0), (0, 0, 10.0))
    )
    np.testing.assert_allclose(m[:3, :3], ry @ rx @ rz, atol=1e-12)


# -- polling reads the header and the blocks it names only (issue 24 item 9) --------------------

HUGE = 256 << 20  # a 256 MB segment: copied whole on every poll, 815 MB and 9 frames/s


class SparseSegment:
    """A segment of ``size`` bytes, zero but for ``parts`` ({offset: bytes}), read through
    ``read(offset, count)``; remembers every read."""

    def __init__(self, size: int, parts: dict[int, bytes]) -> None:
        self.size, self.parts, self.reads = size, parts, []

    def read(self, offset: int, count: int) -> bytes:
        assert offset >= 0 and offset + count <= self.size
        self.reads.append((offset, count))
        out = bytearray(count)
        for start, part in self.parts.items():
            low, high = max(start, offset), min(start + len(part), offset + count)
            if low < high:
                out[low - offset : high - offset] = part[low - start : high - start]
        return bytes(out)


@pytest.mark.parametrize("stride", [SENSOR.size, 1 << 20])
def test_a_tracker_poll_reads_the_header_and_the_named_sensors_only(stride) -> None:
    poses = [sensor_pose(5, i) for i in range(3)]
    offset = 100 << 20
    header = TRACKER_HEADER.pack(1, 3, offset, stride, 7, 8, 0)
    parts = {0: header} | {
        offset + i * stride: SENSOR.pack(*pose, 7, 8, 1, i) for i, pose in enumerate(poses)
    }
    segment = SparseSegment(HUGE, parts)
    data = read_tracker(segment.read, segment.size)
    assert sum(count for _, count in segment.reads) == TRACKER_HEADER.size + 3 * SENSOR.size
    assert data == encode_tracker(poses, (7, 8))  # the compact layout decodes alike
    np.testing.assert_allclose(tracker_poses(data), np.array(poses, dtype=np.float32))


def test_a_controller_poll_reads_the_header_and_the_named_blocks_only() -> None:
    b_off, v_off = 50 << 20, 200 << 20
    header = CONTROLLER_HEADER.pack(1, b_off, v_off, 2, 3, 4, 5, 0)
    parts = {0: header, b_off: struct.pack("=2i", 1, 0), v_off: struct.pack("=3f", 0.5, -1, 1)}
    segment = SparseSegment(HUGE, parts)
    state = decode_controller(read_controller(segment.read, segment.size))
    assert state.buttons == (1, 0) and state.valuators == (0.5, -1.0, 1.0)
    assert state.timestamp == (4, 5)
    assert sum(count for _, count in segment.reads) == CONTROLLER_HEADER.size + 20


@pytest.mark.parametrize(
    "header",
    [
        TRACKER_HEADER.pack(1, MAX_UNITS + 1, 28, 40, 0, 0, 0),  # too many sensors
        TRACKER_HEADER.pack(1, 2, HUGE - 40, 40, 0, 0, 0),  # the second one beyond the end
        TRACKER_HEADER.pack(1, 2, 28, 8, 0, 0, 0),  # sensors overlapping
    ],
    ids=["too-many", "beyond-the-end", "overlapping"],
)
def test_a_bad_tracker_header_reads_nothing_more_and_decodes_as_bad(header) -> None:
    segment = SparseSegment(HUGE, {0: header})
    data = read_tracker(segment.read, segment.size)
    assert segment.reads == [(0, TRACKER_HEADER.size)] and data == header
    with pytest.raises(BadSegment):
        tracker_poses(data)


def test_a_large_real_segment_is_read_in_a_few_bytes(fresh_key) -> None:
    import sysv_ipc

    key = fresh_key()
    memory = sysv_ipc.SharedMemory(key, sysv_ipc.IPC_CREX, mode=0o600, size=64 << 20)
    try:
        poses = [sensor_pose(1, i) for i in range(2)]
        memory.write(encode_tracker(poses, (1, 2)))
        segment = TrackdSegment(key)
        segment.open()
        try:
            data = segment.read_tracker()
            assert data == encode_tracker(poses, (1, 2))
        finally:
            segment.close()
    finally:
        memory.detach()
        memory.remove()


# -- the reader over shared memory --------------------------------------------------------------


def test_the_reader_attaches_read_only_and_notices_a_removed_segment(fresh_key) -> None:
    sensor_key, controller_key = fresh_key(), fresh_key()
    emulator = TrackdEmulator(sensor_key, controller_key, scenario="idle", sensors=3).start()
    segment = TrackdSegment(sensor_key)
    try:
        segment.open()
        state = decode_tracker(segment.read())
        assert len(state.sensors) == 3
        assert state.sensors[2].x == pytest.approx(sensor_pose(0, 2)[0])
        emulator.stop()
        with pytest.raises(TrackdDisconnected, match="removed"):
            segment.read()
    finally:
        segment.close()
        emulator.stop()
    with pytest.raises(TrackdDisconnected, match="no shared-memory segment"):
        TrackdSegment(sensor_key).open()


# -- the input manager ------------------------------------------------------------------------


def sensor(name: str, key: int, feet: bool = True) -> str:
    filters = (
        '<position_filters><position_transform_filter name="F" version="1">'
        f"<device_units>{FEET}</device_units></position_transform_filter></position_filters>"
        if feet
        else ""
    )
    return (
        f'<trackd_sensor name="{name}" version="1"><shared_memory_key>{key}</shared_memory_key>'
        f"{filters}</trackd_sensor>\n"
    )


def controller(name: str, key: int) -> str:
    return (
        f'<trackd_controller name="{name}" version="1"><shared_memory_key>{key}'
        "</shared_memory_key><min>-1.0</min><max>1.0</max></trackd_controller>\n"
    )


build = managers_fixture("Trackd_drv", name="build", ready=True)


@pytest.fixture
def keys(fresh_key) -> tuple[int, int]:
    return fresh_key(), fresh_key()


def test_sensors_buttons_and_valuators_arrive_through_proxies_and_aliases(build, keys) -> None:
    skey, ckey = keys
    body = sensor("Sensors", skey) + controller("Controller", ckey)
    for i in range(3):
        body += proxy("position", f"Sensor {i}", "Sensors", i) + alias(
            f"VJSensor{i}", f"Sensor {i}"
        )
    body += proxy("digital", "Button 0", "Controller", 0) + alias("VJButton0", "Button 0")
    body += proxy("digital", "Button 1", "Controller", 1)
    body += proxy("analog", "Valuator 1", "Controller", 1) + alias("VJAnalog1", "Valuator 1")
    with TrackdEmulator(skey, ckey, scenario="idle", sensors=3, buttons=4, valuators=2):
        manager = build(body)
        frames_until(
            manager,
            lambda: (
                all(manager.proxy(f"VJSensor{i}").timestamp is not None for i in range(3))
                and manager.proxy("VJAnalog1").timestamp is not None
            ),
        )
        for i in range(3):
            x, y, z, azim, elev, roll = sensor_pose(0, i)
            expected = sensor_matrix(
                SensorReading(x * FEET, y * FEET, z * FEET, azim, elev, roll, 1, i)
            )
            np.testing.assert_allclose(manager.proxy(f"VJSensor{i}").matrix, expected, atol=1e-5)
        assert manager.proxy("VJButton0").data in PRESSED  # the emulator holds button 0
        assert manager.proxy("Button 1").data not in PRESSED
        assert manager.proxy("VJAnalog1").data == pytest.approx(
            (valuator_value(0, 1) + 1) / 2, abs=1e-6
        )
        sensors, ctl = manager.device("Sensors"), manager.device("Controller")
        assert sensors.counters == {"records": 1, "bad_records": 0}  # idle: read once...
        assert ctl.counters == {"records": 1, "bad_records": 0}
        assert wait_until(lambda: ctl.polls > 10)  # ...though polled again and again


def test_sixteen_sensors_are_sixteen_position_units(build, keys) -> None:
    skey, ckey = keys
    body = sensor("Sensors", skey, feet=False) + proxy("position", "Last", "Sensors", 15)
    with TrackdEmulator(skey, ckey, scenario="motion", rate=200.0, sensors=16):
        manager = build(body)
        frames_until(
            manager,
            lambda: (
                manager.device("Sensors").counters["records"] > 5
                and manager.proxy("Last").timestamp is not None
            ),
        )
        x = manager.proxy("Last").matrix[0, 3]
    assert 14.0 <= x <= 16.0  # sensor 15 circles about x = 15


def test_every_button_toggles_in_the_buttons_scenario(build, keys) -> None:
    skey, ckey = keys
    body = controller("Controller", ckey)
    for b in range(4):
        body += proxy("digital", f"Button {b}", "Controller", b) + alias(
            f"VJButton{b}", f"Button {b}"
        )
    with TrackdEmulator(skey, ckey, scenario="buttons", rate=200.0, buttons=4):
        manager = build(body)
        seen: dict[int, set[DigitalState]] = {b: set() for b in range(4)}

        def all_toggled() -> bool:
            for b in range(4):
                seen[b].add(manager.proxy(f"VJButton{b}").data)
            return all(
                {DigitalState.TOGGLE_ON, DigitalState.TOGGLE_OFF} <= s for s in seen.values()
            )

        frames_until(manager, all_toggled, timeout=10.0)


def test_garbage_headers_are_counted_and_never_fault(build, keys) -> None:
    skey, ckey = keys
    body = sensor("Sensors", skey) + controller("Controller", ckey)
    body += proxy("position", "Head", "Sensors", 0) + proxy("digital", "Button", "Controller", 0)
    with TrackdEmulator(skey, ckey, scenario="garbage", rate=200.0) as emulator:
        manager = build(body)
        sensors, ctl = manager.device("Sensors"), manager.device("Controller")
        frames_until(
            manager,
            lambda: (
                sensors.bad_records >= 10
                and ctl.bad_records >= 10
                and sensors.records >= 10
                and ctl.records >= 10
            ),
            timeout=10.0,
        )
        assert emulator.bad_writes >= 10
        assert manager.status("Sensors").state == "running" and sensors.faults == 0
        assert manager.status("Controller").state == "running" and ctl.faults == 0
        assert manager.proxy("Head").timestamp is not None


def test_a_removed_segment_faults_and_data_returns_within_two_seconds(build, keys) -> None:
    skey, ckey = keys
    body = sensor("Sensors", skey) + proxy("position", "Head", "Sensors", 0)
    emulator = TrackdEmulator(skey, ckey, scenario="motion", rate=200.0).start()
    try:
        manager = build(body)
        device = manager.device("Sensors")
        frames_until(manager, lambda: device.records > 5)
        emulator.stop()
        frames_until(
            manager, lambda: manager.status("Sensors").state in ("faulted", "reconnecting")
        )
        assert device.faults >= 1
        with TrackdEmulator(skey, ckey, scenario="motion", rate=200.0):
            before = device.records
            resumed = frames_until(manager, lambda: device.records > before + 5, timeout=6.0)
            assert resumed < 2.0
            frames_until(manager, lambda: manager.status("Sensors").state == "running")
    finally:
        emulator.stop()


def test_the_disconnect_scenario_is_survived_again_and_again(build, keys) -> None:
    skey, ckey = keys
    body = controller("Controller", ckey) + proxy("analog", "Valuator", "Controller", 0)
    with TrackdEmulator(
        skey, ckey, scenario="disconnect", rate=200.0, disconnect_after=20, down_time=0.2
    ) as emulator:
        manager = build(body)
        device = manager.device("Controller")
        frames_until(manager, lambda: emulator.removals >= 2 and device.restarts >= 2, timeout=15.0)
        before = device.records
        frames_until(manager, lambda: device.records > before, timeout=5.0)
    assert device.faults >= 2


# -- the corpus configuration under monitor -----------------------------------------------------


def corpus_with_keys(tmp_path: Path, skey: int, ckey: int) -> Path:
    return corpus_copy(
        "sim.trackd.jconf",
        tmp_path,
        (
            "<shared_memory_key>4148</shared_memory_key>",
            f"<shared_memory_key>{skey}</shared_memory_key>",
        ),
        (
            "<shared_memory_key>4147</shared_memory_key>",
            f"<shared_memory_key>{ckey}</shared_memory_key>",
        ),
    )


def test_the_corpus_sim_trackd_delivers_through_its_proxies_and_aliases(
    build, keys, tmp_path
) -> None:
    skey, ckey = keys
    with TrackdEmulator(skey, ckey, scenario="idle", sensors=2, buttons=3):
        manager = build(corpus_with_keys(tmp_path, skey, ckey))
        frames_until(
            manager,
            lambda: (
                manager.proxy("VJHead").timestamp is not None
                and manager.proxy("VJButton0").timestamp is not None
            ),
        )
        head = manager.proxy("VJHead").matrix
        x, y, z = sensor_pose(0, 0)[:3]
        np.testing.assert_allclose(head[:3, 3], (x * FEET, y * FEET, z * FEET), atol=1e-5)
        assert manager.proxy("VJButton0").data in PRESSED
        assert manager.proxy("VJButton1").data not in PRESSED
        assert manager.status("Wand Proxy").state == "active"


def test_monitor_ndjson_shows_the_corpus_samples(tmp_path: Path, keys) -> None:
    skey, ckey = keys
    path = corpus_with_keys(tmp_path, skey, ckey)
    with TrackdEmulator(skey, ckey, scenario="motion", rate=100.0, sensors=2, buttons=3):
        result, records = monitor_ndjson(path, duration=1, timeout=60)
    assert result.returncode == 0, result.stderr[-2000:]
    seen = {(r["device"], r["kind"]) for r in records if r.get("type") == "sample"}
    assert {("TrackdSensorDev", "position"), ("TrackdControllerDev", "digital")} <= seen
    active = {
        r["name"] for r in records if r.get("type") == "status" and r.get("state") == "active"
    }
    assert {"VJHead", "VJButton0", "Head Proxy", "Button2Proxy"} <= active


# -- the emulator's command line ----------------------------------------------------------------


@pytest.mark.parametrize("how", [signal.SIGTERM, signal.SIGHUP, signal.SIGINT])
def test_the_emulator_removes_its_segments_when_stopped(keys, how) -> None:
    skey, ckey = keys
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "gadgetctl",
            "emulate",
            "Trackd_drv",
            "--sensor-key",
            str(skey),
            "--controller-key",
            str(ckey),
        ],
        cwd=REPO,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    try:
        out = b""
        with selectors.DefaultSelector() as selector:
            selector.register(proc.stdout, selectors.EVENT_READ)
            deadline = time.monotonic() + 30
            while b"Press Ctrl-C" not in out:
                assert time.monotonic() < deadline and selector.select(deadline - time.monotonic())
                chunk = os.read(proc.stdout.fileno(), 4096)
                assert chunk, out
                out += chunk
        assert {skey, ckey} <= segment_keys()
        assert re.search(rf"<shared_memory_key>{skey}</shared_memory_key>", out.decode())
        proc.send_signal(how)
        _, err = proc.communicate(timeout=20)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 0 and b"Traceback" not in err, err
    assert not {skey, ckey} & segment_keys()


def test_a_left_over_segment_of_a_killed_emulator_is_taken_over(keys) -> None:
    skey, ckey = keys
    first = TrackdEmulator(skey, ckey, scenario="idle")
    first.start()
    left_over, first._segments = first._segments, []  # as if killed: nothing removed
    second = TrackdEmulator(skey, ckey, scenario="idle", sensors=5).start()
    try:
        segment = TrackdSegment(skey)
        segment.open()
        assert len(decode_tracker(segment.read()).sensors) == 5
        segment.close()
    finally:
        second.stop()
        first.stop()  # its writing thread outlived the test, attached to the old segments
        for memory in left_over:
            memory.detach()
    assert wait_until(lambda: not {skey, ckey} & segment_keys(), timeout=2.0)


# -- doctor and a missing binding ------------------------------------------------------------------


def doctor(path: Path) -> tuple[int, dict]:
    result = run_gadgetctl("doctor", str(path), "--format", "json", timeout=60)
    return result.returncode, json.loads(result.stdout)


def test_doctor_finds_the_segments_present_and_readable_or_missing(tmp_path: Path, keys) -> None:
    skey, ckey = keys
    path = tmp_path / "trackd.jconf"
    path.write_text(
        configuration("Trackd_drv", sensor("Sensors", skey) + controller("Controller", ckey))
    )
    code, report = doctor(path)
    assert code == 1
    checks = {d["name"]: d["checks"] for d in report["devices"]}
    [missing] = checks["Sensors"]
    assert (
        missing["kind"] == "shm" and missing["status"] == "problem" and missing["code"] == "DRV100"
    )
    assert missing["property"] == "shared_memory_key" and str(skey) in missing["target"]
    assert "gadgetctl emulate Trackd_drv" in missing["hint"]
    with TrackdEmulator(skey, ckey, scenario="idle"):
        code, report = doctor(path)
    checks = {d["name"]: d["checks"] for d in report["devices"]}
    assert [c["status"] for c in checks["Sensors"] + checks["Controller"]] == ["ok", "ok"], checks
    assert code == 0


def test_doctor_judges_a_segments_mode_for_another_user(tmp_path: Path) -> None:
    from gadgetctl.doctor.permissions import Identity
    from gadgetctl.doctor.shm import check_shm

    table = tmp_path / "shm"
    table.write_text(
        "       key      shmid perms       size  cpid  lpid nattch   uid   gid\n"
        "      4148         7   600        308    10    10      1     0     0\n"
        "      4147         8   644        100    10    10      1     0     0\n"
    )
    someone = Identity(1000, frozenset({1000}))
    denied = check_shm(4148, identity=someone, table=table)
    assert (
        denied.status is Status.PROBLEM and denied.code == "DRV101" and "mode 600" in denied.detail
    )
    assert check_shm(4147, identity=someone, table=table).status is Status.OK
    assert check_shm(4148, identity=Identity(0, frozenset({0})), table=table).status is Status.OK
    assert check_shm(0, table=table).code == "DRV106"


def test_without_sysv_ipc_the_plugin_fails_to_load_in_one_line(tmp_path: Path) -> None:
    blocker = tmp_path / "block"
    blocker.mkdir()
    (blocker / "sysv_ipc.py").write_text("raise ImportError('No module named sysv_ipc')\n")
    env = {**os.environ, "PYTHONPATH": str(blocker), "NO_COLOR": "1"}

    def gadgetctl(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run(
            [sys.executable, "-m", "gadgetctl", *args],
            capture_output=True,
            text=True,
            timeout=60,
            cwd=REPO,
            env=env,
        )

    listed = gadgetctl("drivers", "list")
    assert listed.returncode == 0 and "Trackd_drv" in listed.stdout  # listed without importing
    loaded = gadgetctl("drivers", "load", "Trackd_drv")
    assert loaded.returncode != 0 and "Traceback" not in loaded.stdout + loaded.stderr
    [line] = [ln for ln in loaded.stdout.splitlines() if "DRV003" in ln]
    assert "Trackd_drv needs the sysv_ipc package (pip install sysv_ipc)" in line


def test_the_polling_path_gives_the_same_matrices_as_the_readable_one() -> None:
    from Trackd_drv.standalone import pose_matrices, tracker_poses

    data = encode_tracker([sensor_pose(t, i) for i, t in enumerate(range(0, 160, 10))])
    expected = np.array([sensor_matrix(s) for s in decode_tracker(data).sensors])
    np.testing.assert_allclose(pose_matrices(tracker_poses(data)), expected, atol=1e-12)
    with pytest.raises(BadSegment, match="sensors"):
        tracker_poses(encode_tracker([(0.0,) * 6], claimed=2))
