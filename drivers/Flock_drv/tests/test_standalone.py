"""The Flock of Birds protocol half against the emulator over a real pty pair, and its decoder."""

from __future__ import annotations

import math

import numpy as np
import pytest
from Flock_drv.emulator import FlockEmulator, encode_record, encode_word, pose
from Flock_drv.standalone import (
    ADDRESSING_FROM_CONFIG,
    POS_ANGLES,
    POS_QUATERNION,
    SUPER_EXPANDED,
    Flock,
    FlockDisconnected,
    RecordScanner,
    decode_word,
    euler_matrix,
    fbb_prefix,
)

from gadgetctl.input.testing import gather, wait_until
from gadgetctl.input.testing.fixtures import emulator_fixture

pytestmark = pytest.mark.timeout(20)
FAST = {"reset_time": 0.0, "examine_delay": 0.0, "read_timeout": 2.0, "poll_interval": 0.005}
WORD = 4 / 32768  # one step of a 14-bit word


emulator = emulator_fixture(FlockEmulator, rate=300.0)


def expected_matrix(position: tuple[float, ...], angles: tuple[float, ...]) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = euler_matrix(*angles)
    m[:3, 3] = position
    return m


def test_words_are_14_bits_low_byte_first() -> None:
    assert decode_word(0x00, 0x40) == -1.0  # MS 0x40 -> bit 15
    assert decode_word(0x7F, 0x3F) == pytest.approx(1.0 - WORD)
    assert decode_word(0x01, 0x00) == pytest.approx(WORD)
    for value in (-0.75, -0.1, 0.0, 0.3333, 0.9):
        ls, ms = encode_word(value)
        assert abs(decode_word(ls, ms) - value) <= WORD


def test_addressing_prefixes_and_the_super_expanded_fix() -> None:
    assert fbb_prefix(3) == b"\xf3" and fbb_prefix(17, 1) == b"\xe1"
    assert fbb_prefix(100, SUPER_EXPANDED) == b"\xa0\x64"
    # the definition's "Super Extended" (2) is the protocol's 3
    assert ADDRESSING_FROM_CONFIG[2] == SUPER_EXPANDED == 3
    with pytest.raises(ValueError):
        fbb_prefix(20)  # normal addressing reaches 15


def test_group_mode_start_sequence_and_position_quaternion_records(emulator) -> None:
    emu = emulator("motion", birds=3)
    with Flock(emu.address, hemisphere=5, **FAST) as flock:
        assert flock.revision == (3, 67) and flock.model == "6DFOB"
        assert flock.sensors == [1, 2, 3] and not flock.standalone
        assert flock.scale_inches == 36.0
        got = gather(flock.read, 30)
    assert emu.group and emu.auto_configured == 3
    assert emu.formats == {1: POS_QUATERNION, 2: POS_QUATERNION, 3: POS_QUATERNION}
    assert set(emu.hemispheres.values()) == {b"\x06\x00"}  # Right
    assert [t for t, c in emu.addressed if c == b"O\x00"] == [1, 2, 3]  # each bird's status
    # report rate and stream last ('?' follows once the driver closed, whenever the emulator
    # reads it)
    start = emu.commands.index(b"@")
    assert emu.commands[start - 1 : start + 1] == [b"Q", b"@"]
    assert emu.commands[start + 1 :] in ([], [b"?"])
    # records come in address order, one per bird per frame, none lost
    assert [r.address for r in got[:6]] == [1, 2, 3, 1, 2, 3]
    for record, (bird, position, angles) in zip(got, emu.sent[: len(got)], strict=True):
        assert record.address == bird + 1
        assert record.quaternion is not None
        # position in feet (36-inch scale: 3 ft full scale), the quaternion used as sent
        np.testing.assert_allclose(record.matrix(), expected_matrix(position, angles), atol=2e-3)


def test_position_angles_records_and_angle_order(emulator) -> None:
    emu = emulator("idle", birds=2)
    with Flock(emu.address, output_format=POS_ANGLES, **FAST) as flock:
        got = gather(flock.read, 4)
    for record in got:
        _bird, position, angles = emu.sent[record.address - 1]
        assert record.angles == pytest.approx(angles, abs=180 * WORD)  # azimuth, elevation, roll
        assert record.position == pytest.approx(position, abs=3 * WORD)


def test_standalone_bird_has_no_prefix_and_no_address_byte(emulator) -> None:
    emu = emulator("motion", birds=1, master=0)
    with Flock(emu.address, **FAST) as flock:
        assert flock.standalone and flock.sensors == [0]
        got = gather(flock.read, 10)
    assert not emu.group and all(target is None for target, _ in emu.addressed)
    assert all(r.address == 0 for r in got)
    np.testing.assert_allclose(got[0].matrix(), expected_matrix(*emu.sent[0][1:]), atol=2e-3)


def test_extended_range_transmitter_scales_to_144_inches(emulator) -> None:
    emu = emulator("idle", birds=2, extended_range=True)
    with Flock(emu.address, **FAST) as flock:
        assert flock.extended_range and flock.scale_inches == 144.0
        assert flock.sensors == [2, 3]  # the controller at address 1 has no sensor
        got = gather(flock.read, 2)
    assert got[0].position == pytest.approx(emu.sent[0][1], abs=12 * WORD)


def test_72_inch_scaling(emulator) -> None:
    emu = emulator("idle", birds=1, scale_inches=72)
    with Flock(emu.address, **FAST) as flock:
        assert flock.scale_inches == 72.0
        got = gather(flock.read, 1)
    assert got[0].position == pytest.approx(emu.sent[0][1], abs=6 * WORD)


def test_garbage_is_skipped_by_whole_runs_and_counted(emulator) -> None:
    emu = emulator("garbage", birds=2)
    with Flock(emu.address, **FAST) as flock:
        got = gather(flock.read, 40)
        assert flock.bad_records >= 20 and flock.skipped_bytes > flock.bad_records
    assert [r.address for r in got[:4]] == [1, 2, 1, 2]
    for record, (bird, position, angles) in zip(got, emu.sent[: len(got)], strict=True):
        assert record.address == bird + 1
        np.testing.assert_allclose(record.matrix(), expected_matrix(position, angles), atol=2e-3)


def test_scanner_bounds_and_junk_runs() -> None:
    scale = 3.0
    good = encode_record(POS_QUATERNION, (1.0, -0.5, 0.25), (30.0, 10.0, -5.0), scale, 1)
    scanner = RecordScanner(POS_QUATERNION, scale, True, frozenset({1, 2}))
    junk = bytes(range(0x00, 0x7F)) * 10  # one run without a phasing bit
    wrong_address = good[:-1] + b"\x09"
    out = scanner.feed(junk + good + wrong_address + good)
    assert len(out) == 2 and scanner.records == 2
    assert scanner.bad_records == 2  # the run, then the record from address 9
    assert scanner.skipped_bytes == len(junk) + len(wrong_address)
    assert not scanner.buffer
    q = out[0].quaternion
    assert q is not None and math.isclose(sum(v * v for v in q), 1.0, abs_tol=1e-3)


def test_lost_line_raises_disconnected(emulator) -> None:
    emu = emulator("disconnect", birds=2, disconnect_after=10)
    with Flock(emu.address, **FAST) as flock:
        got: list = []
        with pytest.raises(FlockDisconnected):
            wait_until(lambda: False, timeout=5, step=lambda: got.extend(flock.read()))
    assert len(got) == 20 and emu.disconnected.is_set()


def test_motion_scenario_moves(emulator) -> None:
    assert pose("motion", 0, 0) != pose("motion", 0, 10)
    assert pose("idle", 0, 0) == pose("idle", 0, 10)
