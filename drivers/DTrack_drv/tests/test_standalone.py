"""The DTrack receiver against its loopback emulator, and against hand-written datagrams."""

from __future__ import annotations

import socket
import time
from collections.abc import Callable, Iterator

import numpy as np
import pytest
from DTrack_drv.emulator import (
    DTrackEmulator,
    euler_rotation,
    flystick_buttons,
    flystick_joystick,
    main,
    marker_location,
    object_angles,
    object_location,
)
from DTrack_drv.standalone import (
    CMD_CAMERAS_AND_TRACKING_ON,
    CMD_CAMERAS_OFF,
    CMD_START_SENDING,
    CMD_STOP_SENDING,
    DTrackDisconnected,
    DTrackFrame,
    DTrackStandalone,
    DTrackUnits,
    _decimals,
    parse_frame,
    parse_frames,
)

pytestmark = pytest.mark.timeout(10)

RATE = 500.0


def receiver(**kwargs: object) -> DTrackStandalone:
    options: dict[str, object] = {
        "bind_address": "127.0.0.1",
        "receive_timeout": 0.02,
        "peer_timeout": None,
    }
    options.update(kwargs)
    return DTrackStandalone(0, **options)  # type: ignore[arg-type]


@pytest.fixture
def rx() -> Iterator[DTrackStandalone]:
    with receiver() as r:
        yield r


def collect(
    rx: DTrackStandalone, done: Callable[[list[DTrackFrame]], bool], timeout: float = 3.0
) -> list[DTrackFrame]:
    frames: list[DTrackFrame] = []
    end = time.monotonic() + timeout
    while not done(frames):
        assert time.monotonic() < end, f"timed out with {len(frames)} frames"
        frames.extend(rx.sample_all())
    return frames


def drain(rx: DTrackStandalone) -> list[DTrackFrame]:
    """Everything still queued once the sender has stopped."""
    frames: list[DTrackFrame] = []
    while batch := rx.sample_all():
        frames.extend(batch)
    return frames


def run(
    rx: DTrackStandalone, frames: int, **options: object
) -> tuple[list[DTrackFrame], DTrackEmulator]:
    """Let an emulator send ``frames`` frames, then receive them all.

    A bounded run keeps the socket buffer from overflowing on a loaded machine, so every frame
    sent can be expected.
    """
    options.setdefault("rate", RATE)
    with DTrackEmulator(rx.port, max_frames=frames, **options) as emu:  # type: ignore[arg-type]
        received = collect(rx, lambda f: len(f) >= frames or emu.finished.is_set())
        assert emu.finished.wait(3.0)
    received += drain(rx)
    assert emu.error is None
    assert [f.frame for f in received] == emu.frames_sent
    return received, emu


def send(rx: DTrackStandalone, text: str | bytes) -> DTrackFrame:
    """Send one datagram from a plain socket (the test plays the tracker) and receive it."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
        tx.sendto(text.encode("ascii") if isinstance(text, str) else text, ("127.0.0.1", rx.port))
    frames = collect(rx, lambda f: len(f) >= 1, timeout=1.0)
    assert len(frames) == 1
    return frames[0]


# -- hand-written datagrams: the wire format itself ------------------------------------------


def test_rotation_is_read_column_by_column_and_mm_become_m(rx: DTrackStandalone) -> None:
    # R = rotation of +90 degrees about z: x -> y. Sent column by column: R00 R10 R20 R01 ...
    frame = send(rx, "fr 17\r\n6d 1 [0 0.9][100 200 300 0 0 90][0 1 0 -1 0 0 0 0 1]\r\n")
    body = frame.bodies[0]
    expected = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    assert body.matrix.dtype == np.float64 and body.matrix.shape == (4, 4)
    np.testing.assert_allclose(body.matrix[:3, :3], expected)
    np.testing.assert_allclose(body.matrix[:3, 3], [0.1, 0.2, 0.3])
    np.testing.assert_allclose(body.matrix[3], [0, 0, 0, 1])
    np.testing.assert_allclose(body.matrix[:3, :3] @ [1, 0, 0], [0, 1, 0])  # x axis turned onto y
    assert (
        frame.frame == 17
        and body.quality == pytest.approx(0.9)
        and body.location_mm == (100, 200, 300)
    )


def test_reference_example_datagram(rx: DTrackStandalone) -> None:
    b = "0.36 0.48 -0.8 -0.8 0.6 0 0.48 0.64 0.6"  # an orthonormal matrix, column by column
    frame = send(
        rx,
        f"fr 17\r\n6df2 1 1 [0 1.000 8 2][100 200 300][{b}][5 0.25 -1.0]\r\n"
        "6d 1 [0 0.9][10 20 30 0 0 0][1 0 0 0 1 0 0 0 1]\r\n",
    )
    stick = frame.flysticks[0]
    assert stick.buttons == (1, 0, 1, 0, 0, 0, 0, 0)  # 5 = bits 0 and 2
    assert stick.joystick == (0.25, -1.0)
    np.testing.assert_allclose(
        stick.matrix[:3, :3], np.array([float(v) for v in b.split()]).reshape(3, 3).T
    )
    assert frame.calibrated_flysticks == 1
    np.testing.assert_allclose(frame.bodies[0].matrix[:3, 3], [0.01, 0.02, 0.03])


def test_6df2_flysticks_with_more_than_eight_buttons(rx: DTrackStandalone) -> None:
    # 40 buttons need two 32-bit fields: buttons 9, 11 (field 0) and 35 (bit 3 of field 1).
    fields = f"{(1 << 9) | (1 << 11)} {1 << 3}"
    frame = send(
        rx,
        "6df2 2 2 [0 1.0 40 3][1 2 3][1 0 0 0 1 0 0 0 1]"
        f"[{fields} 0.5 -0.5 1]"
        " [1 -1 12 0][0 0 0][1 0 0 0 1 0 0 0 1][4095]\r\n",
    )
    first, second = frame.flysticks
    assert len(first.buttons) == 40
    assert [i for i, b in enumerate(first.buttons) if b] == [9, 11, 35]
    assert first.joystick == (0.5, -0.5, 1.0)
    assert second.buttons == (1,) * 12 and second.joystick == () and not second.tracked


def test_old_6df_flystick_hat_bits_give_the_joystick(rx: DTrackStandalone) -> None:
    frame = send(rx, "6df 1 [0 1.0 161][0 0 0 0 0 0][1 0 0 0 1 0 0 0 1]\r\n")  # 0x01|0x20|0x80
    stick = frame.flysticks[0]
    assert stick.buttons == (1, 0, 0, 0, 0, 1, 0, 1)
    assert stick.joystick == (-1.0, 0.0)  # 0x20 (left) wins over 0x80
    assert frame.old_flysticks == 1


def test_other_record_types(rx: DTrackStandalone) -> None:
    eye = "[1 0 0 0 1 0 0 0 1]"
    frame = send(
        rx,
        "ts 39596.024000\r\n6dcal 3\r\n"
        f"6di 1 [2 2 0.5][1000 0 0]{eye}\r\n"
        f"6dmt 1 [0 0.8 5][0 0 10]{eye}\r\n"
        f"6dmt2 1 1 [1 0.7 3 2.5][0 0 20]{eye}[6][1 2 3 4 5 6]\r\n"
        "3d 2 [1 0.5][1 2 3] [2 0.6][-1000 0 500]\r\n"
        f"glcal 1\r\ngl 1 [0 1.0 0 1][0 0 0]{eye}[10 0 0]{eye}[5 30 20 15 10 25]\r\n"
        "xyz some future record\r\n",
    )
    assert frame.timestamp == pytest.approx(39596.024) and frame.calibrated_bodies == 3
    inertial = frame.bodies[0]
    assert inertial.inertial and inertial.quality == 1.0 and inertial.drift_error == 0.5
    np.testing.assert_allclose(inertial.matrix[:3, 3], [1.0, 0, 0])
    assert frame.meatools[0].buttons == (1, 0, 1, 0)
    tool = frame.meatools[1]
    assert (
        tool.buttons == (0, 1, 1)
        and tool.tip_radius_mm == 2.5
        and tool.covariance == (1, 2, 3, 4, 5, 6)
    )
    assert [m.id for m in frame.markers] == [1, 2]
    np.testing.assert_allclose(frame.markers[1].position, [-1.0, 0.0, 0.5])
    glove = frame.gloves[0]
    assert not glove.right and frame.calibrated_gloves == 1 and len(glove.fingers) == 1
    finger = glove.fingers[0]
    np.testing.assert_allclose(finger.matrix[:3, 3], [0.01, 0, 0])
    assert finger.tip_radius_mm == 5 and finger.phalanx_lengths_mm == (30, 15, 25)
    assert finger.phalanx_angles_deg == (20, 10)
    assert frame.bad_lines == 0


@pytest.mark.parametrize(
    "line",
    [
        "6d 2 [0 1.0][1 2 3][1 0 0 0 1 0 0 0 1]",  # says 2 bodies, holds 1
        "6d 1 [0 1.0][1 2 3][1 0 0 0 1 0 0]",  # 8 rotation values
        "6d 1 [0 1.0][1 2 3][1 0 0 0 1 0 0 0 1",  # unbalanced
        "6d 1 [0 nan][1 2 3][1 0 0 0 1 0 0 0 1]",  # not finite
        "6df2 1 1 [1 1.0 8 2][1 2 3][1 0 0 0 1 0 0 0 1][0 0 0]",  # id is not the index
        "6df2 1 1 [0 1.0 40 2][1 2 3][1 0 0 0 1 0 0 0 1][0 0 0]",  # 2 fields + 2 values needed
        "6df2 1 1 [0 1.0 -1 2][1 2 3][1 0 0 0 1 0 0 0 1][0 0 0]",  # negative count
        "gl 1 [0 1.0 2 0][0 0 0][1 0 0 0 1 0 0 0 1]",  # hand is neither 0 nor 1
        "3d 1 [1.5 1.0][1 2 3]",  # id not an integer
        "fr -3",
    ],
)
def test_malformed_lines_are_skipped_and_counted(line: str) -> None:
    frame = parse_frame(f"fr 5\r\n{line}\r\nts 1.5\r\n".encode())
    assert frame is not None and frame.bad_lines == 1
    assert frame.frame == 5 and frame.timestamp == 1.5 and not frame.bodies and not frame.flysticks


def test_datagrams_without_a_frame_are_counted(rx: DTrackStandalone) -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
        for junk in (b"\xff\x00\x81garbage", b"hello\r\n", b"", b"6d 1 [0 1.0][1 2"):
            tx.sendto(junk, ("127.0.0.1", rx.port))
        tx.sendto(b"fr 9\r\n", ("127.0.0.1", rx.port))
    frames = collect(rx, lambda f: len(f) >= 1, timeout=1.0)
    assert [f.frame for f in frames] == [9]
    assert rx.datagrams == 5 and rx.bad_datagrams == 4 and rx.bad_lines == 0


def test_datagram_larger_than_the_buffer_is_truncated() -> None:
    with receiver(buffer_size=40) as rx:  # the cut falls inside the 3d line
        text = "fr 3\r\n" + "3d 3 [1 1.0][1 2 3] [2 1.0][4 5 6] [3 1.0][7 8 9]\r\n" + "ts 1.0\r\n"
        frame = send(rx, text)
        assert rx.truncated_datagrams == 1 and frame.frame == 3 and frame.bad_lines == 1
        assert rx.bad_lines == 1 and not frame.markers


def test_injected_socket_is_used_and_not_closed() -> None:
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    try:
        with DTrackStandalone(sock, receive_timeout=0.02) as rx:
            assert rx.port == sock.getsockname()[1]
            assert send(rx, "fr 1\r\n").frame == 1
        assert sock.fileno() != -1
    finally:
        sock.close()


def test_sample_needs_open() -> None:
    with pytest.raises(RuntimeError):
        DTrackStandalone(0).sample()


# -- the emulator --------------------------------------------------------------------------------


def test_motion_frames_counter_timestamp_and_poses(rx: DTrackStandalone) -> None:
    frames, _ = run(rx, 12, scenario="motion", bodies=3)
    assert [f.frame for f in frames] == list(range(1, 13))
    for frame in frames:
        n = frame.frame
        assert n is not None
        assert frame.timestamp == pytest.approx(36000.0 + n / RATE, abs=1e-6)
        assert frame.calibrated_bodies == 3
        ids = [b.id for b in frame.bodies]
        assert ids == ([0, 2] if n % 4 == 3 else [0, 1, 2])  # body 1 drops out every 4th frame
        for body in frame.bodies:
            expected = np.eye(4)
            expected[:3, :3] = euler_rotation(*object_angles(n, body.id, True))
            expected[:3, 3] = np.array(object_location(n, body.id, True)) / 1000.0
            np.testing.assert_allclose(body.matrix, expected, atol=2e-6)
        stick = frame.flysticks[0]
        assert stick.joystick == flystick_joystick(n, "motion")
        np.testing.assert_allclose(
            stick.matrix[:3, 3], np.array(object_location(n, 100, True)) / 1000.0
        )
        for marker in frame.markers:
            np.testing.assert_allclose(
                marker.position, np.array(marker_location(n, marker.id, True)) / 1000
            )
        glove = frame.gloves[0]
        assert glove.right and len(glove.fingers) == 3  # glove 0 is a right hand (lr = 1)
        assert [f.phalanx_lengths_mm for f in glove.fingers] == [(20 + f, 25, 30) for f in range(3)]


def test_units_order_and_untracked_bodies_keep_their_pose(rx: DTrackStandalone) -> None:
    frames, _ = run(rx, 8, scenario="motion", bodies=2)
    units = DTrackUnits()
    for frame in frames:
        before = units.positions()
        units.update(frame)
        positions = units.positions()
        assert len(positions) == 3  # unit 0: Flystick, units 1 and 2: bodies 0 and 1
        np.testing.assert_allclose(positions[0], frame.flysticks[0].matrix)
        np.testing.assert_allclose(positions[1], frame.bodies[0].matrix)
        if frame.frame is not None and frame.frame % 4 == 3:
            assert units.qualities()[2] == -1.0
            np.testing.assert_allclose(positions[2], before[2])  # the last known pose
        else:
            np.testing.assert_allclose(positions[2], frame.bodies[1].matrix)
        assert units.analog() == list(frame.flysticks[0].joystick)
        assert len(units.digital()) == 8


def test_buttons_scenario_reaches_beyond_eight(rx: DTrackStandalone) -> None:
    frames, _ = run(rx, 20, scenario="buttons", rate=1000.0, flystick_buttons=10)
    units = DTrackUnits()
    for frame in frames:
        assert frame.frame is not None
        stick = frame.flysticks[0]
        assert stick.buttons == flystick_buttons(frame.frame, 10, "buttons")
        units.update(frame)
        assert units.digital() == list(stick.buttons[:8])  # Gadgeteer maps 8 per Flystick
    pressed = {i for f in frames for i, b in enumerate(f.flysticks[0].buttons) if b}
    assert {8, 9} <= pressed


def test_old_format_flystick_from_the_emulator(rx: DTrackStandalone) -> None:
    frames, _ = run(rx, 10, scenario="motion", flystick_format="6df")
    for frame in frames:
        assert frame.frame is not None and frame.calibrated_bodies == 3  # 2 bodies + 1 old Flystick
        x, y = flystick_joystick(frame.frame, "motion")
        expected = (
            -1.0 if x < -0.5 else 1.0 if x > 0.5 else 0.0,
            -1.0 if y < -0.5 else 1.0 if y > 0.5 else 0.0,
        )
        assert frame.flysticks[0].joystick == expected
        units = DTrackUnits()
        units.update(frame)
        assert len(units.positions()) == 3  # 6dcal 3 - 1 old Flystick = 2 bodies, plus the Flystick


def test_idle_poses_do_not_change(rx: DTrackStandalone) -> None:
    frames, _ = run(rx, 5, scenario="idle")
    for frame in frames[1:]:
        for a, b in zip(frame.bodies, frames[0].bodies, strict=True):
            np.testing.assert_array_equal(a.matrix, b.matrix)
        assert frame.flysticks[0].joystick == (0.0, 0.0)


def test_garbage_is_counted_and_every_valid_frame_kept(rx: DTrackStandalone) -> None:
    frames, emu = run(rx, 24, scenario="garbage", seed=7)
    assert len(frames) == 24
    assert rx.bad_datagrams == emu.garbage_sent > 0
    assert rx.bad_lines == emu.bad_lines_sent > 0
    assert sum(f.bad_lines for f in frames) == emu.bad_lines_sent


def test_disconnect_is_reported_then_a_new_sender_is_received() -> None:
    with receiver(peer_timeout=0.1) as rx:
        with DTrackEmulator(rx.port, scenario="disconnect", rate=RATE, disconnect_after=5) as emu:
            frames: list[DTrackFrame] = []
            end = time.monotonic() + 3.0
            with pytest.raises(DTrackDisconnected):
                while time.monotonic() < end:
                    frames.extend(rx.sample_all())
            assert [f.frame for f in frames] == [1, 2, 3, 4, 5]
            assert emu.finished.wait(1.0)
        rx.close()
        rx.open()
        with DTrackEmulator(rx.port, scenario="motion", rate=RATE, first_frame=100):
            again = collect(rx, lambda f: len(f) >= 1)
        assert again[0].frame == 100


def test_remote_commands_start_and_stop_the_tracker() -> None:
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    try:
        with DTrackEmulator(
            sock.getsockname()[1], rate=RATE, command_port=0, wait_for_start=True
        ) as emu:
            host, port = emu.command_address.rsplit(":", 1)  # type: ignore[union-attr]
            rx = DTrackStandalone(
                sock,
                server_name=host,
                command_port=int(port),
                receive_timeout=0.02,
                start_delay=0.01,
            )
            assert not emu.frames_sent  # nothing before "dtrack 31"
            with rx:
                assert collect(rx, lambda f: len(f) >= 3)
            assert emu.wait_for_command(CMD_CAMERAS_OFF)
            assert emu.commands == [
                CMD_CAMERAS_AND_TRACKING_ON,
                CMD_START_SENDING,
                CMD_STOP_SENDING,
                CMD_CAMERAS_OFF,
            ]
            assert all(b"\0" not in raw for raw in emu.raw_commands)
    finally:
        sock.close()


def test_emulator_main_runs_for_a_duration(
    rx: DTrackStandalone, capsys: pytest.CaptureFixture[str]
) -> None:
    assert (
        main(["--port", str(rx.port), "--duration", "0.05", "--rate", "200", "--bodies", "1"]) == 0
    )
    assert f"<receive_port>{rx.port}</receive_port>" in capsys.readouterr().out
    frames = drain(rx)
    assert frames and all(len(f.bodies) == 1 for f in frames)


def test_emulator_is_loopback_only() -> None:
    assert DTrackEmulator(5999).address == "127.0.0.1:5999"  # not started: nothing is sent
    with pytest.raises(ValueError):
        DTrackEmulator(0)
    with pytest.raises(ValueError):
        DTrackEmulator(5999, scenario="dance")


# -- the fast body decoder against the general parser ----------------------------------------------

EYE = "[1 0 0 0 1 0 0 0 1]"


def _same(a: DTrackFrame | None, b: DTrackFrame | None) -> None:
    assert (a is None) == (b is None)
    if a is None or b is None:
        return
    assert (a.frame, a.timestamp, a.bad_lines, a.calibrated_bodies) == (
        b.frame,
        b.timestamp,
        b.bad_lines,
        b.calibrated_bodies,
    )
    assert len(a.bodies) == len(b.bodies)
    for x, y in zip(a.bodies, b.bodies, strict=True):
        assert (x.id, x.quality, x.location_mm, x.inertial, x.drift_error) == (
            y.id,
            y.quality,
            y.location_mm,
            y.inertial,
            y.drift_error,
        )
        np.testing.assert_array_equal(x.matrix, y.matrix)
    np.testing.assert_array_equal(a.bodies.matrices, b.bodies.matrices)


@pytest.mark.parametrize(
    "body",
    [
        f"6d 2 [0 1.000][10.5 -20.25 3000 1 2 3]{EYE} [7 -1.000][1 2 3 4 5 6]{EYE}",  # DTrack's layout
        f"6d 1 [007 0.5][1e2 2E-1 -0.0]{EYE}",  # short middle block, exponents, leading zeros
        f"6d 1 [0 1][1 2 3 4]{EYE}",  # a layout the fast path leaves to the general parser
        f"6d 1 [0 1 9][1 2 3]{EYE}",  # a longer first block: likewise
        f"6d 2 [0 1][1 2 3]{EYE}",  # says 2, holds 1
        "6d 1 [0 1][1 2 3][1 0 0 0 1 0 0 0]",  # 8 rotation values
        f"6d 1 [0 1][1 2 3]{EYE}[",  # unbalanced
        f"6d 1 [0 nan][1 2 3]{EYE}",  # not finite
        f"6d 1 [-1 1][1 2 3]{EYE}",  # negative id
        f"6d 1 [0 x][1 2 3]{EYE}",  # not a number
        f"6d 1 [0 1]x[1 2 3]{EYE}",  # stray text between blocks
        f"6d 1  [0 1] [1 2 3] {EYE} ",  # blanks between blocks
        "6d 0",
        f"6d 1 [0 1][1 2 3]{EYE}\r\n6di 1 [1 2 0.5][1 2 3]{EYE}",  # both kinds of body
    ],
)
def test_fast_body_decoding_agrees_with_the_general_parser(body: str) -> None:
    data = f"fr 3\r\nts 1.25\r\n6dcal 4\r\n{body}\r\n".encode()
    _same(parse_frame(data), parse_frame(data, fast=False))


def test_fast_decoding_agrees_on_every_emulator_scenario() -> None:
    for scenario in ("motion", "idle", "buttons", "garbage"):
        for flystick_format in ("6df2", "6df"):
            emulator = DTrackEmulator(
                5999, scenario=scenario, bodies=12, flystick_format=flystick_format
            )
            for n in range(1, 9):  # body 1 is missing from frame 3 and 7 in motion
                text = emulator.writer.frame(n)
                _same(parse_frame(text), parse_frame(text, fast=False))


# -- many frames merged at once ------------------------------------------------------------------


def _step_by_step(frames: list[DTrackFrame]) -> list[tuple[np.ndarray, list, list, list]]:
    units = DTrackUnits(extra_units=True)
    states = []
    for frame in frames:
        units.update(frame)
        states.append((units.position_array(), units.qualities(), units.digital(), units.analog()))
    return states


@pytest.mark.parametrize("scenario", ["motion", "buttons", "idle"])
def test_merging_many_frames_equals_merging_them_one_by_one(scenario: str) -> None:
    emulator = DTrackEmulator(5999, scenario=scenario, bodies=4, flysticks=2, flystick_buttons=11)
    frames = [parse_frame(emulator.writer.frame(n)) for n in range(1, 13)]
    merged = DTrackUnits(extra_units=True).merge(frames)
    for k, (positions, qualities, digital, analog) in enumerate(_step_by_step(frames)):
        np.testing.assert_array_equal(merged.positions[k], positions)
        assert merged.qualities[k].tolist() == qualities
        assert merged.digital[k].tolist() == digital and merged.analog[k].tolist() == analog
    assert merged.digital.shape == (12, 2 * 8 + 2 * 3)  # 8 per Flystick, then 3 more each


def test_objects_appearing_in_a_batch_take_the_last_layout() -> None:
    body = "[1 0 0 0 1 0 0 0 1]"
    frames = [
        parse_frame(f"fr 1\r\n6d 2 [0 1.0][1 2 3]{body} [1 -1][4 5 6]{body}\r\n"),
        parse_frame(
            f"fr 2\r\n6df2 1 1 [0 1.0 10 2][7 8 9]{body}[512 0.5 -0.5]\r\n6d 1 [1 1.0][4 5 6]{body}\r\n"
        ),
    ]
    merged = DTrackUnits(extra_units=True).merge(frames)
    assert merged.positions.shape == (2, 3, 4, 4)  # the Flystick, then bodies 0 and 1
    np.testing.assert_array_equal(merged.positions[0, 0], np.eye(4))  # not seen yet
    np.testing.assert_allclose(merged.positions[0, 1, :3, 3], [0.001, 0.002, 0.003])
    np.testing.assert_array_equal(merged.positions[0, 2], np.eye(4))  # untracked so far
    assert merged.qualities.tolist() == [[-1.0, 1.0, -1.0], [1.0, -1.0, 1.0]]
    np.testing.assert_allclose(merged.positions[1, 1, :3, 3], [0.001, 0.002, 0.003])  # kept
    np.testing.assert_allclose(merged.positions[1, 2, :3, 3], [0.004, 0.005, 0.006])
    assert merged.digital.tolist() == [[0] * 10, [0] * 8 + [0, 1]]  # button 9 (bit 9 of 512)
    assert merged.analog.tolist() == [[0.0, 0.0], [0.5, -0.5]]


def test_decoding_many_datagrams_at_once_agrees_with_the_general_parser() -> None:
    emulator = DTrackEmulator(5999, scenario="motion", bodies=12, flysticks=2, flystick_buttons=40)
    texts = [emulator.writer.frame(n) for n in range(1, 30)]
    texts[3] += "6d 1 [0 -1.000][-0.000 0 -0][-0.000000 1 0 -.5 1. 0 0 0 1]\r\n"  # signed zeros
    for batched, text in zip(parse_frames(texts), texts, strict=True):
        general = parse_frame(text, fast=False)
        _same(batched, general)
        assert batched is not None and general is not None
        assert np.array_equal(
            np.signbit(batched.bodies.matrices), np.signbit(general.bodies.matrices)
        )
        for a, b in zip(batched.flysticks, general.flysticks, strict=True):
            assert (a.id, a.quality, a.location_mm, a.buttons, a.joystick) == (
                b.id,
                b.quality,
                b.location_mm,
                b.buttons,
                b.joystick,
            )
            np.testing.assert_array_equal(a.matrix, b.matrix)


def test_a_bad_number_in_a_batch_costs_only_its_own_line() -> None:
    good = "fr {n}\r\n6d 1 [0 1.000][100.000 200.000 300.000][1 0 0 0 1 0 0 0 1]\r\n"
    bad = "fr 2\r\n6d 1 [0 1.000][100.000 2x0.000 300.000][1 0 0 0 1 0 0 0 1]\r\nts 1.0\r\n"
    frames = parse_frames([good.format(n=1), bad, good.format(n=3)] * 40)
    assert [f.frame for f in frames[:3]] == [1, 2, 3]  # type: ignore[union-attr]
    assert frames[1].bad_lines == 1 and not frames[1].bodies  # type: ignore[union-attr]
    assert all(len(f.bodies) == 1 and f.bad_lines == 0 for f in frames[0::3] + frames[2::3])  # type: ignore[union-attr]


def test_decimal_tokens_are_read_exactly_as_float_reads_them() -> None:
    tokens = ["-0.000", "0", "-0", "12.25", "-.5", "7.", "0.1", "123456789.012345", "-1.000001"]
    values = _decimals(" ".join(tokens).encode(), tokens)
    assert values is not None
    assert values.tolist() == [float(t) for t in tokens]
    assert np.signbit(values).tolist() == [t.startswith("-") for t in tokens]
    for odd in (["1.2.3"], ["1-2"], ["-"], ["-."], ["1", "."], ["1" * 20], ["1." + "0" * 23]):
        assert _decimals(" ".join(odd).encode(), odd) is None, odd
