"""A Logitech 3D mouse / head tracker on a pseudo-terminal, independent of gadgetctl's input
manager (it uses only the shared emulator scaffolding, :mod:`gadgetctl.emulation`).

It answers the two-byte commands ``*D``, ``*R``, ``*\\x05`` (diagnostics: ``0xBF 0x3F``),
``*H``, ``*h``, ``*G`` and ``*d`` (one 16-byte report, at most ``rate`` a second).
Scenarios:

``idle``        the mouse holds still, no button pressed
``motion``      it circles and turns about all three axes
``buttons``     still; left, middle and right buttons press in turn
``garbage``     motion, with junk and broken reports before the reports
``disconnect``  ``disconnect_after`` reports, then hang-up
"""

from __future__ import annotations

import fcntl
import math
import os
import random
import select
import struct
import sys
import termios
import threading
import time
from pathlib import Path
from types import TracebackType

from gadgetctl.emulation import PseudoTerminal, emulator_parser, run

#: Seconds after a write before the pty's reader queue shows the bytes for sure.
PTY_SETTLE = 0.05
SCENARIOS = ("idle", "motion", "buttons", "garbage", "disconnect")
DEFAULT_LINK = "/tmp/gadgetctl-3dmouse"
BUTTONS = (0x04, 0x02, 0x01)  # left, middle, right

#: Junk put before reports by the ``garbage`` scenario, in turn.
GARBAGE_CHUNKS: tuple[bytes, ...] = (
    b"\x13\x37\x00\x7e",  # 7-bit bytes outside any report
    b"\x80\x01\x02\x03",  # a report cut short by the next one
    b"\x80" + b"\x00" * 9 + b"\x7f\x7f" + b"\x00" * 4,  # an angle beyond a turn
    b"\xff\xfe\x90",  # flag bytes only
)

Sample = tuple[tuple[int, int, int], tuple[int, int, int], int]


def encode_report(
    position: tuple[int, int, int], angles: tuple[int, int, int], flags: int = 0
) -> bytes:
    """A report: position in thousandths of an inch, angles in fortieths of a degree."""
    out = bytearray([0x80 | (flags & 0x7F)])
    for value in position:
        raw = value & ((1 << 21) - 1)  # 21-bit two's complement
        out += bytes((raw >> 14 & 0x7F, raw >> 7 & 0x7F, raw & 0x7F))
    for value in angles:
        out += bytes((value >> 7 & 0x7F, value & 0x7F))
    return bytes(out)


def state(scenario: str, step: int) -> Sample:
    """Position (1/1000 inch), angles (1/40 degree) and flag bits at a step."""
    if scenario in ("motion", "garbage"):
        t = step / 25.0
        position = (
            round(4000 * math.cos(t)),
            round(-3000 + 4000 * math.sin(t)),
            round(12000 + 1500 * math.sin(2 * t)),
        )
        angles = (step * 40 % 14400, (step * 80 + 3600) % 14400, (7200 + step * 120) % 14400)
        return position, angles, 0
    flags = BUTTONS[step // 3 % 3] if scenario == "buttons" and step % 6 < 3 else 0
    return (1500, -2500, 9000), (40 * 30, 40 * 45, 40 * 60), flags


class ThreeDMouseEmulator:
    """The mouse side on a pty pair. ``sent`` records each valid report as ``(position in
    1/1000 inch, angles in 1/40 degree, flag bits)``."""

    def __init__(
        self,
        scenario: str = "motion",
        rate: float = 100.0,
        *,
        disconnect_after: int = 20,
        linger: float = 1.0,
        link: str | os.PathLike[str] | None = None,
        diagnostic: bytes = b"\xbf\x3f",
        seed: int = 7,
    ) -> None:
        if scenario not in SCENARIOS:
            raise ValueError(f"unknown scenario {scenario!r}; choose from {', '.join(SCENARIOS)}")
        if rate <= 0:
            raise ValueError("rate must be positive")
        self.scenario = scenario
        self.rate = rate
        self.disconnect_after = disconnect_after
        self.linger = linger
        self.link = Path(link) if link is not None else None
        self.diagnostic = diagnostic
        self.commands: list[bytes] = []
        self.sent: list[Sample] = []
        self.dropped_bytes = 0
        self.disconnected = threading.Event()
        #: while True nothing is sent (a benchmark counts what was sent)
        self.paused = False
        self._emit_lock = threading.Lock()
        self._written_at = 0.0
        self.address = ""
        self._pty = PseudoTerminal(self.link)
        self._rng = random.Random(seed)
        self._pending: int | None = None
        self._polled = False
        self._next_due = 0.0
        self._hangup_due: float | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def start(self) -> ThreeDMouseEmulator:
        if self._thread is None:
            self.address = self._pty.open().address
            self._stop.clear()
            self._thread = threading.Thread(target=self._run, name="3dmouse-emulator", daemon=True)
            self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5)
            self._thread = None
        self._pty.close()

    def __enter__(self) -> ThreeDMouseEmulator:
        return self.start()

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.stop()

    def pause(self) -> None:
        """Send nothing more; returns once a record being sent is out, so ``sent`` is final."""
        with self._emit_lock:
            self.paused = True

    def send_raw(self, data: bytes) -> None:
        self._write(data)

    def _run(self) -> None:
        while not self._stop.is_set() and self._pty.master >= 0:
            wait = 0.05
            if self._polled:
                wait = max(0.0, min(wait, self._next_due - time.monotonic()))
            try:
                ready, _, _ = select.select([self._pty.master], [], [], wait)
                if ready:
                    for value in os.read(self._pty.master, 4096):
                        self._on_byte(value)
                with self._emit_lock:
                    if self._polled and not self.paused and time.monotonic() >= self._next_due:
                        self._report()
            except OSError:
                break

    def _on_byte(self, value: int) -> None:
        if self._pending is None:
            if value == ord("*"):
                self._pending = value
            return
        self._pending = None
        self.commands.append(b"*" + bytes([value]))
        if value == 0x05:
            self._write(self.diagnostic)
        elif value == ord("d"):
            if not self._polled:
                self._next_due = max(self._next_due, time.monotonic())
            self._polled = True

    def _report(self) -> None:
        self._polled = False
        self._next_due = max(self._next_due + 1.0 / self.rate, time.monotonic() - 1.0 / self.rate)
        count = len(self.sent)
        if self.scenario == "disconnect" and count >= self.disconnect_after:
            if self._hangup_due is None:
                self._hangup_due = time.monotonic() + self.linger
            if not self._all_read() and time.monotonic() < self._hangup_due:
                self._polled = True
                return
            self.disconnected.set()
            self._pty.hang_up()
            return
        sample = state(self.scenario, count)
        junk = b""
        if self.scenario == "garbage":
            junk = GARBAGE_CHUNKS[count % len(GARBAGE_CHUNKS)]
            junk += bytes(self._rng.randrange(0x00, 0x80) for _ in range(count % 3))
        self.sent.append(sample)
        self._write(junk + encode_report(*sample))

    def unread(self) -> int:
        """Bytes sent that the driver has not read yet."""
        slave = self._pty.slave
        if slave < 0:
            return 0
        try:
            raw = fcntl.ioctl(slave, termios.FIONREAD, b"\0\0\0\0")
        except OSError:
            return 0
        return struct.unpack("i", raw)[0]

    def _all_read(self) -> bool:
        """The driver has read everything sent. A pty moves written bytes to the reader's queue
        a moment later (the kernel's flip buffer), so the queue is trusted only once
        :data:`PTY_SETTLE` seconds have passed since the last write."""
        return time.monotonic() - self._written_at >= PTY_SETTLE and not self.unread()

    def _write(self, data: bytes) -> None:
        self._written_at = time.monotonic()
        self.dropped_bytes += len(data) - self._pty.write(data)


def main(argv: list[str] | None = None) -> int:
    """Run the emulator until Ctrl-C, SIGTERM, SIGHUP or ``--duration`` seconds."""
    parser = emulator_parser(
        "ThreeDMouse_drv.emulator",
        "Emulate a Logitech 3D mouse / head tracker on a pseudo-terminal.",
        scenarios=SCENARIOS,
        default_scenario="motion",
        rate=100.0,
        rate_help="reports per second at most",
    )
    parser.add_argument(
        "--port",
        default=DEFAULT_LINK,
        help=f"symlink to create pointing at the pty (default {DEFAULT_LINK}, where "
        "drivers/ThreeDMouse_drv/example.jconf looks; '' for none)",
    )
    parser.add_argument("--disconnect-after", type=int, default=20, help="reports before hang-up")
    args = parser.parse_args(argv)
    emulator = ThreeDMouseEmulator(
        args.scenario, args.rate, disconnect_after=args.disconnect_after, link=args.port or None
    )

    def announce() -> None:
        where = str(emulator.link) if emulator.link is not None else emulator.address
        print(f"3D mouse emulator ({args.scenario}) on {emulator.address}", flush=True)
        print(f"point the three_d_mouse element at it: <port>{where}</port>", flush=True)

    def check() -> int | None:
        if emulator.disconnected.is_set():
            print("scenario finished: the line was hung up", flush=True)
            return 0
        return None

    return run(emulator, duration=args.duration, announce=announce, check=check)


if __name__ == "__main__":
    sys.exit(main())
