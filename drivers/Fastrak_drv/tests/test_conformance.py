"""Conformance: the Fastrak decoder against records laid out as another implementation reads them,
not as our emulator writes them.

Source: VRPN 07.38 ``vrpn_Tracker_Fastrak.C``, ``get_report`` and ``report_length``. A binary
record is ``'0'``, the ASCII station digit, a status character (a space, or a letter for an
error), x, y, z as little-endian IEEE float32 in inches, the quaternion W, X, Y, Z as
little-endian float32, then the items the output list adds. For the Fastrak stylus (item 16) VRPN
reads two bytes, skipping the first and taking the second as an ASCII ``'0'``/``'1'``. VRPN ends
its output list with item 0 (a space); VR Juggler's ``FastrakStandalone`` and gadgetctl ask for
item 1 (CR LF) instead, so the records below end in CR LF. The encoder here is written from that
reading, independently of ``Fastrak_drv.emulator``.
"""

from __future__ import annotations

import struct

import pytest
from Fastrak_drv.standalone import INCH, RecordScanner

pytestmark = pytest.mark.timeout(10)

INCHES_TO_METRES = 0.0254  # VRPN_INCHES_TO_METERS


def vrpn_layout_record(
    station: int,
    inches: tuple[float, float, float],
    quaternion_wxyz: tuple[float, float, float, float],
    stylus: int,
    status: bytes = b" ",
) -> bytes:
    head = b"0" + str(station).encode() + status
    body = b"".join(struct.pack("<f", v) for v in (*inches, *quaternion_wxyz))
    return head + body + b" " + str(stylus).encode() + b"\r\n"


def test_records_in_vrpns_layout_decode_to_vrpns_metres_and_quaternion() -> None:
    half = 0.5**0.5
    records = [
        vrpn_layout_record(1, (10.0, -4.5, 30.25), (1.0, 0.0, 0.0, 0.0), 0),
        vrpn_layout_record(2, (-1.0, 2.0, -3.0), (half, 0.0, half, 0.0), 1),
        vrpn_layout_record(4, (0.0, 0.0, 72.0), (0.5, 0.5, 0.5, 0.5), 1),
    ]
    scanner = RecordScanner(scale=INCH)
    got = scanner.feed(b"".join(records))
    assert scanner.bad_records == 0
    assert [r.station for r in got] == [1, 2, 4]
    assert [r.stylus for r in got] == [0, 1, 1]
    expected_positions = [(10.0, -4.5, 30.25), (-1.0, 2.0, -3.0), (0.0, 0.0, 72.0)]
    for record, inches in zip(got, expected_positions, strict=True):
        assert record.position == pytest.approx([v * INCHES_TO_METRES for v in inches], rel=1e-6)
    assert got[1].quaternion == pytest.approx((half, 0.0, half, 0.0), rel=1e-6)
    assert got[2].quaternion == pytest.approx((0.5, 0.5, 0.5, 0.5), rel=1e-6)


def test_a_record_split_across_reads_and_junk_before_it_are_handled_as_vrpn_resyncs() -> None:
    record = vrpn_layout_record(3, (1.0, 2.0, 3.0), (1.0, 0.0, 0.0, 0.0), 1)
    scanner = RecordScanner(scale=INCH)
    assert scanner.feed(b"\x07junk" + record[:11]) == []
    got = scanner.feed(record[11:])
    assert [(r.station, r.stylus) for r in got] == [(3, 1)]
    assert scanner.skipped_bytes == 5
