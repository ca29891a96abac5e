"""Conformance: the Wanda driver against packets laid out as VRPN's Wanda server reads them,
played on a pty by a fixture line (not by our emulator).

Source: VRPN ``vrpn_Wanda.C`` (``vrpn_Wanda::mainloop``), read through the ``fetch`` tool:

* on opening the Wanda says ``M3``; VRPN reads those two bytes first;
* a packet starts at a byte with bit 6 set; X = ``byte1 | (byte0 & 3) << 6`` and
  Y = ``byte2 | (byte0 & 12) << 4`` as signed chars, reported as ``-X / 34`` and ``Y / 34``
  clamped to -1..1; bit 4 of byte 0 is the blue button, bit 5 the red one; a 4th byte
  without bit 6 is the yellow (middle) button, pressed when non-zero;
* a Wanda at rest sends nothing (VRPN's comment), and VRPN centres the valuators after 0.2 s
  without a packet.

VR Juggler numbers the buttons differently (``WandaStandalone.cpp``: bit 5 is its button 0,
bit 4 its button 2, the 4th byte button 1), and reports the raw -34..34 instead of VRPN's
-1..1: the expected values below are VRPN's, renumbered and scaled by 34 for that.
"""

from __future__ import annotations

import pytest
from Wanda_drv.standalone import Wanda

from gadgetctl.emulation.testing import FixtureLine
from gadgetctl.input.testing import gather

pytestmark = pytest.mark.timeout(20)


def vrpn_layout(x: int, y: int, blue: int, red: int, yellow: int | None = None) -> bytes:
    """A packet that vrpn_Wanda reads as X = x, Y = y (signed chars, as sent) and the buttons
    given; ``yellow`` None sends the 3-byte form."""
    xb, yb = x & 0xFF, y & 0xFF
    head = 0x40 | blue << 4 | red << 5 | (yb >> 6) << 2 | (xb >> 6)
    packet = bytes((head, xb & 0x3F, yb & 0x3F))
    return packet if yellow is None else packet + bytes((0x20 if yellow else 0x00,))


def vrpn_reading(packet: bytes) -> tuple[tuple[float, float], dict[str, int]]:
    """What vrpn_Wanda reports for a packet: valuators and buttons by colour."""
    x = ((packet[1] | (packet[0] & 3) << 6) + 128) % 256 - 128
    y = ((packet[2] | (packet[0] & 12) << 4) + 128) % 256 - 128
    xd, yd = max(-1.0, min(1.0, -x / 34.0)), max(-1.0, min(1.0, y / 34.0))
    buttons = {"blue": packet[0] >> 4 & 1, "red": packet[0] >> 5 & 1}
    if len(packet) == 4:
        buttons["yellow"] = int(packet[3] != 0)
    return (xd, yd), buttons


PACKETS = [
    vrpn_layout(0, 0, blue=0, red=1),
    vrpn_layout(12, -7, blue=1, red=0, yellow=1),
    vrpn_layout(-40, 90, blue=0, red=0, yellow=0),  # beyond 34: clamped
    vrpn_layout(127, -128, blue=1, red=1),
    vrpn_layout(-1, 1, blue=0, red=0),
]


def test_packets_read_as_vrpn_reads_them_with_vr_juggler_numbering() -> None:
    with FixtureLine() as line, Wanda(line.address, reset_time=0.0) as wanda:
        line.feed(b"M3" + b"".join(PACKETS))  # the hello once the line is open, then packets
        got = gather(wanda.read, len(PACKETS))
    assert wanda.scanner.bad_records == 0 and wanda.scanner.hellos == 1
    for packet, decoded in zip(PACKETS, got, strict=True):
        (xd, yd), buttons = vrpn_reading(packet)
        assert decoded.axes == (round(xd * 34), round(yd * 34))
        assert decoded.buttons == (buttons["red"], buttons.get("yellow", 0), buttons["blue"])


def test_a_wanda_at_rest_is_silence_not_a_lost_line() -> None:
    with FixtureLine() as line, Wanda(line.address, reset_time=0.0) as wanda:
        line.feed(PACKETS[1])
        assert gather(wanda.read, 1)[0].buttons == (0, 1, 1)
        quiet = [wanda.read() for _ in range(60)]  # 60 reads of 20 ms: over a second of rest
        assert quiet == [[]] * 60
        line.feed(PACKETS[0])  # then the red button
        assert gather(wanda.read, 1)[0].buttons == (1, 0, 0)
