"""The IS-900 protocol half against the emulator over a real pty pair, and its decoder."""

from __future__ import annotations

import math
import struct

import numpy as np
import pytest
from IS900_drv.emulator import GARBAGE_CHUNKS, IS900Emulator, encode_record
from IS900_drv.standalone import (
    INCH,
    IS900,
    RECORD_SIZE,
    IS900Disconnected,
    RecordScanner,
    StationSetup,
    decode_record,
    pose_matrix,
)

from gadgetctl.input.testing import gather, wait_until
from gadgetctl.input.testing.fixtures import emulator_fixture

pytestmark = pytest.mark.timeout(20)
FAST = {"settle": 0.0, "read_timeout": 2.0, "poll_timeout": 0.05, "poll_interval": 0.005}


emulator = emulator_fixture(IS900Emulator, rate=500.0)


def test_start_sequence_sets_binary_polled_mode_and_each_station(emulator) -> None:
    emu = emulator("idle")
    stations = (StationSetup(0, True), StationSetup(2, False))
    with IS900(emu.address, stations=stations, **FAST) as tracker:
        assert tracker.product == "9" and tracker.units == "inches"
        assert "IS-900" in tracker.firmware
        assert wait_until(lambda: len(emu.commands) >= 7)
    assert emu.commands[:4] == [b"c", b"MS", b"f", b"S"]
    # station 1 switched on (enabled), station 3 only given its output list (not enabled)
    assert emu.commands[4:] == [b"l1,1", b"O1,2,4,40,22,23,1", b"O3,2,4,40,22,23,1"]
    assert not emu.continuous and emu.binary


@pytest.mark.parametrize(("units", "scale"), [("inches", 0.0254), ("centimetres", 0.01)])
def test_records_decode_to_metres_degrees_and_buttons(emulator, units, scale) -> None:
    emu = emulator("buttons", units=units)
    with IS900(emu.address, stations=(StationSetup(0), StationSetup(1)), **FAST) as tracker:
        got = gather(tracker.read, 40)
    assert tracker.bad_records == 0 and tracker.skipped_bytes == 0
    sent = emu.sent[: len(got)]
    assert [r.station for r in got] == [s[0] for s in sent]
    for record, (_, position, euler, buttons, analog) in zip(got, sent, strict=True):
        np.testing.assert_allclose(record.position, [v * scale for v in position], rtol=1e-6)
        np.testing.assert_allclose(record.euler, euler, rtol=1e-6)
        assert record.digital == tuple(buttons >> k & 1 for k in range(8))
        assert set(record.digital) <= {0, 1}
        assert record.analog == analog
    assert any(r.buttons for r in got) and any(r.analog != (127, 127) for r in got)


def test_euler_angles_are_azimuth_about_z_then_elevation_then_roll() -> None:
    x, y, z = np.eye(3)
    np.testing.assert_allclose(pose_matrix((0, 0, 0), (90, 0, 0))[:3, :3] @ x, y, atol=1e-12)
    np.testing.assert_allclose(pose_matrix((0, 0, 0), (0, 90, 0))[:3, :3] @ x, -z, atol=1e-12)
    np.testing.assert_allclose(pose_matrix((0, 0, 0), (0, 0, 90))[:3, :3] @ y, z, atol=1e-12)
    # R = Rz(azimuth) Ry(elevation): x goes to -z by the elevation, which the azimuth keeps
    np.testing.assert_allclose(pose_matrix((0, 0, 0), (90, 90, 0))[:3, :3] @ x, -z, atol=1e-12)
    m = pose_matrix((1.0, 2.0, 3.0), (30, 20, 10))
    np.testing.assert_allclose(m[:3, 3], (1, 2, 3))
    np.testing.assert_allclose(m[:3, :3] @ m[:3, :3].T, np.eye(3), atol=1e-12)


def test_garbage_is_skipped_whole_runs_at_a_time_and_counted(emulator) -> None:
    emu = emulator("garbage")
    with IS900(emu.address, stations=(StationSetup(0), StationSetup(1)), **FAST) as tracker:
        got = gather(tracker.read, 60)
    sent = emu.sent[: len(got)]
    assert [(r.station, r.buttons, r.analog) for r in got] == [(s[0], s[3], s[4]) for s in sent]
    for record, (_, position, _, _, _) in zip(got, sent, strict=True):
        np.testing.assert_allclose(record.position, [v * INCH for v in position], rtol=1e-6)
    # one junk run before each record, each counted once
    assert tracker.records == len(got)
    assert len(got) - 1 <= tracker.bad_records <= len(got) + 1
    assert tracker.skipped_bytes >= sum(len(c) for c in GARBAGE_CHUNKS)


def test_bad_records_are_numbers_no_tracker_sends() -> None:
    good = encode_record(0, (1.0, 2.0, 3.0), (10.0, 20.0, 30.0), 0b1010, (3, 250))
    assert len(good) == RECORD_SIZE
    record = decode_record(good, INCH)
    assert record is not None and record.digital == (0, 1, 0, 1, 0, 0, 0, 0)
    assert decode_record(good, INCH, frozenset({1})) is None  # a station not configured
    nan = good[:3] + struct.pack("<f", math.nan) + good[7:]
    huge = good[:3] + struct.pack("<f", 1e9) + good[7:]
    angle = good[:15] + struct.pack("<f", 361.0) + good[19:]
    unframed = good[:-1] + b"\n\n"
    for bad in (nan, huge, angle, unframed, b"0\xff" + good[2:]):
        assert decode_record(bad, INCH) is None


def test_a_long_junk_run_is_one_bad_record_and_a_bounded_buffer() -> None:
    scanner = RecordScanner(stations=frozenset({0}))
    good = encode_record(0, (1.0, 2.0, 3.0), (0.0, 0.0, 0.0))
    for _ in range(50):
        assert scanner.feed(b"\x01" * 10_000) == []
    assert len(scanner.buffer) == 0
    assert [r.station for r in scanner.feed(good + good[:10])] == [0]
    assert scanner.feed(good[10:])[0].position == pytest.approx((0.0254, 0.0508, 0.0762))
    assert scanner.bad_records == 1 and scanner.skipped_bytes == 500_000 and scanner.records == 2


def test_a_hang_up_raises_disconnected(emulator) -> None:
    emu = emulator("disconnect", disconnect_after=5)
    with IS900(emu.address, stations=(StationSetup(0), StationSetup(1)), **FAST) as tracker:
        got: list = []
        with pytest.raises(IS900Disconnected):
            for _ in range(10_000):
                got.extend(tracker.read())
    assert emu.disconnected.is_set() and len(got) == 10  # 5 polls of 2 stations, all read


def test_a_silent_line_counts_as_lost(emulator) -> None:
    emu = emulator("idle", stations_on=())  # the tracker reports no station
    tracker = IS900(emu.address, stations=(StationSetup(3, False),), silence_timeout=0.2, **FAST)
    with tracker, pytest.raises(IS900Disconnected, match="no data"):
        wait_until(lambda: False, timeout=5, step=tracker.read)
