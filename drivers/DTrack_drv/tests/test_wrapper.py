"""The DTrack device in the input manager, against the loopback emulator: units, scaling and
rotation order through proxies and aliases, Flystick buttons beyond eight, garbage,
disconnection and reconnection, remote control, the corpus example."""

from __future__ import annotations

import socket
from pathlib import Path

import numpy as np
import pytest
from DTrack_drv.emulator import DTrackEmulator, euler_rotation, object_angles, object_location
from DTrack_drv.standalone import (
    CMD_CAMERAS_AND_TRACKING_ON,
    CMD_CAMERAS_OFF,
    CMD_START_SENDING,
    CMD_STOP_SENDING,
)

from gadgetctl.input import DeviceKind, DigitalState, InputManager, ManagerOptions
from gadgetctl.input.testing import frames_until
from gadgetctl.input.testing.commands import monitor_ndjson
from gadgetctl.input.testing.configs import alias, corpus_copy, free_udp_port, pending_in, proxy
from gadgetctl.input.testing.fixtures import managers_fixture

pytestmark = pytest.mark.timeout(30)

PRESSED = (DigitalState.ON, DigitalState.TOGGLE_ON)
RATE = 250.0


build = managers_fixture("DTrack_drv", name="build", ready=True)


def tracker(name: str, port: int, *extra: str) -> str:
    return f'<dtrack name="{name}" version="1"><receive_port>{port}</receive_port>{"".join(extra)}</dtrack>\n'


def expected_pose(index: int) -> np.ndarray:
    """The emulator's resting pose of object ``index`` (bodies 0.., Flysticks 100..), metres."""
    matrix = np.eye(4)
    matrix[:3, :3] = euler_rotation(*object_angles(0, index, False))
    matrix[:3, 3] = np.array(object_location(0, index, False)) / 1000.0
    return matrix


# -- units through proxies and aliases --------------------------------------------------------


def test_position_units_are_flysticks_then_bodies_in_metres(tmp_path: Path, build) -> None:
    port = free_udp_port()
    body = tracker("DT", port)
    names = ["Flystick", "Body 0", "Body 1", "Body 2"]
    for unit, name in enumerate(names):
        body += proxy("position", name, "DT", unit) + alias(f"VJ{name.replace(' ', '')}", name)
    manager = build(body)
    with DTrackEmulator(port, scenario="idle", rate=RATE, bodies=3, flysticks=1):
        frames_until(manager, lambda: manager.device("DT").store.total(DeviceKind.POSITION) > 3)
    for name, index in zip(names, (100, 0, 1, 2), strict=True):
        matrix = manager.proxy(f"VJ{name.replace(' ', '')}").matrix
        np.testing.assert_allclose(matrix, expected_pose(index), atol=2e-6)
    assert manager.proxy("Body 2").translation[2] == pytest.approx(1.02)  # 1020 mm


def test_rotation_is_read_column_by_column(tmp_path: Path, build) -> None:
    port = free_udp_port()
    manager = build(tracker("DT", port) + proxy("position", "Body", "DT", 0))
    # a quarter turn about z, sent column by column: R00 R10 R20 R01 R11 R21 R02 R12 R22
    datagram = b"fr 1\r\n6d 1 [0 1.0][100 -250 1500 0 0 90][0 1 0 -1 0 0 0 0 1]\r\n"
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sender:
        sender.sendto(datagram, ("127.0.0.1", port))
        frames_until(manager, lambda: manager.proxy("Body").timestamp is not None)
    matrix = manager.proxy("Body").matrix
    np.testing.assert_allclose(matrix[:3, :3] @ [1, 0, 0], [0, 1, 0])  # x turns onto y
    np.testing.assert_allclose(matrix[:3, 3], [0.1, -0.25, 1.5])
    np.testing.assert_allclose(matrix[3], [0, 0, 0, 1])


def test_flystick_buttons_beyond_eight_and_the_joystick(tmp_path: Path, build) -> None:
    port = free_udp_port()
    body = tracker("DT", port)
    for b in range(10):
        body += proxy("digital", f"Button {b}", "DT", b) + alias(f"VJButton{b}", f"Button {b}")
    body += proxy("analog", "Joystick X", "DT", 0) + proxy("analog", "Joystick Y", "DT", 1)
    manager = build(body)
    with DTrackEmulator(port, scenario="buttons", rate=RATE, flystick_buttons=10):
        toggled: set[int] = set()

        def all_pressed() -> bool:
            toggled.update(b for b in range(10) if manager.proxy(f"VJButton{b}").data in PRESSED)
            return len(toggled) == 10

        frames_until(manager, all_pressed)
        assert manager.proxy("Joystick X").data == 0.5  # the joystick rests at 0 in [-1, 1]
    with DTrackEmulator(port, scenario="motion", rate=RATE, first_frame=50) as emu:
        frames_until(manager, lambda: manager.proxy("Joystick X").raw not in (None, 0.0))
        x, y = manager.proxy("Joystick X"), manager.proxy("Joystick Y")
        assert x.data == pytest.approx((x.raw + 1) / 2) and y.data == pytest.approx((y.raw + 1) / 2)
        assert -1.0 <= x.raw <= 1.0 and emu.error is None
    assert len(manager.device("DT").store.latest(DeviceKind.DIGITAL).values) == 10


def test_garbage_is_counted_and_every_valid_frame_is_a_sample(tmp_path: Path, build) -> None:
    port = free_udp_port()
    manager = build(tracker("DT", port) + proxy("position", "Flystick", "DT", 0))
    device = manager.device("DT")
    with DTrackEmulator(port, scenario="garbage", rate=RATE, max_frames=60, seed=3) as emu:
        # the counters move when datagrams are read, the store when their samples are added
        frames_until(
            manager,
            lambda: (
                emu.finished.is_set()
                and device.counters["datagrams"] >= 120
                and device.store.total(DeviceKind.POSITION) >= 60
            ),
        )
        assert manager.status("DT").state == "running" and device.faults == 0
    # exact counts once sampling stopped: the last datagram (junk) is counted received before
    # it is counted bad, and this thread may read between the two
    manager.shutdown()
    counters = device.counters
    assert counters["bad_datagrams"] == emu.garbage_sent == 60
    assert counters["bad_lines"] == emu.bad_lines_sent > 0
    assert counters["missed_frames"] == 0
    assert device.store.total(DeviceKind.POSITION) == len(emu.frames_sent) == 60


# -- disconnection --------------------------------------------------------------------------------


def test_a_silent_tracker_faults_and_resumes_within_two_seconds(tmp_path: Path, build) -> None:
    port, other_port = free_udp_port(), free_udp_port()
    body = tracker("DT", port) + tracker("Other", other_port) + proxy("position", "Body", "DT", 1)
    manager = build(body, peer_timeout=0.3)
    device, other = manager.device("DT"), manager.device("Other")
    with DTrackEmulator(other_port, scenario="motion", rate=RATE):
        with DTrackEmulator(port, scenario="motion", rate=RATE):
            frames_until(manager, lambda: device.store.total() > 10)
        frames_until(manager, lambda: manager.status("DT").state == "faulted")
        status = manager.status("DT")
        assert "DTrack" in status.reason and status.code == "DRV042"
        before, failed_at = other.store.total(), device.error_at
        # silent for a while: a restart attempt finds nothing (its failure renews the fault's
        # time); waited for, not slept
        frames_until(manager, lambda: device.error_at != failed_at, timeout=10.0)
        assert manager.status("DT").state in ("faulted", "reconnecting")
        # the other tracker went on meanwhile (it may have been starved of the CPU for a
        # moment on a loaded machine, so this too is waited for, with a hang guard)
        frames_until(manager, lambda: other.store.total() > before, timeout=10.0)
        assert other.faults == 0

        with DTrackEmulator(port, scenario="motion", rate=RATE, first_frame=1000):
            count = device.store.total()
            resumed = frames_until(manager, lambda: device.store.total() > count, timeout=4.0)
            assert resumed < 2.0
            frames_until(manager, lambda: manager.status("DT").state == "running")
            assert device.restarts >= 1
        assert other.faults == 0 and manager.status("Other").state == "running"


def test_remote_control_starts_and_stops_the_tracker(tmp_path: Path, build, monkeypatch) -> None:
    port = free_udp_port()
    with DTrackEmulator(port, rate=RATE, command_port=0, wait_for_start=True) as emu:
        host, command_port = emu.command_address.rsplit(":", 1)
        body = tracker(
            "DT",
            port,
            f"<server_name>{host}</server_name><command_port>{command_port}</command_port>",
        )
        path = build.write(body + proxy("position", "F", "DT", 0))
        options = ManagerOptions(retry_interval=None, entry_points=False)
        manager, configuration = InputManager.from_files([path], options=options)
        try:  # load the driver first, to shorten its start delay
            manager.configure([e for e in configuration.elements if e.type == "input_manager"])
            device_class = manager.registry.get("dtrack").device_class
            monkeypatch.setattr(device_class, "start_delay", 0.01)
            manager.configure([e for e in configuration.elements if e.type != "input_manager"])
            assert not manager.pending()
            frames_until(manager, lambda: manager.proxy("F").timestamp is not None)
            assert emu.commands == [CMD_CAMERAS_AND_TRACKING_ON, CMD_START_SENDING]
        finally:
            manager.shutdown()
        assert emu.wait_for_command(CMD_CAMERAS_OFF)
        assert emu.commands[2:] == [CMD_STOP_SENDING, CMD_CAMERAS_OFF]


def test_unusable_elements_stay_pending_with_a_reason(build) -> None:
    taken = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    taken.bind(("", 0))
    try:
        path = build.write(tracker("Huge", 70000) + tracker("Taken", taken.getsockname()[1]))
        reasons = pending_in(path)
    finally:
        taken.close()
    assert reasons["Huge"] == "receive_port 70000 is not a UDP port (0 to 65535)"
    assert "failed to start" in reasons["Taken"] and "in use" in reasons["Taken"]


# -- the corpus example and ours -------------------------------------------------------------------


@pytest.fixture
def corpus_config(tmp_path: Path) -> tuple[Path, int]:
    """VR Juggler's example.dtrack.jconf with only its receive_port changed (it keeps the
    configuration namespace 3.1, which does not exist; VR Juggler loads it all the same)."""
    port = free_udp_port()
    path = corpus_copy(
        "example.dtrack.jconf",
        tmp_path,
        ("<receive_port>5000</receive_port>", f"<receive_port>{port}</receive_port>"),
    )
    assert "xsd/3.1/configuration" in path.read_text()
    return path, port


def test_the_corpus_example_delivers_through_its_proxies(
    build, corpus_config: tuple[Path, int]
) -> None:
    path, port = corpus_config
    manager = build(path)
    with DTrackEmulator(
        port, scenario="buttons", rate=RATE, bodies=1, flysticks=1, flystick_buttons=8
    ):
        pressed: set[str] = set()

        def both_buttons() -> bool:
            pressed.update(
                n
                for n in ("Flystick1Button1", "Flystick1Button2")
                if manager.proxy(n).data in PRESSED
            )
            return len(pressed) == 2

        frames_until(manager, both_buttons)
        statuses = {s.name: s.state for s in manager.statuses()}
    np.testing.assert_allclose(manager.proxy("Flystick1").matrix, expected_pose(100), atol=2e-6)
    np.testing.assert_allclose(manager.proxy("StandardBody1").matrix, expected_pose(0), atol=2e-6)
    assert manager.proxy("Flystick1HATHorizontal").data == 0.5
    assert manager.proxy("Flystick1HATVertical").data == 0.5
    assert statuses["DTrack Device"] == "running"
    assert all(
        state == "active"
        for name, state in statuses.items()
        if name.startswith(("Flystick1", "Standard"))
    )


def test_monitor_shows_samples_of_the_corpus_example(corpus_config: tuple[Path, int]) -> None:
    path, port = corpus_config
    with DTrackEmulator(port, scenario="motion", rate=100.0, bodies=1):
        result, records = monitor_ndjson(path, duration=1, timeout=60)
    assert result.returncode == 0, result.stderr[-2000:]
    kinds = {
        r["kind"]
        for r in records
        if r.get("type") == "sample" and r.get("device") == "DTrack Device"
    }
    assert {"position", "digital", "analog"} <= kinds, records[:5]
