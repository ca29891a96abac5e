"""An Ascension Wanda on a pseudo-terminal, independent of gadgetctl's input manager (it uses
only the shared emulator scaffolding, :mod:`gadgetctl.emulation`).

It says ``M3`` once its pty is open (a pty carries no RTS to wait for); once a driver has
opened the line (the ``M3`` left the line's input queue: opening a port discards it, or it was
read) it sends a serial-mouse packet ``rate`` times a second: 3 bytes, or 4 while the middle
button is down. Packets are held back while the driver lags, so ``sent`` lists what the
driver can read. Scenarios:

``idle``        joystick centred, no button pressed
``motion``      the joystick circles (to its -34..34 limits)
``buttons``     buttons 0, 1 (the middle one, 4-byte packets) and 2 press in turn
``garbage``     motion, with junk and broken packets between the packets
``disconnect``  ``disconnect_after`` packets, then hang-up
"""

from __future__ import annotations

import fcntl
import math
import os
import struct
import sys
import termios
import threading
import time
from pathlib import Path
from types import TracebackType

from gadgetctl.emulation import PseudoTerminal, emulator_parser, run

SCENARIOS = ("idle", "motion", "buttons", "garbage", "disconnect")
DEFAULT_LINK = "/tmp/gadgetctl-wanda"
#: Seconds after the last write before the line counts as drained (the kernel moves what the
#: master wrote to the slave's input queue a moment later, and only then does FIONREAD count it).
QUIET = 0.1
#: Unread bytes beyond which packets are held back (no reader).
BACKLOG = 64

#: Junk put between packets by the ``garbage`` scenario, in turn.
GARBAGE_CHUNKS: tuple[bytes, ...] = (
    b"\x93\x00\x3f",  # an 8-bit byte, then bytes without a sync bit
    b"\x40\x01",  # a packet cut short (the next sync comes too early)
    b"\xc0\x81\xff",  # 8-bit bytes, which a 7-bit line cannot carry
)

Sample = tuple[tuple[int, int, int], tuple[int, int]]


def encode_packet(buttons: tuple[int, int, int], axes: tuple[int, int]) -> bytes:
    """The packet of buttons 0..2 and joystick (x, y) as the driver reports them (x is sent
    negated)."""
    x, y = (-axes[0]) & 0xFF, axes[1] & 0xFF
    b0 = 0x40 | buttons[0] << 5 | buttons[2] << 4 | (y >> 6) << 2 | (x >> 6)
    packet = bytes((b0, x & 0x3F, y & 0x3F))
    return packet + b"\x20" if buttons[1] else packet


def controls(scenario: str, step: int) -> Sample:
    """Buttons 0..2 (0/1) and the joystick (x, y) at a step."""
    if scenario == "buttons":
        pressed = step // 10 % 3 if step % 10 < 5 else None
        return tuple(int(pressed == k) for k in range(3)), (0, 0)  # type: ignore[return-value]
    if scenario in ("motion", "garbage", "disconnect"):
        t = step / 15.0
        return (0, 0, 0), (round(34 * math.cos(t)), round(34 * math.sin(t)))
    return (0, 0, 0), (0, 0)


class WandaEmulator:
    """The Wanda side on a pty pair. ``sent`` records each packet written as ``(buttons,
    axes)``."""

    def __init__(
        self,
        scenario: str = "motion",
        rate: float = 40.0,
        *,
        disconnect_after: int = 20,
        linger: float = 1.0,
        link: str | os.PathLike[str] | None = None,
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
        self.sent: list[Sample] = []
        self.paused = False
        #: a driver has opened the line (packets flow from then on)
        self.reader = False
        self.dropped_bytes = 0
        self.disconnected = threading.Event()
        self.address = ""
        self._pty = PseudoTerminal(self.link)
        self._written_at = 0.0
        self._hangup_due: float | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def start(self) -> WandaEmulator:
        if self._thread is None:
            self.address = self._pty.open().address
            self._write(b"M3")
            self._stop.clear()
            self._thread = threading.Thread(target=self._run, name="wanda-emulator", daemon=True)
            self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5)
            self._thread = None
        deadline = time.monotonic() + self.linger
        while (self.unread() or time.monotonic() - self._written_at < QUIET) and (
            time.monotonic() < deadline
        ):
            time.sleep(0.005)  # let a reading driver drain the line before it goes away
        self._pty.close()

    def __enter__(self) -> WandaEmulator:
        return self.start()

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.stop()

    def send_raw(self, data: bytes) -> None:
        """Write bytes to the driver as they are (for tests)."""
        self._write(data)

    def _run(self) -> None:
        due = time.monotonic()
        while not self._stop.wait(max(0.0, due - time.monotonic())):
            due = max(due + 1.0 / self.rate, time.monotonic() - 1.0 / self.rate)
            if self._pty.master < 0:
                break
            if self.scenario == "disconnect" and len(self.sent) >= self.disconnect_after:
                if self._hangup_due is None:
                    self._hangup_due = time.monotonic() + self.linger
                quiet = time.monotonic() - self._written_at >= QUIET
                if (quiet and not self.unread()) or time.monotonic() >= self._hangup_due:
                    self.disconnected.set()
                    self._pty.hang_up()
                    break
                continue
            if not self.reader:
                # M3 waits in the line until a driver opens it (which discards it) or reads it
                landed = time.monotonic() - self._written_at >= QUIET
                self.reader = landed and not self.unread()
                if not self.reader:
                    continue
            if self.paused or self.unread() > BACKLOG:
                continue  # the reader fell behind: hold the packets back
            step = len(self.sent)
            buttons, axes = controls(self.scenario, step)
            out = b""
            if self.scenario == "garbage":
                out += GARBAGE_CHUNKS[step % len(GARBAGE_CHUNKS)]
            out += encode_packet(buttons, axes)
            self.sent.append((buttons, axes))
            self._write(out)

    def unread(self) -> int:
        """Bytes written that the driver has not read yet."""
        slave = self._pty.slave
        if slave < 0:
            return 0
        try:
            raw = fcntl.ioctl(slave, termios.FIONREAD, b"\0\0\0\0")
        except OSError:
            return 0
        return struct.unpack("i", raw)[0]

    def _write(self, data: bytes) -> None:
        self._written_at = time.monotonic()
        self.dropped_bytes += len(data) - self._pty.write(data)


def main(argv: list[str] | None = None) -> int:
    """Run the emulator until Ctrl-C, SIGTERM, SIGHUP or ``--duration`` seconds."""
    parser = emulator_parser(
        "Wanda_drv.emulator",
        "Emulate an Ascension Wanda (serial mouse protocol) on a pseudo-terminal.",
        scenarios=SCENARIOS,
        default_scenario="motion",
        rate=40.0,
        rate_help="packets per second (1200 baud 7N1 carries 44 three-byte packets)",
    )
    parser.add_argument(
        "--port",
        default=DEFAULT_LINK,
        help=f"symlink to create pointing at the pty (default {DEFAULT_LINK}, where "
        "drivers/Wanda_drv/example.jconf looks; '' for none)",
    )
    parser.add_argument("--disconnect-after", type=int, default=20, help="packets before hang-up")
    args = parser.parse_args(argv)
    emulator = WandaEmulator(
        args.scenario, args.rate, disconnect_after=args.disconnect_after, link=args.port or None
    )

    def announce() -> None:
        where = str(emulator.link) if emulator.link is not None else emulator.address
        print(f"Wanda emulator ({args.scenario}) on {emulator.address}", flush=True)
        print(f"point the wanda element at it: <port>{where}</port>", flush=True)

    def check() -> int | None:
        if emulator.disconnected.is_set():
            print("scenario finished: the line was hung up", flush=True)
            return 0
        return None

    return run(emulator, duration=args.duration, announce=announce, check=check)


if __name__ == "__main__":
    sys.exit(main())
