"""The Fastrak protocol half against the emulator over a real pty pair, and its decoder."""

from __future__ import annotations

import math
import struct

import numpy as np
import pytest
from Fastrak_drv.emulator import GARBAGE_CHUNKS, FastrakEmulator, about, encode_record
from Fastrak_drv.standalone import (
    CENTIMETRE,
    RECORD_SIZE,
    Fastrak,
    FastrakDisconnected,
    RecordScanner,
    decode_record,
    quaternion_matrix,
)

from gadgetctl.input.testing import gather, wait_until
from gadgetctl.input.testing.fixtures import emulator_fixture

pytestmark = pytest.mark.timeout(20)
FAST = {"read_timeout": 2.0, "poll_interval": 0.005}


emulator = emulator_fixture(FastrakEmulator, rate=500.0)


def test_port_is_opened_before_the_set_up_which_ends_in_streaming(emulator) -> None:
    emu = emulator("idle", active=(1, 2, 4))
    with Fastrak(emu.address, hemisphere=4, **FAST) as tracker:
        assert tracker.active == (1, 2, 4) and tracker.units == "centimetres"
        assert tracker.version == "3.0GC"
        assert wait_until(lambda: emu.continuous)
    # every command reached the tracker (the C++ sent them before opening the port)
    assert emu.commands[:3] == [b"c", b"f", b"u"]
    assert emu.output_lists == {s: "2,11,16,1" for s in (1, 2, 3, 4)}
    assert emu.hemispheres == {s: "0,0,1" for s in (1, 2, 3, 4)}  # 4: lower
    assert emu.stylus_modes == {1: "0"}
    streaming = emu.commands.index(b"C")
    assert emu.commands[streaming - 2 : streaming + 1] == [b"l1", b"S", b"C"]
    assert emu.commands[streaming + 1 :] in ([], [b"c"])  # close() stops the stream


def test_records_decode_to_metres_quaternions_and_a_0_1_stylus(emulator) -> None:
    emu = emulator("buttons", active=(1, 4))
    with Fastrak(emu.address, **FAST) as tracker:
        got = gather(tracker.read, 30)
    assert tracker.bad_records == 0
    sent = emu.sent[: len(got)]
    assert [r.station for r in got] == [s[0] for s in sent] and {r.station for r in got} == {1, 4}
    for record, (_, position, quaternion, button) in zip(got, sent, strict=True):
        np.testing.assert_allclose(record.position, [v * CENTIMETRE for v in position], rtol=1e-6)
        np.testing.assert_allclose(record.quaternion, quaternion, rtol=1e-6)
        assert record.stylus == button and record.stylus in (0, 1)
    assert {r.stylus for r in got if r.station == 1} == {0, 1}


def test_quaternion_is_w_first_and_its_sign_does_not_matter() -> None:
    x, y, z = np.eye(3)
    q = about((0.0, 0.0, 1.0), 90.0)  # (w, x, y, z)
    np.testing.assert_allclose(quaternion_matrix(*q) @ x, y, atol=1e-12)
    np.testing.assert_allclose(
        quaternion_matrix(*(-v for v in q)), quaternion_matrix(*q), atol=1e-12
    )
    np.testing.assert_allclose(quaternion_matrix(*about((1.0, 0.0, 0.0), 90.0)) @ y, z, atol=1e-12)
    record = decode_record(encode_record(2, (1.0, 2.0, 3.0), q, 1), 0.0254)
    assert record is not None and record.stylus == 1
    np.testing.assert_allclose(record.matrix()[:3, 3], (0.0254, 0.0508, 0.0762), rtol=1e-6)
    np.testing.assert_allclose(record.matrix()[:3, :3] @ x, y, atol=1e-6)


def test_garbage_is_skipped_and_counted(emulator) -> None:
    emu = emulator("garbage")
    with Fastrak(emu.address, **FAST) as tracker:
        got = gather(tracker.read, 40)
    sent = emu.sent[: len(got)]
    assert [(r.station, r.stylus) for r in got] == [(s[0], s[3]) for s in sent]
    for record, (_, position, _, _) in zip(got, sent, strict=True):
        np.testing.assert_allclose(record.position, [v * CENTIMETRE for v in position], rtol=1e-6)
    assert len(got) - 1 <= tracker.bad_records <= len(got) + 1
    assert tracker.skipped_bytes >= sum(len(c) for c in GARBAGE_CHUNKS)


def test_numbers_outside_the_protocol_are_bad_records() -> None:
    q = (1.0, 0.0, 0.0, 0.0)
    good = encode_record(1, (1.0, 2.0, 3.0), q)
    assert len(good) == RECORD_SIZE and decode_record(good, 1.0) is not None
    for bad in (
        encode_record(5, (1.0, 2.0, 3.0), q),
        encode_record(0, (1.0, 2.0, 3.0), q),
        encode_record(1, (math.nan, 2.0, 3.0), q),
        encode_record(1, (1e6, 2.0, 3.0), q),
        encode_record(1, (1.0, 2.0, 3.0), (0.5, 0.0, 0.0, 0.0)),
        good[:-3] + b"2\r\n",
        good[:-1] + b"\r",
    ):
        assert decode_record(bad, 1.0) is None
    scanner = RecordScanner()
    for _ in range(20):
        assert scanner.feed(b"\xff" * 5000) == []
    assert scanner.feed(struct.pack("<3B", 0, 0, 0) + good)[0].station == 1
    assert scanner.bad_records == 1 and scanner.skipped_bytes == 100_003 and not scanner.buffer


def test_a_hang_up_raises_disconnected_after_every_record(emulator) -> None:
    emu = emulator("disconnect", disconnect_after=12)
    got: list = []
    with Fastrak(emu.address, **FAST) as tracker, pytest.raises(FastrakDisconnected):
        for _ in range(100_000):
            got.extend(tracker.read())
    assert emu.disconnected.is_set() and len(got) == 12
