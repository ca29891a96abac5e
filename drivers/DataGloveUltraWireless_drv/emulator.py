"""A 5DT Data Glove Ultra Wireless receiver with gloves on ports A and B, on a pseudo-terminal,
independent of gadgetctl's input manager (it uses only :mod:`gadgetctl.emulation`).

The receiver streams 29-byte records (``<``, port, unused byte, fourteen 12-bit readings,
four status bytes, ``>``), the enabled gloves in turn, ``rate`` records per second, once a
driver has the line open (the first record waits in the line until then; opening the port
discards it):

``idle``        both hands rest half bent
``motion``      every sensor sweeps its range, each at its own pace
``buttons``     both hands step through an open hand and a fist (gestures 15 and 0)
``garbage``     motion with junk between records and records broken at their end
``disconnect``  ``disconnect_after`` records of motion, then the line is hung up
"""

from __future__ import annotations

import math
import os
import sys

from gadgetctl.emulation.device import STANDARD_SCENARIOS, PtyDeviceEmulator, pty_parser, run_pty

# The emulator keeps its own copy of the wire format so that a mistake in the driver cannot be
# mirrored here and go unnoticed by the tests.
SCENARIOS = STANDARD_SCENARIOS
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


class UltraGloveEmulator(PtyDeviceEmulator):
    """The receiver's side of the line on a pty pair. ``sent`` lists every good record sent
    as ``(port, readings)`` (not the first one, which waits for a driver)."""

    DEVICE = "UltraGlove"
    CATCH_UP = 0.05  # catch up at most a few records, never a burst after a stall

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
        super().__init__(
            scenario, rate, disconnect_after=disconnect_after, linger=linger, link=link, drain=0.5
        )
        self.ports = ports
        self.sent: list[tuple[int, tuple[int, ...]]] = []
        self.probe = (ports[0], readings(scenario, ports[0], 0))  # sent before a driver is there
        self._step = 0

    def on_open(self) -> None:
        # waits for a reader; opening the port discards it, unless it was still on its way
        self.write(encode_record(*self.probe))

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
        port = self.ports[step % len(self.ports)]
        scenario = "motion" if self.scenario in ("garbage", "disconnect") else self.scenario
        raw = readings(scenario, port, step)
        junk = GARBAGE[step % len(GARBAGE)] if self.scenario == "garbage" else b""
        self.sent.append((port, raw))
        self.write(junk + encode_record(port, raw))


def main(argv: list[str] | None = None) -> int:
    parser = pty_parser(
        "DataGloveUltraWireless_drv.emulator",
        "Emulate a 5DT Data Glove Ultra Wireless receiver (gloves on ports A and B) on a "
        "pseudo-terminal.",
        default_link=DEFAULT_LINK,
        rate=100.0,
        rate_help="records per second, both gloves together",
        disconnect_after=6,
    )
    parser.add_argument(
        "--gloves", choices=("A", "B", "AB"), default="AB", help="ports with a glove"
    )
    args = parser.parse_args(argv)
    emulator = UltraGloveEmulator(
        args.scenario,
        args.rate,
        ports=tuple("AB".index(p) for p in args.gloves),
        disconnect_after=args.disconnect_after,
        link=args.port or None,
    )
    return run_pty(
        emulator,
        title="5DT Data Glove Ultra Wireless",
        element="data_glove_ultra_wireless",
        duration=args.duration,
    )


if __name__ == "__main__":
    sys.exit(main())
