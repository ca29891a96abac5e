"""A Fakespace PinchGlove box on a pseudo-terminal, independent of gadgetctl's input manager
(it uses only the shared emulator scaffolding, :mod:`gadgetctl.emulation`).

The emulator owns the master side of an ``os.openpty()`` pair; a driver opens
the slave's path (``address``) as a serial port. It answers the two-byte
commands (``C L/R/P/T`` queries, ``T 1/0`` timestamps, ``V`` format version),
replies ``?`` to a pair it does not know, and once timestamps have been set
it plays a scripted scenario of touch frames:

``idle``        no contact ever changes, so nothing is sent
``touches``     a fixed press/release sequence (``buttons`` is an alias)
``motion``      the thumb taps each finger in turn, left hand then right
``garbage``     the touch sequence with junk bytes and broken frames in between
``disconnect``  ``disconnect_after`` frames of the touch sequence, then hang-up
"""

from __future__ import annotations

import math
import os
import random
import sys
from collections.abc import Iterator

from gadgetctl.emulation.device import PtyDeviceEmulator, pty_parser, run_pty

# The emulator keeps its own copy of the wire constants so that a mistake in the
# driver cannot be mirrored here and go unnoticed by the tests.
START_DATA = 0x80
START_DATA_TS = 0x81
START_INFO = 0x82
END = 0x8F
CMD_QUERY = ord("C")
CMD_TIMESTAMPS = ord("T")
CMD_FORMAT_VERSION = ord("V")
QUERIES = {
    ord("L"): "left_version",
    ord("R"): "right_version",
    ord("P"): "processor",
    ord("T"): "tick_length",
}
CONFUSED = b"?"

Groups = tuple[tuple[int, int], ...]

SCENARIOS = ("idle", "touches", "buttons", "motion", "garbage", "disconnect")

# The device's finger bits (see standalone.FINGER_BITS): 0x10 thumb .. 0x01 pinky.
L_THUMB, L_INDEX, L_MIDDLE, L_RING, L_PINKY = 0x10, 0x08, 0x04, 0x02, 0x01
R_THUMB, R_INDEX, R_MIDDLE, R_RING, R_PINKY = L_THUMB, L_INDEX, L_MIDDLE, L_RING, L_PINKY

#: The press/release sequence of the ``touches`` scenario (one frame per step).
TOUCH_SEQUENCE: tuple[Groups, ...] = (
    ((L_THUMB | L_INDEX, 0),),
    (),
    ((0, R_THUMB | R_MIDDLE),),
    (),
    ((L_THUMB, R_THUMB),),
    ((L_THUMB | L_PINKY, 0), (0, R_RING | R_PINKY)),
    (),
)

#: Junk inserted before each valid frame by the ``garbage`` scenario.
GARBAGE_CHUNKS: tuple[bytes, ...] = (
    bytes([0x13, 0x37, 0x00, 0x7E]),  # bytes outside any frame
    bytes([START_DATA_TS, 0x03, 0x00]),  # truncated: the next frame starts at once
    bytes([START_DATA, 0x01, END]),  # odd number of pair bytes
    bytes([START_DATA, 0x60, 0x00, END]),  # bits no finger has
    bytes([END, END]),  # stray end bytes
    bytes([START_INFO]) + b"noise" + bytes([END]),  # an unsolicited info frame
    bytes([START_DATA_TS, END]),  # too short to hold a timestamp
)

#: Where ``main`` puts a symlink to the pty unless told otherwise (example.jconf's port).
DEFAULT_LINK = "/tmp/gadgetctl-pinch"

#: Timestamp tick: 16382 ticks saturate after 13.6511206 s (PinchGlove manual).
TICK_SECONDS = 13.6511206 / 16382
MAX_TICKS = 16382

DEFAULT_INFO = {
    "left_version": "PG-L 1.1",
    "right_version": "PG-R 1.1",
    "processor": "PGP 2.0",
    "tick_length": "833",
}


def encode_frame(groups: Groups, timestamp: int | None) -> bytes:
    """A touch frame: start byte, ``(left, right)`` pairs, 2 timestamp bytes, end."""
    out = bytearray([START_DATA if timestamp is None else START_DATA_TS])
    for left, right in groups:
        out += bytes([left & 0x1F, right & 0x1F])
    if timestamp is not None:
        out += bytes([timestamp & 0x7F, timestamp >> 7 & 0x7F])  # low 7 bits first
    out.append(END)
    return bytes(out)


def touch_steps(scenario: str) -> Iterator[Groups]:
    """Endless contact-group steps of a scenario (none for ``idle``)."""
    if scenario == "idle":
        return
    if scenario == "motion":
        step = 0
        while True:
            finger = (L_INDEX, L_MIDDLE, L_RING, L_PINKY)[step % 4]
            yield ((L_THUMB | finger, 0),) if step // 4 % 2 == 0 else ((0, R_THUMB | finger),)
            yield ()
            step += 1
    while True:
        yield from TOUCH_SEQUENCE


class PinchGloveEmulator(PtyDeviceEmulator):
    """The glove box side of the protocol on a pty pair.

    ``address`` is the slave's path once started. ``rate`` is frames per second.
    ``link`` optionally names a symlink to create pointing at the pty.
    ``disconnect_after`` frames into the ``disconnect`` scenario the line is hung
    up, once the driver has read them (or ``linger`` seconds later).
    ``sent`` records every valid frame sent as ``(groups, timestamp)``.
    """

    DEVICE = "PinchGlove"
    SCENARIOS = SCENARIOS
    CATCH_UP = math.inf  # every frame is sent, late ones at once
    READ_SIZE = 1024

    def __init__(
        self,
        scenario: str = "touches",
        rate: float = 2.0,
        *,
        disconnect_after: int = 5,
        linger: float = 1.0,
        link: str | os.PathLike[str] | None = None,
        info: dict[str, str] | None = None,
        seed: int = 7,
    ) -> None:
        super().__init__(
            scenario, rate, disconnect_after=disconnect_after, linger=linger, link=link
        )
        self.scenario = "touches" if scenario == "buttons" else scenario
        self.info = dict(DEFAULT_INFO if info is None else info)
        self.sent: list[tuple[Groups, int | None]] = []
        self.bytes_received = 0
        self.timestamps = True
        self._rng = random.Random(seed)
        self._pending: int | None = None
        self._steps = touch_steps(self.scenario)
        self._frame_index = 0

    # -- device behaviour ---------------------------------------------------------------

    def on_bytes(self, data: bytes) -> None:
        self.bytes_received += len(data)
        super().on_bytes(data)

    def on_byte(self, value: int) -> None:
        if self._pending is None:
            self._pending = value
            return
        pair = bytes([self._pending, value])
        self._pending = None
        self.commands.append(pair)
        self._answer(pair)

    def _answer(self, pair: bytes) -> None:
        first, second = pair
        if first == CMD_QUERY and second in QUERIES:
            self._reply(self.info[QUERIES[second]].encode("ascii"))
        elif first == CMD_TIMESTAMPS and second in b"01":
            self.timestamps = second == ord("1")
            self._reply(bytes([second]))
            self.begin_sending()
        elif first == CMD_FORMAT_VERSION and second in b"01":
            self._reply(bytes([second]))
        else:
            self._reply(CONFUSED)

    def _reply(self, text: bytes) -> None:
        self.write(bytes([START_INFO]) + text + bytes([END]))

    def emit(self) -> None:
        if self.scenario == "disconnect" and self._frame_index >= self.disconnect_after:
            # Hang up once the driver has read what was sent (a pty drops unread
            # input on hang-up), or after ``linger`` seconds at the latest.
            self.hang_up_once_read()
            return
        groups = next(self._steps, None)
        if groups is None:
            return
        stamp = min(round(self._frame_index / self.rate / TICK_SECONDS), MAX_TICKS)
        timestamp = stamp if self.timestamps else None
        frame = encode_frame(groups, timestamp)
        junk = b""
        if self.scenario == "garbage":
            junk = GARBAGE_CHUNKS[self._frame_index % len(GARBAGE_CHUNKS)]
            junk += bytes(self._rng.randrange(0x00, 0x7F) for _ in range(self._frame_index % 3))
        self._frame_index += 1
        self.sent.append((groups, timestamp))
        self.write(junk + frame)


def main(argv: list[str] | None = None) -> int:
    """Run the emulator until Ctrl-C, SIGTERM, SIGHUP or ``--duration`` seconds."""
    parser = pty_parser(
        "PinchGlove_drv.emulator",
        "Emulate a Fakespace PinchGlove box on a pseudo-terminal.",
        default_link=DEFAULT_LINK,
        rate=2.0,
        rate_help="touch frames per second",
        disconnect_after=5,
        disconnect_help="frames before hang-up",
        scenarios=SCENARIOS,
        default_scenario="touches",
    )
    args = parser.parse_args(argv)
    emulator = PinchGloveEmulator(
        args.scenario, args.rate, disconnect_after=args.disconnect_after, link=args.port or None
    )
    return run_pty(emulator, title="PinchGlove", element="pinch_glove", duration=args.duration)


if __name__ == "__main__":
    sys.exit(main())
