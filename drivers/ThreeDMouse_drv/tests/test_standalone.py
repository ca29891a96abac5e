"""The 3D mouse protocol half against the emulator over a real pty pair, and its decoder."""

from __future__ import annotations

import numpy as np
import pytest
from ThreeDMouse_drv.emulator import GARBAGE_CHUNKS, ThreeDMouseEmulator, encode_report
from ThreeDMouse_drv.standalone import (
    INCH,
    REPORT_SIZE,
    ReportScanner,
    ThreeDMouse,
    ThreeDMouseDisconnected,
    ThreeDMouseProtocolError,
    decode_report,
    rotation_xyz,
)

from gadgetctl.input.testing import gather
from gadgetctl.input.testing.fixtures import emulator_fixture

pytestmark = pytest.mark.timeout(20)
FAST = {
    "demand_wait": 0.0,
    "reset_wait": 0.0,
    "diagnostic_wait": 0.0,
    "read_timeout": 2.0,
    "poll_timeout": 0.05,
    "poll_interval": 0.005,
}


emulator = emulator_fixture(ThreeDMouseEmulator, rate=500.0)


def test_start_resets_checks_diagnostics_and_chooses_modes(emulator) -> None:
    emu = emulator("idle")
    with ThreeDMouse(emu.address, **FAST) as mouse:
        assert mouse.character_format in ("8N2", "8N1")  # a pty may not do two stop bits
        gather(mouse.read, 1)
    assert emu.commands[:5] == [b"*D", b"*R", b"*\x05", b"*H", b"*G"]
    assert emu.commands[5] == b"*d"


def test_wrong_diagnostics_fail_the_start(emulator) -> None:
    emu = emulator("idle", diagnostic=b"\x00\x3f")
    mouse = ThreeDMouse(emu.address, **FAST)
    with pytest.raises(ThreeDMouseProtocolError, match="diagnostics"):
        mouse.open()
    assert not mouse.is_open


def test_reports_decode_to_metres_degrees_and_buttons(emulator) -> None:
    for scenario in ("motion", "buttons"):
        emu = emulator(scenario)
        with ThreeDMouse(emu.address, **FAST) as mouse:
            got = gather(mouse.read, 30)
        assert mouse.bad_records == 0
        for report, (position, angles, flags) in zip(got, emu.sent, strict=False):
            np.testing.assert_allclose(
                report.position, [v / 1000 * INCH for v in position], atol=1e-12
            )
            np.testing.assert_allclose(report.angles, [a / 40 for a in angles])
            assert report.buttons == (
                int(bool(flags & 4)),
                int(bool(flags & 2)),
                int(bool(flags & 1)),
            )
        if scenario == "buttons":
            assert {r.buttons for r in got} >= {(1, 0, 0), (0, 1, 0), (0, 0, 1), (0, 0, 0)}
        else:
            assert any(r.position[1] < 0 for r in got) and any(r.position[1] > 0 for r in got)


def test_angles_rotate_and_no_longer_overwrite_the_translation() -> None:
    report = decode_report(encode_report((-1000, 2000, -(1 << 20)), (40 * 90, 0, 0), 0x04))
    assert report is not None
    assert report.position == pytest.approx((-INCH, 2 * INCH, -(1 << 20) / 1000 * INCH))
    m = report.matrix()
    np.testing.assert_allclose(m[:3, 3], report.position)  # the translation stays
    x, y, z = np.eye(3)
    np.testing.assert_allclose(m[:3, :3] @ y, z, atol=1e-12)  # 90 degrees about x
    np.testing.assert_allclose(rotation_xyz(0, 90, 0) @ z, x, atol=1e-12)
    np.testing.assert_allclose(rotation_xyz(0, 0, 90) @ x, y, atol=1e-12)
    # order Rx Ry Rz: z is turned by Ry (to x), then by Rx (x stays)
    np.testing.assert_allclose(rotation_xyz(90, 90, 0) @ z, x, atol=1e-12)
    assert report.buttons == (1, 0, 0)


def test_garbage_is_skipped_and_counted(emulator) -> None:
    emu = emulator("garbage")
    with ThreeDMouse(emu.address, **FAST) as mouse:
        got = gather(mouse.read, 40)
    for report, (position, _, _) in zip(got, emu.sent, strict=False):
        np.testing.assert_allclose(report.position, [v / 1000 * INCH for v in position], atol=1e-12)
    assert len(got) == len(emu.sent[: len(got)])
    assert mouse.bad_records >= len(got) - 1 and mouse.skipped_bytes >= sum(
        len(c) for c in GARBAGE_CHUNKS
    )


def test_bad_reports_are_numbers_no_mouse_sends() -> None:
    good = encode_report((1, 2, 3), (0, 0, 0))
    assert len(good) == REPORT_SIZE and decode_report(good) is not None
    assert decode_report(good[:10] + bytes([0x7F, 0x7F]) + good[12:]) is None  # beyond a turn
    assert decode_report(good[:5] + b"\x80" + good[6:]) is None  # a flag byte inside
    assert decode_report(b"\x00" + good[1:]) is None  # no flag byte first
    scanner = ReportScanner()
    for _ in range(10):
        assert scanner.feed(b"\x01" * 10_000) == []
    assert [r.position for r in scanner.feed(b"\x80\x01" + good)] == [decode_report(good).position]
    assert scanner.bad_records == 1 and scanner.skipped_bytes == 100_002 and not scanner.buffer


def test_a_hang_up_raises_disconnected_after_every_report(emulator) -> None:
    emu = emulator("disconnect", disconnect_after=12)
    got: list = []
    with ThreeDMouse(emu.address, **FAST) as mouse, pytest.raises(ThreeDMouseDisconnected):
        for _ in range(100_000):
            got.extend(mouse.read())
    assert emu.disconnected.is_set() and len(got) == 12
