"""Conformance: the Interface Box decoder against packets built from another implementation's
reading of the HCI protocol, not from our emulator.

Source: VR Juggler's ``Immersion/IBox/IBoxStandalone.cpp`` (Immersion's HCI library as ported
into Gadgeteer), ``parsePacket``: after the echoed command byte, one button byte (bit k = button k,
buttons 0..6); with the timer bit (0x20) two 7-bit bytes, high first; with analog bits (0x0C), the
analog bytes (each value's upper seven bits) and then one byte carrying the low bits (0x40 for
analog 0 down to 0x01 for analog 6; analog 7 has none); then two 7-bit bytes per encoder, high
first. The packer below is the inverse of that parser, written here from it.
"""

from __future__ import annotations

import pytest
from IBox_drv.standalone import QUERY, PacketScanner, decode_packet, packet_size

pytestmark = pytest.mark.timeout(10)

TIMER_BIT = 0x20
ANALOG_FIELD = {2: 0x04, 4: 0x08, 8: 0x0C}
ENCODER_FIELD = {0: 0, 2: 1, 3: 2, 6: 3}


def hci_packet(
    buttons: list[int], analogs: list[int], timer: int | None = None, encoders: list[int] = ()
) -> tuple[int, bytes]:
    """(command byte, the box's answer) for these values, laid out as parsePacket reads them."""
    command = ANALOG_FIELD.get(len(analogs), 0) | ENCODER_FIELD[len(encoders)]
    if timer is not None:
        command |= TIMER_BIT
    out = bytearray([command | 0x80, sum(bit << k for k, bit in enumerate(buttons))])
    if timer is not None:
        out += bytes([timer >> 7 & 0x7F, timer & 0x7F])
    if analogs:
        out += bytes(value >> 1 for value in analogs)
        out.append(sum((value & 1) << (6 - k) for k, value in enumerate(analogs[:7])))
    for word in encoders:
        out += bytes([word >> 7 & 0x7F, word & 0x7F])
    return command, bytes(out)


def test_gadgeteers_query_buttons_and_four_analogs() -> None:
    command, packet = hci_packet([1, 0, 1, 1, 0, 0, 1], [0, 255, 128, 77])
    assert command == QUERY and len(packet) == packet_size(QUERY) == 7
    decoded = decode_packet(packet)
    assert decoded is not None
    assert decoded.buttons == (1, 0, 1, 1, 0, 0, 1)
    assert decoded.analog == (0, 255, 128, 77)  # odd values need the low-bit byte


@pytest.mark.parametrize(
    ("analogs", "timer", "encoders"),
    [
        ([1, 3, 5, 7, 9, 11, 13, 255], 0x3FFF, [0, 16383]),
        ([200, 201], None, [1234, 5678, 42, 0, 9999, 16000]),
        ([], 5, [7, 8, 9]),
    ],
)
def test_every_field_combination_of_the_command_byte(
    analogs: list[int], timer: int | None, encoders: list[int]
) -> None:
    command, packet = hci_packet([0, 1, 0, 0, 0, 0, 0], analogs, timer, encoders)
    decoded = decode_packet(packet, command)
    assert decoded is not None
    # analog 7 has no low bit in the protocol: its value is even
    expected = tuple(v & ~1 if k == 7 else v for k, v in enumerate(analogs))
    assert decoded.analog == expected
    assert decoded.timer == timer
    assert decoded.encoders == tuple(encoders)
    assert decoded.buttons[1] == 1


def test_junk_between_packets_is_skipped() -> None:
    _, first = hci_packet([1, 0, 0, 0, 0, 0, 0], [10, 20, 30, 40])
    _, second = hci_packet([0, 0, 0, 0, 0, 0, 1], [50, 60, 70, 80])
    scanner = PacketScanner()
    got = scanner.feed(first + b"\x01\x02" + second)
    assert [p.analog for p in got] == [(10, 20, 30, 40), (50, 60, 70, 80)]
    assert scanner.skipped_bytes == 2
