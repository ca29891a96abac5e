"""A 5DT Data Glove Ultra Wireless receiver with gloves on ports A and B, on a pseudo-terminal,
independent of gadgetctl's input manager (it uses only :mod:`gadgetctl.emulation`).

The receiver streams 29-byte records (``<``, port, unused byte, fourteen 12-bit readings,
four status bytes, ``>``), the enabled gloves in turn, ``rate`` records per second, once a
driver has the line open (the first record waits in the line until then; opening the port
discards it):

``idle``        both hands rest half bent
``motion``      every sensor sweeps its range, each at its own pace
``buttons``     both hands step through an open hand and a fist (gestures 0 and 15)
``garbage``     motion with junk between records and records broken at their end
``disconnect``  ``disconnect_after`` records of motion, then the line is hung up
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

from gadgetctl.emulation import PseudoTerminal, emulator_parser, run

# The emulator keeps its own copy of the wire format so that a mistake in the driver cannot be
# mirrored here and go unnoticed by the tests.
SCENARIOS = ("idle", "motion", "buttons", "garbage", "disconnect")
DEFAULT_LINK = "/tmp/gadgetctl-ultraglove"
PORT_IDS = {0: 0x02, 1: 0x05}  # A: low nibble 2 (or 3); B: anything else
GARBAGE = (b"\x00\x3e\x3e", b"<" + bytes(27) + b"!", b"\xff" * 12, b"<<")


def encode_record(port: int, raw: tuple[int, ...], status: bytes = b"\x00\x00\x00\x00") -> bytes:
    packed = 0
    for value in raw:
        packed = packed << 12 | (value & 0xFFF)
    return bytes([0x3C, 0x40 | PORT_IDS[port], 0x01]) + packed.to_bytes(21, "big") + status + b">"


def readings(scenario: str, port: int, step: int) -> tuple[int, ...]:
    """Fourteen raw readings of a glove at a step."""
    if scenario == "idle":
        return (2048,) * 14
    if scenario == "buttons":
        closed = step // 6 % 2 == 1
        # the first record of each glove spans the range, so the auto-range knows both ends
        if step < 4:
            return (400 if step < 2 else 3600,) * 14
        return (3500 if closed else 500,) * 14
    return tuple(round(2047.5 + 1800 * math.sin(step / (6 + i) + port + i)) for i in range(14))


class UltraGloveEmulator:
    """The receiver's side of the line on a pty pair. ``sent`` lists every good record sent
    as ``(port, readings)`` (not the first one, which waits for a driver)."""

    def __init__(
        self,
        scenario: str = "motion",
        rate: float = 100.0,
        *,
        ports: tuple[int, ...] = (0, 1),
        disconnect_after: int = 6,
        linger: float = 1.0,
        link: str | os.PathLike[str] | None = None,
    ) -> None:
        if scenario not in SCENARIOS:
            raise ValueError(f"unknown scenario {scenario!r}; choose from {', '.join(SCENARIOS)}")
        if rate <= 0:
            raise ValueError("rate must be positive")
        self.scenario, self.rate, self.ports = scenario, rate, ports
        self.disconnect_after, self.linger = disconnect_after, linger
        self.link = Path(link) if link is not None else None
        self.address = ""
        self.sent: list[tuple[int, tuple[int, ...]]] = []
        self.probe = (ports[0], readings(scenario, ports[0], 0))  # sent before a driver is there
        self.dropped_bytes = 0
        self.drain = 0.5
        self.streaming = threading.Event()
        self.disconnected = threading.Event()
        self._pty = PseudoTerminal(self.link)
        self._stop = threading.Event()
        self._quiet = threading.Event()
        self._thread: threading.Thread | None = None
        self._next_due = 0.0
        self._step = 0
        self._hangup_due: float | None = None
        self._lock = threading.Lock()

    def start(self) -> UltraGloveEmulator:
        if self._thread is None:
            self.address = self._pty.open().address
            # waits for a reader; opening the port discards it, unless it was still on its way
            self._write(encode_record(*self.probe))
            self._stop.clear()
            self._thread = threading.Thread(
                target=self._run, name="ultraglove-emulator", daemon=True
            )
            self._thread.start()
        return self

    def stop(self) -> None:
        """Stop sending, give a reading driver up to ``drain`` seconds to read what was sent,
        then close the pty and remove the link."""
        self._quiet.set()
        deadline = time.monotonic() + self.drain
        while self.streaming.is_set() and self._unread() and time.monotonic() < deadline:
            time.sleep(0.005)
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5)
            self._thread = None
        self._pty.close()

    def __enter__(self) -> UltraGloveEmulator:
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
            self._stop.wait(max(0.0, min(0.05, self._next_due - time.monotonic())))
            now = time.monotonic()
            if now >= self._next_due:
                self._next_due = max(self._next_due + 1.0 / self.rate, now - 0.05)
                self._emit()

    def _emit(self) -> None:
        if self._quiet.is_set():
            return
        step = self._step
        if self.scenario == "disconnect" and step >= self.disconnect_after:
            if self._hangup_due is None:
                self._hangup_due = time.monotonic() + self.linger
            if self._unread() and time.monotonic() < self._hangup_due:
                return
            self.disconnected.set()
            self._pty.hang_up()
            return
        self._step += 1
        port = self.ports[step % len(self.ports)]
        scenario = "motion" if self.scenario in ("garbage", "disconnect") else self.scenario
        raw = readings(scenario, port, step)
        junk = GARBAGE[step % len(GARBAGE)] if self.scenario == "garbage" else b""
        self.sent.append((port, raw))
        self._write(junk + encode_record(port, raw))

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
        "DataGloveUltraWireless_drv.emulator",
        "Emulate a 5DT Data Glove Ultra Wireless receiver (gloves on ports A and B) on a "
        "pseudo-terminal.",
        scenarios=SCENARIOS,
        default_scenario="motion",
        rate=100.0,
        rate_help="records per second, both gloves together",
    )
    parser.add_argument(
        "--gloves", choices=("A", "B", "AB"), default="AB", help="ports with a glove"
    )
    parser.add_argument(
        "--port",
        default=DEFAULT_LINK,
        help=f"symlink to create pointing at the pty (default {DEFAULT_LINK}, where "
        "drivers/DataGloveUltraWireless_drv/example.jconf looks; '' for none)",
    )
    parser.add_argument("--disconnect-after", type=int, default=6, help="records before hang-up")
    args = parser.parse_args(argv)
    emulator = UltraGloveEmulator(
        args.scenario,
        args.rate,
        ports=tuple("AB".index(p) for p in args.gloves),
        disconnect_after=args.disconnect_after,
        link=args.port or None,
    )

    def announce() -> None:
        where = str(emulator.link) if emulator.link is not None else emulator.address
        print(
            f"5DT Data Glove Ultra Wireless emulator ({args.scenario}) on {emulator.address}",
            flush=True,
        )
        print(
            f"point the data_glove_ultra_wireless element at it: <port>{where}</port>", flush=True
        )

    def check() -> int | None:
        if emulator.disconnected.is_set():
            print("scenario finished: the line was hung up", flush=True)
            return 0
        return None

    return run(emulator, duration=args.duration, announce=announce, check=check)


if __name__ == "__main__":
    sys.exit(main())
