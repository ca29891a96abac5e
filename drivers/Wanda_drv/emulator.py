"""An Ascension Wanda on a pseudo-terminal, independent of gadgetctl's input manager (it uses
only the shared emulator scaffolding, :mod:`gadgetctl.emulation`).

It says ``M3`` once its pty is open (a pty carries no RTS to wait for); once a driver has
opened the line (the ``M3`` left the line's input queue: opening a port discards it, or it was
read) it steps its scenario ``rate`` times a second and sends a serial-mouse packet (3 bytes,
or 4 while the middle button is down) at a step where the ball is pushed off centre or a
button changed, and nothing otherwise: a real Wanda is silent at rest (VRPN ``vrpn_Wanda.C``),
and does not always send the centred packet when the ball is let go (neither does this one).
Packets are held back while the driver lags, so ``sent`` lists what the driver can read.
Scenarios:

``idle``        at rest: joystick centred, no button pressed, nothing sent
``motion``      the joystick circles (to its -34..34 limits), let go for ``REST`` steps
                (silent) after each turn
``buttons``     buttons 0, 1 (the middle one, 4-byte packets) and 2 press and release in turn,
                the ball at rest: one packet per change
``garbage``     motion, with junk and broken packets between the packets
``disconnect``  ``disconnect_after`` packets, then hang-up
"""

from __future__ import annotations

import math
import os
import sys

from gadgetctl.emulation.device import STANDARD_SCENARIOS, PtyDeviceEmulator, pty_parser, run_pty

SCENARIOS = STANDARD_SCENARIOS
DEFAULT_LINK = "/tmp/gadgetctl-wanda"
#: Seconds after the last write before the line counts as drained (the kernel moves what the
#: master wrote to the slave's input queue a moment later, and only then does FIONREAD count it).
QUIET = 0.1
#: Unread bytes beyond which packets are held back (no reader).
BACKLOG = 64

#: Steps of a turn of the ``motion`` circle, then of rest (the ball let go: silence).
TURN, REST = 90, 30

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
    if scenario == "motion" and step % (TURN + REST) >= TURN:
        return (0, 0, 0), (0, 0)  # let go
    if scenario in ("motion", "garbage", "disconnect"):
        t = step / 15.0
        return (0, 0, 0), (round(34 * math.cos(t)), round(34 * math.sin(t)))
    return (0, 0, 0), (0, 0)


def sends(now: Sample, before: Sample) -> bool:
    """Whether a Wanda sends a packet: the ball is off centre, or a button changed."""
    return now[1] != (0, 0) or now[0] != before[0]


class WandaEmulator(PtyDeviceEmulator):
    """The Wanda side on a pty pair. ``sent`` records each packet written as ``(buttons,
    axes)``."""

    DEVICE = "Wanda"
    SETTLE = QUIET

    def __init__(
        self,
        scenario: str = "motion",
        rate: float = 40.0,
        *,
        disconnect_after: int = 20,
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
        self.sent: list[Sample] = []
        self._step = 0
        self._state: Sample = ((0, 0, 0), (0, 0))  # at rest

    @property
    def reader(self) -> bool:
        """A driver has opened the line (packets flow from then on)."""
        return self.streaming.is_set()

    def on_open(self) -> None:
        self.write(b"M3")  # the serial mouse's hello, at power-up

    def sending(self) -> bool:
        # M3 waits in the line until a driver opens it (which discards it) or reads it
        if not self.streaming.is_set() and self.probe_taken():
            self.begin_sending()
        return self.streaming.is_set()

    def draining(self) -> bool:
        return not self.all_read()  # let a reading driver drain the line before it goes away

    def emit(self) -> None:
        if self.scenario == "disconnect" and len(self.sent) >= self.disconnect_after:
            self.hang_up_once_read()
            return
        if self.unread() > BACKLOG:
            return  # the reader fell behind: hold the packets back
        step, self._step = self._step, self._step + 1
        buttons, axes = controls(self.scenario, step)
        before, self._state = self._state, (buttons, axes)
        if not sends(self._state, before):
            return  # at rest: silence
        out = b""
        if self.scenario == "garbage":
            out += GARBAGE_CHUNKS[step % len(GARBAGE_CHUNKS)]
        out += encode_packet(buttons, axes)
        self.sent.append((buttons, axes))
        self.write(out)


def main(argv: list[str] | None = None) -> int:
    """Run the emulator until Ctrl-C, SIGTERM, SIGHUP or ``--duration`` seconds."""
    parser = pty_parser(
        "Wanda_drv.emulator",
        "Emulate an Ascension Wanda (serial mouse protocol) on a pseudo-terminal.",
        default_link=DEFAULT_LINK,
        rate=40.0,
        rate_help="packets per second (1200 baud 7N1 carries 44 three-byte packets)",
        disconnect_after=20,
        disconnect_help="packets before hang-up",
    )
    args = parser.parse_args(argv)
    emulator = WandaEmulator(
        args.scenario, args.rate, disconnect_after=args.disconnect_after, link=args.port or None
    )
    return run_pty(emulator, title="Wanda", element="wanda", duration=args.duration)


if __name__ == "__main__":
    sys.exit(main())
