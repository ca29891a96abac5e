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

import fcntl
import math
import os
import select
import struct
import sys
import termios
import threading
import time
from pathlib import Path

from gadgetctl.emulation import PseudoTerminal, emulator_parser, run

# The emulator keeps its own copy of the wire format so that a mistake in the driver cannot be
# mirrored here and go unnoticed by the tests.
SCENARIOS = ("idle", "motion", "buttons", "garbage", "disconnect")
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


class DataGloveEmulator:
    """The glove's side of the line on a pty pair. ``sent`` lists the data bytes of every good
    packet sent (not the first one, which waits for a driver and is discarded at its open)."""

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
        if scenario not in SCENARIOS:
            raise ValueError(f"unknown scenario {scenario!r}; choose from {', '.join(SCENARIOS)}")
        if rate <= 0:
            raise ValueError("rate must be positive")
        self.scenario, self.rate, self.hand = scenario, rate, hand
        self.disconnect_after, self.linger = disconnect_after, linger
        self.link = Path(link) if link is not None else None
        self.address = ""
        self.sent: list[tuple[int, ...]] = []
        self.probe = pose(scenario, 0)  # the packet sent before a driver is there
        self.dropped_bytes = 0
        self.streaming = threading.Event()  # a driver has the line
        self.disconnected = threading.Event()
        self._pty = PseudoTerminal(self.link)
        self._stop = threading.Event()
        self._quiet = threading.Event()
        self.drain = 0.5
        self._thread: threading.Thread | None = None
        self._next_due = 0.0
        self._step = 0
        self._hangup_due: float | None = None
        self._lock = threading.Lock()

    def start(self) -> DataGloveEmulator:
        if self._thread is None:
            self.address = self._pty.open().address
            # waits for a reader; opening the port discards it, unless it was still on its way
            self._write(encode_packet(self.probe, self.hand))
            self._stop.clear()
            self._thread = threading.Thread(
                target=self._run, name="dataglove-emulator", daemon=True
            )
            self._thread.start()
        return self

    def stop(self) -> None:
        """Stop sending, give a reading driver up to ``drain`` seconds to read what was sent
        (a pty drops unread input when it closes), then close the pty and remove the link."""
        self._quiet.set()
        deadline = time.monotonic() + self.drain
        while self.streaming.is_set() and self._unread() and time.monotonic() < deadline:
            time.sleep(0.005)
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5)
            self._thread = None
        self._pty.close()

    def __enter__(self) -> DataGloveEmulator:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def _run(self) -> None:
        while not self._stop.is_set() and self._pty.master >= 0:
            if not self.streaming.is_set():
                if self._unread():
                    self._stop.wait(0.005)
                    continue
                self.streaming.set()  # read or discarded: a driver is there
                self._next_due = time.monotonic()
            try:
                select.select(
                    [self._pty.master],
                    [],
                    [],
                    max(0.0, min(0.05, self._next_due - time.monotonic())),
                )
                now = time.monotonic()
                if now >= self._next_due:
                    self._next_due = max(self._next_due + 1.0 / self.rate, now - 0.05)
                    self._emit()
            except OSError:
                break

    def _emit(self) -> None:
        step = self._step
        if self._quiet.is_set():
            return
        if self.scenario == "disconnect" and step >= self.disconnect_after:
            if self._hangup_due is None:
                self._hangup_due = time.monotonic() + self.linger
            if self._unread() and time.monotonic() < self._hangup_due:
                return  # a pty drops unread input on hang-up: let the driver read first
            self.disconnected.set()
            self._pty.hang_up()
            return
        self._step += 1
        data = pose(
            "motion" if self.scenario in ("garbage", "disconnect") else self.scenario, step + 1
        )
        junk = GARBAGE[step % len(GARBAGE)] if self.scenario == "garbage" else b""
        self.sent.append(data)
        self._write(junk + encode_packet(data, self.hand))

    def _unread(self) -> int:
        with self._lock:
            if self._pty.slave < 0:
                return 0
            try:
                raw = fcntl.ioctl(self._pty.slave, termios.FIONREAD, b"\0\0\0\0")
            except OSError:
                return 0
        return struct.unpack("i", raw)[0]

    def send_raw(self, data: bytes) -> None:
        """Write bytes to the driver as they are (for tests)."""
        self._write(data)

    def _write(self, data: bytes) -> None:
        with self._lock:
            self.dropped_bytes += len(data) - self._pty.write(data)


def main(argv: list[str] | None = None) -> int:
    parser = emulator_parser(
        "DataGlove_drv.emulator",
        "Emulate a 5DT DataGlove on a pseudo-terminal.",
        scenarios=SCENARIOS,
        default_scenario="motion",
        rate=100.0,
        rate_help="packets per second (38400 baud carries 384)",
    )
    parser.add_argument("--hand", choices=("right", "left"), default="right")
    parser.add_argument(
        "--port",
        default=DEFAULT_LINK,
        help=f"symlink to create pointing at the pty (default {DEFAULT_LINK}, where "
        "drivers/DataGlove_drv/example.jconf looks; '' for none)",
    )
    parser.add_argument("--disconnect-after", type=int, default=5, help="packets before hang-up")
    args = parser.parse_args(argv)
    emulator = DataGloveEmulator(
        args.scenario,
        args.rate,
        hand=LEFT if args.hand == "left" else RIGHT,
        disconnect_after=args.disconnect_after,
        link=args.port or None,
    )

    def announce() -> None:
        where = str(emulator.link) if emulator.link is not None else emulator.address
        print(
            f"5DT DataGlove emulator ({args.scenario}, {args.hand} hand) on {emulator.address}",
            flush=True,
        )
        print(f"point the data_glove element at it: <port>{where}</port>", flush=True)

    def check() -> int | None:
        if emulator.disconnected.is_set():
            print("scenario finished: the line was hung up", flush=True)
            return 0
        return None

    return run(emulator, duration=args.duration, announce=announce, check=check)


if __name__ == "__main__":
    sys.exit(main())
