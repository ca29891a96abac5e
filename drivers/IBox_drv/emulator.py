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

import math
import os
import sys

from gadgetctl.emulation.device import STANDARD_SCENARIOS, PtyDeviceEmulator, pty_parser, run_pty

#: Seconds after the last write before the line counts as drained: the kernel moves what the
#: master wrote to the slave's input queue a moment later, and only then does FIONREAD count it.
QUIET = 0.1
SCENARIOS = STANDARD_SCENARIOS
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


class IBoxEmulator(PtyDeviceEmulator):
    """The box side on a pty pair. ``sent`` records each valid packet as ``(buttons,
    analogs 0..3)``."""

    DEVICE = "IBox"
    SETTLE = QUIET

    def __init__(
        self,
        scenario: str = "motion",
        rate: float = 500.0,
        *,
        disconnect_after: int = 40,
        linger: float = 1.0,
        link: str | os.PathLike[str] | None = None,
    ) -> None:
        super().__init__(
            scenario,
            rate,
            disconnect_after=disconnect_after,
            linger=linger,
            link=link,
            drain=linger,
        )
        self.session = False
        self.queries: list[int] = []
        self.sent: list[Sample] = []
        self._text = bytearray()
        self._waiting: list[int] = []  # queries received, answered in order

    def draining(self) -> bool:
        return not self.all_read()  # let a reading driver drain the line before it goes away

    def on_byte(self, value: int) -> None:
        if 0x40 <= value < 0x80:  # letters: the text commands
            self._text.append(value)
            text = bytes(self._text)
            for word in (b"IMMC", b"BEGIN", b"END"):
                if text.endswith(word):
                    self._text.clear()
                    self.commands.append(word)
                    if word == b"IMMC":
                        self.write(b"IMMC")
                    elif word == b"BEGIN":
                        self.session = True
                        self.write(PRODUCT_ID + b"\0")
                    else:
                        self.session = False
                        self._waiting.clear()
                        self.streaming.clear()
            del self._text[:-8]
            return
        if value in INFO:
            self.commands.append(bytes((value,)))
            self.write(bytes((value,)) + INFO[value] + b"\0")
        elif value < 0x40 and self.session:
            self.queries.append(value)
            self.begin_sending()
            if len(self._waiting) < MAX_WAITING:  # a small input buffer; more are lost
                self._waiting.append(value)

    def emit(self) -> None:
        """Answer the oldest query waiting."""
        step = len(self.sent)
        if self.scenario == "disconnect" and step >= self.disconnect_after:
            self.hang_up_once_read()  # the query stays waiting until the line is hung up
            return
        query = self._waiting.pop(0)
        if not self._waiting:
            self.streaming.clear()
        buttons, analog = controls(self.scenario, step)
        out = b""
        if self.scenario == "garbage":
            out += GARBAGE_CHUNKS[step % len(GARBAGE_CHUNKS)]
        out += encode_packet(query, buttons, analog, timer=step & 0x3FFF)
        self.sent.append((buttons, analog))
        self.write(out)


def main(argv: list[str] | None = None) -> int:
    """Run the emulator until Ctrl-C, SIGTERM, SIGHUP or ``--duration`` seconds."""
    parser = pty_parser(
        "IBox_drv.emulator",
        "Emulate an Immersion Interface Box (HCI) on a pseudo-terminal.",
        default_link=DEFAULT_LINK,
        rate=500.0,
        rate_help="queries answered per second at most",
        disconnect_after=40,
        disconnect_help="packets before hang-up",
    )
    args = parser.parse_args(argv)
    emulator = IBoxEmulator(
        args.scenario, args.rate, disconnect_after=args.disconnect_after, link=args.port or None
    )
    return run_pty(emulator, title="IBox", element="ibox", duration=args.duration)


if __name__ == "__main__":
    sys.exit(main())
