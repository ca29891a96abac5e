"""A 5DT DataGlove on a pseudo-terminal, independent of gadgetctl's input manager (it uses
only the shared emulator scaffolding, :mod:`gadgetctl.emulation`).

``model`` picks the glove, each sending what such a glove sends (VRPN ``vrpn_Analog_5dt.C``,
VR Juggler ``DataGloveStandalone.cpp``):

``classic``     streams 10-byte packets unasked, the 10th byte 0 (right) or 6 (left), as VR
                Juggler reads them (the default)
``wireless``    streams 10-byte packets unasked and ignores commands, the 10th byte 0x01
                (right) or 0x40 (left)
``wired``       answers ``A`` with 0x55 and ``G`` with its 32 bytes of information, and streams
                9-byte packets (the manual's) once asked with ``D``
``wired-55``    the same with a 10th byte 0x55, as VRPN saw from wired gloves

A glove that streams unasked starts once a driver has the line open (the first packet waits
in the line until then; opening the port discards it), at ``rate`` packets per second.
Scenarios:

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
MODELS = ("classic", "wireless", "wired", "wired-55")
#: The 10th byte of each model's packets for a right and a left hand (None: 9-byte packets).
TENTH_BYTE = {
    "classic": (0x00, 0x06),
    "wireless": (0x01, 0x40),
    "wired": (None, None),
    "wired-55": (0x55, 0x55),
}
#: The models that stream only once asked (``A``, ``G``, ``D``).
ASKED = ("wired", "wired-55")
NAME = b"5DT Data Glove 5"
#: Flexure bytes (thumb..pinky) of the ``buttons`` scenario: fist, pointing, open hand.
POSES = ((230, 240, 240, 235, 220), (200, 20, 240, 235, 220), (10, 15, 12, 20, 18))
GARBAGE = (
    b"\x13\x37",  # stray bytes
    b"\x80\x01\x02",  # a header and a packet cut short
    b"\x80" + bytes(7) + b"\x55\x00",  # a bad checksum
    b"\x80" + bytes(6) + b"\x01\x00",  # a checksum that does not match
    bytes(range(0x70, 0x90)),  # a run holding headers
)

Packet = tuple[int, ...]  # the nine bytes after the header


def encode_packet(data: tuple[int, ...], capability: int | None = RIGHT) -> bytes:
    """Header, seven data bytes, their XOR and the 10th byte (None: a 9-byte packet)."""
    check = 0
    for value in data:
        check ^= value
    return bytes([0x80, *data, check]) + (b"" if capability is None else bytes([capability]))


def info_reply(right: bool) -> bytes:
    """The 32-byte answer to ``G``: ``BR``, version 2.1, the hand (bit 0 of byte 4), pitch and
    roll fitted (bit 4 of byte 5), ten spare bytes, then the name."""
    return b"BR" + bytes([2, 1, int(right), 0x10]) + bytes(10) + NAME.ljust(16, b"\0")


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
        model: str = "classic",
        disconnect_after: int = 5,
        linger: float = 1.0,
        link: str | os.PathLike[str] | None = None,
    ) -> None:
        super().__init__(
            scenario, rate, disconnect_after=disconnect_after, linger=linger, link=link, drain=0.5
        )
        if model not in MODELS:
            raise ValueError(f"model {model!r} is not one of {', '.join(MODELS)}")
        self.hand = hand
        self.model = model
        self.tenth = TENTH_BYTE[model][hand == LEFT]
        self.sent: list[tuple[int, ...]] = []
        # the packet sent before a driver is there (a glove that streams unasked)
        self.probe = None if model in ASKED else pose(scenario, 0)
        self._step = 0

    def on_open(self) -> None:
        if self.probe is not None:
            # waits for a reader; opening the port discards it, unless still on its way
            self.write(encode_packet(self.probe, self.tenth))

    def on_byte(self, value: int) -> None:
        if self.model not in ASKED:
            return  # this glove ignores commands
        self.commands.append(bytes([value]))
        if value == ord("A"):
            self.write(b"\x55")
        elif value == ord("G"):
            self.write(info_reply(self.hand != LEFT))
        elif value == ord("D"):
            self.begin_sending()

    def sending(self) -> bool:
        if self.probe is not None and not self.streaming.is_set() and self.probe_taken():
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
        self.write(junk + encode_packet(data, self.tenth))


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
    parser.add_argument(
        "--model", choices=MODELS, default="classic", help="which glove (see the module help)"
    )
    args = parser.parse_args(argv)
    emulator = DataGloveEmulator(
        args.scenario,
        args.rate,
        hand=LEFT if args.hand == "left" else RIGHT,
        model=args.model,
        disconnect_after=args.disconnect_after,
        link=args.port or None,
    )
    return run_pty(
        emulator,
        title="5DT DataGlove",
        element="data_glove",
        duration=args.duration,
        detail=f"{args.hand} hand, {args.model}",
    )


if __name__ == "__main__":
    sys.exit(main())
