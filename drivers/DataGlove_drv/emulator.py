"""A 5DT DataGlove on a pseudo-terminal, independent of gadgetctl's input manager (it uses
only the shared emulator scaffolding, :mod:`gadgetctl.emulation`).

The glove streams 10-byte packets at ``rate`` per second once a driver has the line open
(the first packet waits in the line until then; opening the port discards it):

``idle``        a relaxed hand that does not move (packets keep coming)
``motion``      the fingers close and open in turn, the hand pitches and rolls
``buttons``     the hand steps through fist, point and open-hand gestures
``garbage``     motion with junk between packets: stray bytes, false headers, bad checksums
``disconnect``  ``disconnect_after`` packets of motion, then the line is hung up
"""

from __future__ import annotations

import math
import os
import sys

from gadgetctl.emulation.device import STANDARD_SCENARIOS, PtyDeviceEmulator, pty_parser, run_pty

# The emulator keeps its own copy of the wire format so that a mistake in the driver cannot be
# mirrored here and go unnoticed by the tests.
SCENARIOS = STANDARD_SCENARIOS
DEFAULT_LINK = "/tmp/gadgetctl-dataglove"
RIGHT, LEFT = 0, 6
#: Flexure bytes (thumb..pinky) of the ``buttons`` scenario: fist, pointing, open hand.
POSES = ((230, 240, 240, 235, 220), (200, 20, 240, 235, 220), (10, 15, 12, 20, 18))
GARBAGE = (
    b"\x13\x37",  # stray bytes
    b"\x80\x01\x02",  # a header and a packet cut short
    b"\x80" + bytes(7) + b"\x55\x00",  # a bad checksum
    b"\x80" + bytes(8) + b"\x03",  # a capability no glove has
    bytes(range(0x70, 0x90)),  # a run holding headers
)

Packet = tuple[int, ...]  # the nine bytes after the header


def encode_packet(data: tuple[int, ...], capability: int = RIGHT) -> bytes:
    """Header, seven data bytes, their XOR and the capability byte."""
    check = 0
    for value in data:
        check ^= value
    return bytes([0x80, *data, check, capability])


def pose(scenario: str, step: int) -> tuple[int, ...]:
    """The seven data bytes (five flexures, pitch, roll) of a step."""
    if scenario == "idle":
        return (40, 40, 40, 40, 40, 128, 128)
    if scenario == "buttons":
        return (*POSES[step // 4 % len(POSES)], 128, 128)
    fingers = tuple(round(127.5 + 127 * math.sin(step / 8 + k)) for k in range(5))
    # the thumb also carries the step, so consecutive packets differ
    fingers = ((fingers[0] & 0xF0) | (step & 0x0F), *fingers[1:])
    return (
        *fingers,
        round(127.5 + 120 * math.sin(step / 20)),
        round(127.5 + 120 * math.cos(step / 25)),
    )


class DataGloveEmulator(PtyDeviceEmulator):
    """The glove's side of the line on a pty pair. ``sent`` lists the data bytes of every good
    packet sent (not the first one, which waits for a driver and is discarded at its open)."""

    DEVICE = "DataGlove"
    CATCH_UP = 0.05  # catch up at most a few packets, never a burst after a stall

    def __init__(
        self,
        scenario: str = "motion",
        rate: float = 100.0,
        *,
        hand: int = RIGHT,
        disconnect_after: int = 5,
        linger: float = 1.0,
        link: str | os.PathLike[str] | None = None,
    ) -> None:
        super().__init__(
            scenario, rate, disconnect_after=disconnect_after, linger=linger, link=link, drain=0.5
        )
        self.hand = hand
        self.sent: list[tuple[int, ...]] = []
        self.probe = pose(scenario, 0)  # the packet sent before a driver is there
        self._step = 0

    def on_open(self) -> None:
        # waits for a reader; opening the port discards it, unless it was still on its way
        self.write(encode_packet(self.probe, self.hand))

    def sending(self) -> bool:
        if not self.streaming.is_set() and self.probe_taken():
            self.begin_sending()  # read or discarded: a driver is there
        return self.streaming.is_set()

    def emit(self) -> None:
        step = self._step
        if self.scenario == "disconnect" and step >= self.disconnect_after:
            self.hang_up_once_read()  # a pty drops unread input on hang-up
            return
        self._step += 1
        data = pose(
            "motion" if self.scenario in ("garbage", "disconnect") else self.scenario, step + 1
        )
        junk = GARBAGE[step % len(GARBAGE)] if self.scenario == "garbage" else b""
        self.sent.append(data)
        self.write(junk + encode_packet(data, self.hand))


def main(argv: list[str] | None = None) -> int:
    parser = pty_parser(
        "DataGlove_drv.emulator",
        "Emulate a 5DT DataGlove on a pseudo-terminal.",
        default_link=DEFAULT_LINK,
        rate=100.0,
        rate_help="packets per second (38400 baud carries 384)",
        disconnect_after=5,
        disconnect_help="packets before hang-up",
    )
    parser.add_argument("--hand", choices=("right", "left"), default="right")
    args = parser.parse_args(argv)
    emulator = DataGloveEmulator(
        args.scenario,
        args.rate,
        hand=LEFT if args.hand == "left" else RIGHT,
        disconnect_after=args.disconnect_after,
        link=args.port or None,
    )
    return run_pty(
        emulator,
        title="5DT DataGlove",
        element="data_glove",
        duration=args.duration,
        detail=f"{args.hand} hand",
    )


if __name__ == "__main__":
    sys.exit(main())
