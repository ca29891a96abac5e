"""Conformance: the Logitech 3D mouse decoder against reports packed as another implementation
reads them, not as our emulator writes them.

Source: VRPN 07.38 ``vrpn_Tracker_3DMouse.C``, ``get_report``: a 16-byte report; byte 0 carries
the status and button bits (32 out of range, 8 suspend, 4 left, 2 middle, 1 right); bytes 1..9
are X, Y, Z as 21-bit two's complement numbers, 7 bits a byte, high part first, the sign in bit
0x40 of the first byte (VRPN extends it with 0xFFE00000), in thousandths of an inch (VRPN:
``a / 100000.0 * 2.54`` metres); bytes 10..15 are three 14-bit angles, 7 + 7 bits, in fortieths of
a degree. The packer below is the inverse of that reader, written here from it.
"""

from __future__ import annotations

import pytest
from ThreeDMouse_drv.standalone import ReportScanner, decode_report

pytestmark = pytest.mark.timeout(10)

LEFT, MIDDLE, RIGHT, SUSPEND, OUT_OF_RANGE = 4, 2, 1, 8, 32


def seven_bit_groups(value: int, groups: int) -> list[int]:
    return [(value >> (7 * (groups - 1 - k))) & 0x7F for k in range(groups)]


def logitech_report(
    flags: int, thousandths: tuple[int, int, int], fortieths: tuple[int, ...]
) -> bytes:
    out = [0x80 | flags]
    for value in thousandths:
        out += seven_bit_groups(value & 0x1FFFFF, 3)  # 21-bit two's complement
    for value in fortieths:
        out += seven_bit_groups(value, 2)
    return bytes(out)


def vrpn_metres(thousandths: int) -> float:
    return thousandths / 100000.0 * 2.54


def test_positions_angles_and_buttons_read_as_vrpn_reads_them() -> None:
    position = (12_345, -54_321, -1)
    angles = (40 * 90, 40 * 45 + 20, 14_399)
    report = logitech_report(LEFT | RIGHT, position, angles)
    decoded = decode_report(report)
    assert decoded is not None
    assert decoded.position == pytest.approx([vrpn_metres(v) for v in position], abs=1e-12)
    assert decoded.angles == pytest.approx((90.0, 45.5, 14_399 / 40))
    assert decoded.buttons == (1, 0, 1)  # left, middle, right


def test_the_extremes_of_the_21_bit_range_and_the_status_bits() -> None:
    low, high = -(1 << 20), (1 << 20) - 1
    report = logitech_report(MIDDLE | SUSPEND | OUT_OF_RANGE, (low, high, 0), (0, 0, 0))
    decoded = decode_report(report)
    assert decoded is not None
    assert decoded.position == pytest.approx((vrpn_metres(low), vrpn_metres(high), 0.0))
    assert decoded.buttons == (0, 1, 0)
    assert decoded.status & OUT_OF_RANGE and decoded.status & SUSPEND


def test_a_stream_of_reports_with_a_cut_one_between() -> None:
    first = logitech_report(0, (1, 2, 3), (4, 5, 6))
    second = logitech_report(LEFT, (-1, -2, -3), (7, 8, 9))
    scanner = ReportScanner()
    got = scanner.feed(first + second[:7] + second)
    assert [r.buttons for r in got] == [(0, 0, 0), (1, 0, 0)]
    assert got[1].position == pytest.approx([vrpn_metres(v) for v in (-1, -2, -3)])
    assert scanner.skipped_bytes == 7
