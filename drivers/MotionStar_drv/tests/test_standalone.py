"""MotionStar standalone driver against the emulator over loopback TCP."""

from __future__ import annotations

import math
import socket
import struct

import numpy as np
import pytest
from MotionStar_drv.emulator import BUTTON_STEPS, MotionStarEmulator, encode_words, pose
from MotionStar_drv.standalone import (
    MotionStar,
    MotionStarDisconnected,
    MotionStarSample,
    decode_record,
    parse_records,
)

from gadgetctl.input.testing.fixtures import emulator_fixture

pytestmark = pytest.mark.timeout(10)

FAST = {"connect_timeout": 2.0, "read_timeout": 1.0, "sample_timeout": 1.0, "close_timeout": 0.5}
FULL_SCALE = 144


emulator = emulator_fixture(MotionStarEmulator, "idle", rate=500.0)


def client(emu: MotionStarEmulator, **kwargs: object) -> MotionStar:
    host, port = emu.address.rsplit(":", 1)
    return MotionStar(host, int(port), **{**FAST, **kwargs})  # type: ignore[arg-type]


def take(ms: MotionStar, count: int) -> list[MotionStarSample]:
    samples = []
    while len(samples) < count:
        sample = ms.sample()
        assert sample is not None, f"no data packet after {len(samples)}"
        samples.append(sample)
    return samples


def rz(deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def ry(deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rx(deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def test_startup_messages_and_sequence_numbers(emulator) -> None:
    emu = emulator("idle", erc=True, birds=2)
    ms = client(emu, measurement_rate=86.1, hemisphere=3, report_rate=2)
    with ms:
        assert [(kind, xtype) for kind, xtype, _ in emu.received] == [
            (10, 0),  # wake-up
            (101, 0),  # system status
            (102, 0),  # new measurement rate
            (101, 0),  # status again, to see the rate taken
            (101, 2),  # ERC at address 1 is skipped
            (102, 2),
            (101, 3),
            (102, 3),
            (104, 0),  # run continuous
        ]
        assert [seq for _, _, seq in emu.received] == list(range(9))
        assert ms.sequence == 9  # each reply echoed the number, the counter moved on
        assert emu.measurement_rate == pytest.approx(86.1)
        assert ms.system_status is not None
        assert ms.system_status.measurement_rate == pytest.approx(86.1)
        assert ms.sensors == (2, 3)
        assert ms.full_scale == FULL_SCALE and ms.units == "inches"
        for device in emu.sensors:
            assert device.status[6] == 0x64  # 6 words, position/angles
            assert device.status[5] & 0x08  # buttons appended
            assert device.status[7] == 2 and device.status[10] == 3

        samples = take(ms, 5)
        sequences = [s.sequence for s in samples]
        assert sequences == list(range(9, 14))  # the stream continues the count
        assert ms.sequence == 14
        assert ms.sequence_resyncs == 0
    # stop and shut-down carry on from the last packet read
    assert emu.received[-2][:2] == (105, 0) and emu.received[-2][2] == 14
    assert emu.received[-1] == (11, 0, 15)


def test_positions_are_scaled_inches_and_angles_are_zyx(emulator) -> None:
    emu = emulator("idle", erc=True, birds=2)
    with client(emu) as ms:
        samples = take(ms, 3)
    for sample in samples:
        sent = emu.sent_data[sample.sequence]
        assert [b.unit for b in sample.birds] == [0, 1]
        assert [b.address for b in sample.birds] == [2, 3]  # unit order = address order
        for bird in sample.birds:
            code, words, _buttons = sent[bird.address]
            assert code == 4 and bird.data_format == 4
            position = [FULL_SCALE * w / 32767 for w in words[:3]]
            z, y, x = (180 * w / 32767 for w in words[3:6])
            assert bird.position == pytest.approx(position, abs=1e-12)
            assert bird.angles == pytest.approx((z, y, x), abs=1e-12)
            expected = np.eye(4)
            expected[:3, :3] = rz(z) @ ry(y) @ rx(x)
            expected[:3, 3] = position
            assert bird.matrix.dtype == np.float64 and bird.matrix.shape == (4, 4)
            np.testing.assert_allclose(bird.matrix, expected, atol=1e-12)
            wrong_order = rx(x) @ ry(y) @ rz(z)
            assert not np.allclose(bird.matrix[:3, :3], wrong_order, atol=1e-3)
            # and the physical pose the emulator meant, within one word's step
            pos, ang = pose("idle", bird.unit, 0)
            assert bird.position == pytest.approx(pos, abs=FULL_SCALE / 32767)
            assert bird.angles == pytest.approx(ang, abs=180 / 32767)


@pytest.mark.parametrize("data_format", [1, 2, 3, 4, 5, 7, 8])
def test_every_data_format_gives_the_same_pose(emulator, data_format: int) -> None:
    emu = emulator("idle", birds=2)
    with client(emu, data_format=data_format) as ms:
        sample = take(ms, 1)[0]
    has_position = data_format in (1, 4, 5, 8)
    has_rotation = data_format != 1
    for bird in sample.birds:
        assert bird.data_format == data_format
        pos, (z, y, x) = pose("idle", bird.unit, 0)
        expected_rot = rz(z) @ ry(y) @ rx(x) if has_rotation else np.eye(3)
        np.testing.assert_allclose(bird.matrix[:3, :3], expected_rot, atol=2e-4)
        expected_pos = pos if has_position else (0.0, 0.0, 0.0)
        np.testing.assert_allclose(bird.matrix[:3, 3], expected_pos, atol=0.005)
        np.testing.assert_allclose(bird.matrix[3], [0, 0, 0, 1])
        if data_format in (7, 8):
            assert bird.quaternion is not None and bird.quaternion[0] > 0


@pytest.mark.parametrize("code", [3, 5, 7, 8])
def test_rotation_words_round_trip_over_all_orientations(code: int) -> None:
    for k in range(0, 3000, 7):  # the motion path sweeps all quadrants
        position, (z, y, x) = pose("motion", 1, k)
        words = encode_words(code, position, (z, y, x), FULL_SCALE)
        record = parse_records(
            bytes([0x01, code << 4 | len(words)]) + struct.pack(f">{len(words)}h", *words)
        )
        assert record is not None
        matrix = decode_record(record[0], 0, float(FULL_SCALE)).matrix
        np.testing.assert_allclose(matrix[:3, :3], rz(z) @ ry(y) @ rx(x), atol=3e-4)


def test_matrix_words_are_signed_fractions() -> None:
    # one MATRIX record: identity with -1 and the smallest negative value mixed in
    words = (32767, 0, -1, 0, -32768, 0, 0, 0, 32767)
    payload = bytes([0x01, 0x39]) + struct.pack(">9h", *words)
    (record,) = parse_records(payload)
    matrix = decode_record(record, 0, 144.0).matrix
    assert matrix[1, 1] == -1.0
    assert matrix[0, 2] == pytest.approx(-1 / 32768)  # the C++ read 0xFFFF as about -2.0
    assert matrix[0, 0] == pytest.approx(32767 / 32768)


def test_buttons_follow_each_record(emulator) -> None:
    emu = emulator("buttons", birds=2)
    with client(emu, data_format=1) as ms:  # 3 words: buttons sit 8 bytes into the record
        samples = take(ms, len(BUTTON_STEPS))
    for sample in samples:
        for bird in sample.birds:
            assert bird.buttons == emu.sent_data[sample.sequence][bird.address][2]
    # the first data packet is step 0 of the press/release script, for every sensor
    for unit in (0, 1):
        assert [s.birds[unit].buttons for s in samples] == [(b, 0) for b in BUTTON_STEPS]


def test_parse_records_reads_buttons_after_short_data() -> None:
    first = bytes([0x81, 0x13]) + struct.pack(">3h", 1, 2, 3) + bytes([0x05, 0x06])
    second = bytes([0x02, 0x13]) + struct.pack(">3h", 4, 5, 6)
    records = parse_records(first + second)
    assert records is not None
    assert [(r.address, r.words, r.buttons) for r in records] == [
        (1, (1, 2, 3), (5, 6)),
        (2, (4, 5, 6), None),
    ]
    assert parse_records(first[:-1]) is None  # cut short
    assert parse_records(bytes([0x00, 0x13]) + bytes(6)) is None  # FBB addresses start at 1
    assert parse_records(bytes([0x01, 0x14]) + bytes(8)) is None  # word count != format


def test_a_feed_through_record_is_stepped_over_not_the_whole_packet() -> None:
    # 0xE1: format code 14, one data word, after the sensor's record (a wand button held);
    # the C++ steps over every record by its word count
    pose_record = bytes([0x81, 0x46]) + struct.pack(">6h", 100, 200, 300, 0, 0, 0) + b"\x01\x00"
    feed_through = bytes([0x01, 0xE1]) + struct.pack(">h", 1)
    second = bytes([0x02, 0x46]) + struct.pack(">6h", -100, 0, 50, 0, 0, 0)
    records = parse_records(pose_record + feed_through + second)
    assert records is not None
    assert [(r.address, r.format_code, len(r.words)) for r in records] == [
        (1, 4, 6),
        (1, 14, 1),
        (2, 4, 6),
    ]


def test_feed_through_records_leave_tracking_alone(emulator) -> None:
    emu = emulator("buttons", birds=2)
    with client(emu, data_format=4) as ms:
        samples = take(ms, 2 * len(BUTTON_STEPS))
        assert ms.other_records > 0  # the buttons were held at times: 0xE1 records came
        assert ms.bad_packets == 0
    assert all(len(s.birds) == 2 for s in samples)  # every packet kept both sensors
    held = [s for s in samples if s.birds[0].buttons and s.birds[0].buttons[0]]
    assert held, "no packet with a button held"


def test_garbage_and_truncated_packets_are_counted(emulator) -> None:
    emu = emulator("garbage", birds=2)
    with client(emu) as ms:
        samples = take(ms, 24)
        assert ms.bad_packets == 24  # one junk run before every packet
        assert ms.skipped_bytes > 0
        assert ms.sequence_resyncs == 0  # no valid packet was lost
    sequences = [s.sequence for s in samples]
    assert sequences == list(range(sequences[0], sequences[0] + 24))
    for sample in samples:
        for bird in sample.birds:
            words = emu.sent_data[sample.sequence][bird.address][1]
            assert bird.position == pytest.approx([FULL_SCALE * w / 32767 for w in words[:3]])


def test_disconnect_is_reported_and_reconnect_works(emulator) -> None:
    emu = emulator("disconnect", birds=1, disconnect_after=4)
    ms = client(emu)
    ms.open()
    take(ms, 4)
    with pytest.raises(MotionStarDisconnected):
        for _ in range(3):
            ms.sample()
    ms.close()  # must not raise with the peer gone
    assert not ms.is_open
    assert emu.client_left.wait(2)
    with client(emu) as again:
        assert len(take(again, 2)) == 2
    assert emu.connections == 2
    wake_ups = [seq for kind, _, seq in emu.received if kind == 10]
    assert wake_ups == [0, 0]  # a new connection counts from 0 again


def test_single_shot_mode_asks_for_each_packet(emulator) -> None:
    emu = emulator("motion", birds=2)
    with client(emu, mode=1) as ms:
        assert 104 not in [kind for kind, _, _ in emu.received]
        first, second = take(ms, 2)
    shots = [(kind, seq) for kind, _, seq in emu.received if kind == 103]
    assert [seq for _, seq in shots] == [first.sequence, second.sequence]
    assert second.sequence == first.sequence + 1
    assert [kind for kind, _, _ in emu.received][-1] == 11  # no stop-data needed


def test_injected_socket_is_used_not_closed(emulator) -> None:
    emu = emulator("idle", birds=1)
    host, port = emu.address.rsplit(":", 1)
    sock = socket.create_connection((host, int(port)), timeout=2)
    try:
        with MotionStar(sock=sock, **FAST) as ms:
            assert take(ms, 1)[0].birds[0].address == 1
        assert sock.fileno() != -1
    finally:
        sock.close()


def test_sample_times_out_between_slow_packets(emulator) -> None:
    emu = emulator("idle", birds=1, rate=2.0)
    with client(emu, sample_timeout=0.05) as ms:
        assert ms.sample() is not None  # the first packet comes at once
        assert ms.sample() is None


@pytest.mark.parametrize(("asked", "taken"), [(500.0, 144.0), (5.0, 20.0), (72.4, 72.4)])
def test_measurement_rate_is_clamped(emulator, asked: float, taken: float) -> None:
    emu = emulator("idle", birds=1)
    with client(emu, measurement_rate=asked):
        pass
    assert emu.measurement_rate == pytest.approx(taken)


def test_invalid_settings_are_rejected() -> None:
    with pytest.raises(ValueError):
        MotionStar("127.0.0.1", 1, data_format=6)
    with pytest.raises(ValueError):
        MotionStar("127.0.0.1", 1, report_rate=256)


def test_refused_connection_is_reported_as_disconnected() -> None:
    probe = socket.socket()
    probe.bind(("127.0.0.1", 0))
    port = probe.getsockname()[1]
    probe.close()  # nothing listens there now
    with pytest.raises(MotionStarDisconnected):
        MotionStar("127.0.0.1", port, **FAST).open()


def test_emulator_main_prints_where_to_point(capsys) -> None:
    from MotionStar_drv.emulator import main

    argv = [
        "--scenario",
        "idle",
        "--birds",
        "3",
        "--rate",
        "10",
        "--duration",
        "0.1",
        "--port",
        "0",
    ]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "3 sensors" in out and "<address>127.0.0.1</address>" in out
    assert "<server_port>" in out


# -- junk on the stream -------------------------------------------------------------------------


def test_a_reply_like_header_in_junk_does_not_swallow_the_next_packets(emulator) -> None:
    """A false header inside junk that claims a payload must not eat the data that follows."""
    emu = emulator("motion", birds=2)
    fake = struct.pack(
        ">HH4sBBBBHH", 7, 0, bytes(4), 20, 0, 3, 0, 0, 200
    )  # wake-up reply, 200 bytes
    with client(emu) as ms:
        samples = take(ms, 3)
        emu.inject(b"\x55" * 5 + fake)
        while ms.skipped_bytes == 0:
            samples += take(ms, 1)
        samples += take(ms, 10)
        assert ms.skipped_bytes == 5 + len(fake) and ms.bad_packets == 1
    sequences = [s.sequence for s in samples]
    assert sequences == list(range(sequences[0], sequences[0] + len(samples)))


@pytest.mark.timeout(30)  # a hang guard; bench/motionstar_resync.py measures the speed
def test_a_long_junk_run_is_skipped_whole_and_no_packet_is_lost(emulator) -> None:
    import random

    emu = emulator("motion", birds=2)
    junk = random.Random(12).randbytes(16 << 20)
    with client(emu) as ms:
        samples = take(ms, 3)
        emu.inject(junk)
        while ms.skipped_bytes < len(junk):
            samples += take(ms, 1)
        samples += take(ms, 3)
        assert ms.skipped_bytes == len(junk) and ms.bad_packets == 1
    sequences = [s.sequence for s in samples]
    assert sequences == list(range(sequences[0], sequences[0] + len(samples)))


def packet(sequence: int, payload: bytes, kind: int = 210) -> bytes:
    return (
        struct.pack(">HH4sBBBBHH", sequence, 0, bytes(4), kind, 0, 3, 0, 0, len(payload)) + payload
    )


def test_framer_prefers_the_expected_packet_over_a_cut_short_one() -> None:
    """A data packet cut short by the next one can parse with the next header as its tail
    (here: sequence 0x02F7 reads as an error record of address 2 with 7 words)."""
    from MotionStar_drv.standalone import Framer

    record = bytes([0x81, 0x46]) + bytes(12) + bytes(2)  # address 1, position/angles, buttons
    real = packet(0x02F7, record + bytes([0x82, 0x46]) + bytes(14))
    cut = packet(0xFFFF, record + bytes(16))[: 16 + 16]
    framer = Framer()
    framer.feed(cut + real)
    header, _payload, records = framer.next(frozenset({210}), expected=0x02F7)
    assert header.sequence == 0x02F7 and [r.address for r in records] == [1, 2]
    assert framer.skipped_bytes == len(cut) and framer.bad_packets == 1
    assert framer.next(frozenset({210}), expected=0x02F8) is None and not framer.buffer


def test_framer_skips_types_it_does_not_wait_for_and_keeps_partial_packets() -> None:
    from MotionStar_drv.standalone import Framer

    framer = Framer()
    data = packet(4, bytes([0x81, 0x13]) + bytes(8))
    framer.feed(packet(3, b"", kind=20) + data[:20])
    assert framer.next(frozenset({210})) is None  # the reply is junk here; the packet is cut
    assert framer.skipped_bytes == 16 and len(framer.buffer) == 20
    framer.feed(data[20:])
    header, _payload, records = framer.next(frozenset({210}))
    assert header.sequence == 4 and records[0].words == (0, 0, 0)
