"""Conformance: the 5DT DataGlove driver against the start and the packets as VRPN's and VR
Juggler's 5DT drivers describe them, played on a pty by a fixture line (not by our emulator).

Sources:

* VRPN ``vrpn_Analog_5dt.C`` (read through the ``fetch`` tool): a wired glove is sent ``A``
  and answers 85 (0x55); then ``G``, answered with 32 bytes starting 66, 82 (``BR``), the
  version in bytes 2 and 3, bit 0 of byte 4 set for a right glove, bit 4 of byte 5 when pitch
  and roll are fitted, the name from byte 16; then ``D`` for streaming. A report is 128
  (0x80), thumb..pinky (``/ 255``), pitch and roll (``180 * b / 255``), the checksum: 9 bytes,
  "the official doc ... says we should get only 9 bytes", but VRPN also met 10-byte reports
  ending in 0x55 from wired gloves, and wireless gloves (9600 baud) ending every report in
  0x40 or 0x01 (0x01: a right hand).
* VR Juggler ``DataGloveStandalone.cpp``: the checksum is the XOR of the seven data bytes, and
  a 10th byte is kept as the capability (its comment: 0 right hand, 6 left hand).

The packets and the answers below are packed here from those descriptions.
"""

from __future__ import annotations

import pytest
from DataGlove_drv.standalone import DataGlove

from gadgetctl.emulation.testing import FixtureLine
from gadgetctl.input.testing import gather

pytestmark = pytest.mark.timeout(20)


def report(thumb: int, index: int, middle: int, ring: int, pinky: int, pitch: int, roll: int):
    """The 9 bytes VRPN expects (header, seven data bytes, VR Juggler's XOR checksum)."""
    data = bytes((thumb, index, middle, ring, pinky, pitch, roll))
    check = 0
    for value in data:
        check ^= value
    return b"\x80" + data + bytes((check,))


def vrpn_channels(packet: bytes) -> tuple[float, ...]:
    """VRPN's channels 1..7 of a report: five flexures, pitch and roll in degrees."""
    return (*(b / 255.0 for b in packet[1:6]), 180 * packet[6] / 255.0, 180 * packet[7] / 255.0)


# Fist, open hand, pointing, and a rolled wrist, as data bytes
HANDS = [
    (230, 240, 235, 240, 220, 128, 128),
    (10, 15, 12, 20, 18, 128, 128),
    (200, 20, 240, 235, 220, 100, 140),
    (128, 128, 128, 128, 128, 0, 255),
]
INFO_RIGHT = b"BR" + bytes((2, 1, 1, 0x10)) + bytes(10) + b"5DT Data Glove 5".ljust(16, b"\0")


def test_a_wired_glove_is_started_with_a_g_d_and_its_9_byte_reports_read() -> None:
    stream = b"".join(report(*hand) for hand in HANDS)
    with FixtureLine({b"A": b"\x55", b"G": INFO_RIGHT, b"D": stream}) as line:
        with DataGlove(line.address, sample_timeout=0.02, reply_timeout=2.0) as glove:
            got = gather(glove.poll, len(HANDS))
        assert bytes(line.received) == b"AGD"
    assert glove.info is not None and glove.info.right and glove.info.pitch_roll
    assert glove.info.version == (2, 1) and glove.info.name == "5DT Data Glove 5"
    for packet, sample in zip((report(*h) for h in HANDS), got, strict=True):
        assert (*sample.flexure, sample.pitch, sample.roll) == pytest.approx(vrpn_channels(packet))
    assert [s.capability for s in got] == [0] * len(HANDS)  # right hand, VR Juggler's value
    assert glove.scanner.bad_records == 0


@pytest.mark.parametrize(
    ("tenth", "hand"),
    [
        (0x55, "right"),  # VRPN: wired gloves seen ending reports in 0x55
        (0x01, "right"),  # VRPN: wireless, right hand
        (0x40, "left"),  # VRPN: wireless, left hand
        (0x00, "right"),  # VR Juggler: right hand
        (0x06, "left"),  # VR Juggler: left hand
    ],
)
def test_ten_byte_reports_of_every_kind_are_read(tenth: int, hand: str) -> None:
    stream = b"".join(report(*h) + bytes((tenth,)) for h in HANDS)
    # such a glove streams whether asked or not: its reports come after the driver's A (the
    # line plays them then, so that none is lost to the open)
    with FixtureLine({b"A": stream}) as line:
        with DataGlove(line.address, sample_timeout=0.02, reply_timeout=2.0) as glove:
            got = gather(glove.poll, len(HANDS))
        assert bytes(line.received) == b"A"  # it streamed: no G, no D
    assert [s.capability for s in got] == [tenth] * len(HANDS)
    assert {s.hand for s in got} == {hand}
    assert [s.flexure[1] for s in got] == pytest.approx([h[1] / 255 for h in HANDS])
    assert glove.scanner.bad_records == 0 and glove.scanner.skipped_bytes == 0
