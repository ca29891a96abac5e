"""An Immersion Interface Box on a pseudo-terminal, independent of gadgetctl's input manager
(it uses only the shared emulator scaffolding, :mod:`gadgetctl.emulation`).

It speaks HCI: ``IMMC`` is echoed, ``BEGIN`` answered by the product id, ``END`` ends the
session, info commands 0xC8..0xCE are echoed and answered by a NUL-ended string, and a
standard query byte (0x00..0x3F) by a packet (buttons, timer, analogs with their low bits,
encoders, as the query asks), at most ``rate`` packets per second. Four buttons and four
analog inputs are wired. Scenarios:

``idle``        analogs rest at 128, no button pressed
``motion``      the analogs sweep
``buttons``     buttons 0..3 press in turn, analogs rest
``garbage``     motion, with junk and broken packets before the packets
``disconnect``  ``disconnect_after`` packets, then hang-up
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
from types import TracebackType

from gadgetctl.emulation import PseudoTerminal, emulator_parser, run

#: Seconds after the last write before the line counts as drained: the kernel moves what the
#: master wrote to the slave's input queue a moment later, and only then does FIONREAD count it.
QUIET = 0.1
SCENARIOS = ("idle", "motion", "buttons", "garbage", "disconnect")
DEFAULT_LINK = "/tmp/gadgetctl-ibox"
PRODUCT_ID = b"IBox emulator"
INFO = {
    0xC8: b"Interface Box",
    0xC9: b"IBOX",
    0xCA: b"Standard",
    0xCB: b"0001",
    0xCC: b"gadgetctl emulator",
    0xCD: b"std",
    0xCE: b"2.0",
}
# The emulator keeps its own copy of the wire layout.
ANALOGS = {0x00: 0, 0x04: 2, 0x08: 4, 0x0C: 8}
ENCODERS = {0: 0, 1: 2, 2: 3, 3: 6}
#: Queries the box holds while answering, at most.
MAX_WAITING = 4

#: Junk put before packets by the ``garbage`` scenario, in turn.
GARBAGE_CHUNKS: tuple[bytes, ...] = (
    b"\x13\x37\x00\x7e",  # bytes outside any packet
    b"\x88\x01\x02",  # a packet cut short
    b"\x88\x00\x90\x10\x10\x10\x00",  # bit 7 set inside a packet
    b"\x99\xaa",  # heads of packets nobody asked for
)

Sample = tuple[int, tuple[int, int, int, int]]


def controls(scenario: str, step: int) -> tuple[int, tuple[int, int, int, int]]:
    """Buttons (bit k = button k) and analogs 0..3 (0..255) at a step."""
    if scenario == "buttons":
        return (1 << (step // 10 % 4) if step % 10 < 5 else 0), (128, 128, 128, 128)
    if scenario in ("motion", "garbage", "disconnect"):
        return 0, tuple(  # type: ignore[return-value]
            int(127.5 + 127.5 * math.sin(step / 20.0 + k)) for k in range(4)
        )
    return 0, (128, 128, 128, 128)


def encode_packet(
    query: int,
    buttons: int,
    analog: tuple[int, ...],
    timer: int = 0,
    encoders: tuple[int, ...] = (),
) -> bytes:
    """The packet answering ``query`` (analogs beyond those given read 0)."""
    out = bytearray((query | 0x80, buttons & 0x7F))
    if query & 0x20:
        out += bytes((timer >> 7 & 0x7F, timer & 0x7F))
    count = ANALOGS[query & 0x0C]
    if count:
        values = [analog[i] if i < len(analog) else 0 for i in range(count)]
        out += bytes(v >> 1 for v in values)
        out.append(sum((v & 1) << (6 - i) for i, v in enumerate(values[:7])))
    for i in range(ENCODERS[query & 0x03]):
        value = encoders[i] if i < len(encoders) else 0
        out += bytes((value >> 7 & 0x7F, value & 0x7F))
    return bytes(out)


class IBoxEmulator:
    """The box side on a pty pair. ``sent`` records each valid packet as ``(buttons,
    analogs 0..3)``."""

    def __init__(
        self,
        scenario: str = "motion",
        rate: float = 500.0,
        *,
        disconnect_after: int = 40,
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
        self.session = False
        self.commands: list[bytes] = []
        self.queries: list[int] = []
        self.sent: list[Sample] = []
        self.paused = False
        self.dropped_bytes = 0
        self.disconnected = threading.Event()
        self.address = ""
        self._pty = PseudoTerminal(self.link)
        self._text = bytearray()
        self._waiting: list[int] = []  # queries received, answered in order
        self._next_due = 0.0
        self._hangup_due: float | None = None
        self._written_at = 0.0
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def start(self) -> IBoxEmulator:
        if self._thread is None:
            self.address = self._pty.open().address
            self._stop.clear()
            self._thread = threading.Thread(target=self._run, name="ibox-emulator", daemon=True)
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

    def __enter__(self) -> IBoxEmulator:
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
        while not self._stop.is_set() and self._pty.master >= 0:
            wait = 0.05
            if self._waiting:
                wait = max(0.0, min(wait, self._next_due - time.monotonic()))
            try:
                ready, _, _ = select.select([self._pty.master], [], [], wait)
                if ready:
                    for value in os.read(self._pty.master, 4096):
                        self._on_byte(value)
                if self._waiting and time.monotonic() >= self._next_due:
                    self._answer()
            except OSError:
                break

    def _on_byte(self, value: int) -> None:
        if 0x40 <= value < 0x80:  # letters: the text commands
            self._text.append(value)
            text = bytes(self._text)
            for word in (b"IMMC", b"BEGIN", b"END"):
                if text.endswith(word):
                    self._text.clear()
                    self.commands.append(word)
                    if word == b"IMMC":
                        self._write(b"IMMC")
                    elif word == b"BEGIN":
                        self.session = True
                        self._write(PRODUCT_ID + b"\0")
                    else:
                        self.session = False
                        self._waiting.clear()
            del self._text[:-8]
            return
        if value in INFO:
            self.commands.append(bytes((value,)))
            self._write(bytes((value,)) + INFO[value] + b"\0")
        elif value < 0x40 and self.session:
            self.queries.append(value)
            if not self._waiting:
                self._next_due = max(self._next_due, time.monotonic())
            if len(self._waiting) < MAX_WAITING:  # a small input buffer; more are lost
                self._waiting.append(value)

    def _answer(self) -> None:
        query = self._waiting.pop(0)
        self._next_due = max(self._next_due + 1.0 / self.rate, time.monotonic() - 1.0 / self.rate)
        step = len(self.sent)
        if self.scenario == "disconnect" and step >= self.disconnect_after:
            if self._hangup_due is None:
                self._hangup_due = time.monotonic() + self.linger
            quiet = time.monotonic() - self._written_at >= QUIET
            if not (quiet and not self.unread()) and time.monotonic() < self._hangup_due:
                self._waiting.insert(0, query)  # hang up once the driver has read what was sent
                return
            self.disconnected.set()
            self._pty.hang_up()
            return
        if self.paused:
            self._waiting.clear()
            return
        buttons, analog = controls(self.scenario, step)
        out = b""
        if self.scenario == "garbage":
            out += GARBAGE_CHUNKS[step % len(GARBAGE_CHUNKS)]
        out += encode_packet(query, buttons, analog, timer=step & 0x3FFF)
        self.sent.append((buttons, analog))
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
        "IBox_drv.emulator",
        "Emulate an Immersion Interface Box (HCI) on a pseudo-terminal.",
        scenarios=SCENARIOS,
        default_scenario="motion",
        rate=500.0,
        rate_help="queries answered per second at most",
    )
    parser.add_argument(
        "--port",
        default=DEFAULT_LINK,
        help=f"symlink to create pointing at the pty (default {DEFAULT_LINK}, where "
        "drivers/IBox_drv/example.jconf looks; '' for none)",
    )
    parser.add_argument("--disconnect-after", type=int, default=40, help="packets before hang-up")
    args = parser.parse_args(argv)
    emulator = IBoxEmulator(
        args.scenario, args.rate, disconnect_after=args.disconnect_after, link=args.port or None
    )

    def announce() -> None:
        where = str(emulator.link) if emulator.link is not None else emulator.address
        print(f"IBox emulator ({args.scenario}) on {emulator.address}", flush=True)
        print(f"point the ibox element at it: <port>{where}</port>", flush=True)

    def check() -> int | None:
        if emulator.disconnected.is_set():
            print("scenario finished: the line was hung up", flush=True)
            return 0
        return None

    return run(emulator, duration=args.duration, announce=announce, check=check)


if __name__ == "__main__":
    sys.exit(main())
