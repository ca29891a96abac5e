"""Two US Digital encoders on an SEI bus behind a pseudo-terminal, independent of gadgetctl's
input manager (it uses only the shared emulator scaffolding, :mod:`gadgetctl.emulation`).

Encoder 1 is a table's tilt (degrees) and encoder 2 its height (inches). Each read-position
command (``0x10 | address``) is answered with the command byte and the position as a
big-endian float; other addresses stay silent, as an empty bus address does.

``idle``        the table stands still (tilt 0, height 30 in)
``motion``      the table tilts (±30 degrees) and rises and falls (20..40 in)
``buttons``     the table steps between three preset positions (encoders have no buttons)
``garbage``     motion, with junk before replies, corrupt positions and unasked bytes
``disconnect``  ``disconnect_after`` answers, then the line is hung up
"""

from __future__ import annotations

import math
import os
import select
import struct
import sys
import threading
import time
from pathlib import Path

from gadgetctl.emulation import PseudoTerminal, emulator_parser, run

# The emulator keeps its own copy of the wire format so that a mistake in the driver cannot be
# mirrored here and go unnoticed by the tests.
SCENARIOS = ("idle", "motion", "buttons", "garbage", "disconnect")
DEFAULT_LINK = "/tmp/gadgetctl-encoder"
TILT, HEIGHT = 1, 2
PRESETS = ((0.0, 30.0), (15.0, 36.0), (-20.0, 24.5))
#: Junk of the ``garbage`` scenario: never the command bytes 0x11 / 0x12 themselves.
JUNK = (b"\x00\x7f", b"\xff" * 7, b"\x13\x10\x20")
NAN = b"\x7f\xc0\x00\x00"


def encode_reply(address: int, value: float) -> bytes:
    return bytes([0x10 | address]) + struct.pack(">f", value)


def table_position(scenario: str, step: int) -> tuple[float, float]:
    """(tilt degrees, height inches) of a step, as float32 values."""
    if scenario == "idle":
        tilt, height = 0.0, 30.0
    elif scenario == "buttons":
        tilt, height = PRESETS[step // 5 % len(PRESETS)]
    else:
        tilt, height = 30.0 * math.sin(step / 15), 30.0 + 10.0 * math.sin(step / 23)
    as_f32 = struct.Struct(">f")
    return tuple(as_f32.unpack(as_f32.pack(v))[0] for v in (tilt, height))  # type: ignore[return-value]


class SerialEncoderEmulator:
    """The encoders' side of the bus on a pty pair. ``rate`` caps answers per second;
    ``sent`` lists every good answer as ``(address, position)``."""

    def __init__(
        self,
        scenario: str = "motion",
        rate: float = 500.0,
        *,
        disconnect_after: int = 10,
        link: str | os.PathLike[str] | None = None,
    ) -> None:
        if scenario not in SCENARIOS:
            raise ValueError(f"unknown scenario {scenario!r}; choose from {', '.join(SCENARIOS)}")
        if rate <= 0:
            raise ValueError("rate must be positive")
        self.scenario, self.rate, self.disconnect_after = scenario, rate, disconnect_after
        self.link = Path(link) if link is not None else None
        self.address = ""
        self.sent: list[tuple[int, float]] = []
        self.commands: list[int] = []
        self.dropped_bytes = 0
        self.streaming = threading.Event()  # set at the first command: a driver is there
        self.disconnected = threading.Event()
        self._pty = PseudoTerminal(self.link)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._step = 0
        self._answers = 0
        self._next_due = 0.0
        self._lock = threading.Lock()

    def start(self) -> SerialEncoderEmulator:
        if self._thread is None:
            self.address = self._pty.open().address
            self._stop.clear()
            self._thread = threading.Thread(target=self._run, name="encoder-emulator", daemon=True)
            self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5)
            self._thread = None
        self._pty.close()

    def __enter__(self) -> SerialEncoderEmulator:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def _run(self) -> None:
        while not self._stop.is_set() and self._pty.master >= 0:
            try:
                ready, _, _ = select.select([self._pty.master], [], [], 0.05)
                if ready:
                    for value in os.read(self._pty.master, 256):
                        self._on_command(value)
            except OSError:
                break

    def _on_command(self, value: int) -> None:
        self.commands.append(value)
        self.streaming.set()
        if value & 0xF0 != 0x10 or (value & 0x0F) not in (TILT, HEIGHT):
            return  # nobody at that address
        if self.scenario == "disconnect" and self._answers >= self.disconnect_after:
            self.disconnected.set()
            self._pty.hang_up()
            return
        wait = self._next_due - time.monotonic()
        if wait > 0:
            self._stop.wait(wait)
        self._next_due = max(self._next_due, time.monotonic() - 0.05) + 1.0 / self.rate
        address = value & 0x0F
        scenario = "motion" if self.scenario in ("garbage", "disconnect") else self.scenario
        tilt, height = table_position(scenario, self._step)
        if address == HEIGHT:
            self._step += 1
        position = tilt if address == TILT else height
        self._answers += 1
        n = self._answers
        if self.scenario == "garbage" and n % 4 == 0:
            self._write(bytes([value]) + NAN)  # a corrupt position: not in ``sent``
            return
        junk = JUNK[n % len(JUNK)] if self.scenario == "garbage" and n % 4 == 1 else b""
        self.sent.append((address, position))
        self._write(junk + encode_reply(address, position))
        if self.scenario == "garbage" and n % 4 == 2:
            self._write(b"\x00\x01")  # unasked bytes after an answer

    def send_raw(self, data: bytes) -> None:
        """Write bytes to the driver as they are (for tests)."""
        self._write(data)

    def _write(self, data: bytes) -> None:
        with self._lock:
            self.dropped_bytes += len(data) - self._pty.write(data)


def main(argv: list[str] | None = None) -> int:
    parser = emulator_parser(
        "SerialEncoder_drv.emulator",
        "Emulate two US Digital encoders (a table's tilt and height) on an SEI bus over a "
        "pseudo-terminal.",
        scenarios=SCENARIOS,
        default_scenario="motion",
        rate=500.0,
        rate_help="answers per second at most",
    )
    parser.add_argument(
        "--port",
        default=DEFAULT_LINK,
        help=f"symlink to create pointing at the pty (default {DEFAULT_LINK}, where "
        "drivers/SerialEncoder_drv/example.jconf looks; '' for none)",
    )
    parser.add_argument("--disconnect-after", type=int, default=10, help="answers before hang-up")
    args = parser.parse_args(argv)
    emulator = SerialEncoderEmulator(
        args.scenario, args.rate, disconnect_after=args.disconnect_after, link=args.port or None
    )

    def announce() -> None:
        where = str(emulator.link) if emulator.link is not None else emulator.address
        print(f"SEI encoder emulator ({args.scenario}) on {emulator.address}", flush=True)
        print(f"point the serial_encoder element at it: <port>{where}</port>", flush=True)

    def check() -> int | None:
        if emulator.disconnected.is_set():
            print("scenario finished: the line was hung up", flush=True)
            return 0
        return None

    return run(emulator, duration=args.duration, announce=announce, check=check)


if __name__ == "__main__":
    sys.exit(main())
