"""A TUIO touch source emulated on loopback: the sender's side of TUIO 1.x cursors, built
with ``python-osc``. Knows nothing of gadgetctl's input manager (the command line comes from
the shared emulator scaffolding, :mod:`gadgetctl.emulation`). Bundles go as UDP datagrams to
``127.0.0.1:port`` only.

Each frame is one OSC bundle: ``/tuio/2Dcur alive ...``, a ``set`` per cursor, ``fseq n``.
Scenarios: ``idle`` (the cursors rest), ``motion`` (they move), ``buttons`` (fingers touch
down and lift in turn, each touch a new session: the even fingers, all up, the odd ones, all
up, ...), ``garbage`` (``motion``, and after every
frame a datagram that is not OSC, a cut-off bundle, a ``set`` for a session never made
alive, or a bare message rather than a bundle) and ``disconnect`` (``motion`` for
``disconnect_after`` frames, then the sender closes).

Run ``python emulator.py --help`` (or ``gadgetctl emulate TUIO_drv``) for the command line.
"""

from __future__ import annotations

import math
import random
import sys

from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder
from pythonosc.osc_message_builder import OscMessageBuilder

from gadgetctl.emulation import emulator_parser, run
from gadgetctl.emulation.network import STANDARD_SCENARIOS, UdpFrameSender, ended

SCENARIOS = STANDARD_SCENARIOS
ADDRESS = "/tuio/2Dcur"
PHASE = 20  # frames a finger stays down or up in the buttons scenario


def cursor_position(frame: int, index: int, moving: bool) -> tuple[float, float]:
    """x, y (0 to 1) of cursor ``index``."""
    t = frame if moving else 0
    return (0.05 + 0.09 * index + 0.02 * math.sin(0.1 * t), 0.5 + 0.2 * math.cos(0.1 * t))


def sessions(frame: int, cursors: int, scenario: str) -> list[tuple[int, int]]:
    """(session id, cursor index) of the fingers down in ``frame``."""
    if scenario != "buttons":
        return [(k + 1, k) for k in range(cursors)]
    phase = frame // PHASE
    if frame % PHASE >= PHASE - 5:  # every finger lifted at the end of a phase
        return []
    return [(1000 * phase + k + 1, k) for k in range(cursors) if (phase + k) % 2 == 0]


def message(*args: object) -> OscMessageBuilder:
    builder = OscMessageBuilder(ADDRESS)
    for value in args:
        builder.add_arg(value, "f" if isinstance(value, float) else None)
    return builder


def frame_bundle(frame: int, cursors: int, scenario: str) -> bytes:
    """One TUIO frame as an OSC bundle."""
    moving = scenario not in ("idle", "buttons")
    down = sessions(frame, cursors, scenario)
    bundle = OscBundleBuilder(IMMEDIATELY)
    bundle.add_content(message("alive", *(s for s, _ in down)).build())
    for session, index in down:
        x, y = cursor_position(frame, index, moving)
        bundle.add_content(message("set", session, x, y, 0.0, 0.0, 0.0).build())
    bundle.add_content(message("fseq", frame).build())
    return bundle.build().dgram


class TuioEmulator(UdpFrameSender):
    """Sends TUIO frames to ``127.0.0.1:port`` at ``rate`` frames per second. ``frames_sent``
    counts the frames; the garbage scenario counts its extras in ``garbage``."""

    NAME = "tuio"

    def __init__(
        self,
        port: int = 3333,
        *,
        scenario: str = "motion",
        rate: float = 60.0,
        cursors: int = 3,
        disconnect_after: int = 10,
        max_frames: int | None = None,
        first_frame: int = 1,
        seed: int = 0,
    ) -> None:
        if cursors < 0:
            raise ValueError("cursors must not be negative")
        super().__init__(
            port,
            scenario=scenario,
            rate=rate,
            disconnect_after=disconnect_after,
            max_frames=max_frames,
            first_frame=first_frame,
        )
        self.cursors = cursors
        self.frames_sent = 0
        self.garbage = {"bad_datagrams": 0, "unknown_sessions": 0, "bare_messages": 0}
        self._rng = random.Random(seed)

    def send_frame(self, n: int) -> None:
        self.send_raw(frame_bundle(n, self.cursors, self.scenario))
        self.frames_sent += 1
        if self.scenario == "garbage":
            self.send_raw(self._garbage(n))

    def _garbage(self, n: int) -> bytes:
        kind = n % 4
        if kind == 0:  # not OSC at all
            self.garbage["bad_datagrams"] += 1
            return b"\xff" + self._rng.randbytes(self._rng.randint(8, 40))
        if kind == 1:  # a bundle cut off inside an element
            self.garbage["bad_datagrams"] += 1
            good = frame_bundle(n, max(1, self.cursors), self.scenario)
            return good[: len(good) - 7]
        if kind == 2:  # a set for a session never made alive (upstream crashed)
            self.garbage["unknown_sessions"] += 1
            bundle = OscBundleBuilder(IMMEDIATELY)
            bundle.add_content(message("set", 999_999, 0.5, 0.5, 0.0, 0.0, 0.0).build())
            return bundle.build().dgram
        # a bare message, no bundle (upstream threw): the current alive list, valid
        self.garbage["bare_messages"] += 1
        alive = sessions(n, self.cursors, self.scenario)
        return message("alive", *(s for s, _ in alive)).build().dgram


def main(argv: list[str] | None = None) -> int:
    """Command line: send frames until Ctrl-C, SIGTERM, SIGHUP or ``--duration`` seconds."""
    parser = emulator_parser(
        "TUIO_drv.emulator",
        "Emulate a TUIO multi-touch source on loopback UDP.",
        scenarios=SCENARIOS,
        default_scenario="buttons",
        rate=60.0,
        rate_help="frames per second (default 60)",
    )
    parser.add_argument(
        "--port", type=int, default=3333, help="UDP port on 127.0.0.1 to send to (default 3333)"
    )
    parser.add_argument("--cursors", type=int, default=3, help="fingers (default 3)")
    parser.add_argument("--disconnect-after", type=int, default=10, metavar="N")
    parser.add_argument("--seed", type=int, default=0, help="seed of the garbage scenario")
    args = parser.parse_args(argv)
    try:
        emulator = TuioEmulator(
            args.port,
            scenario=args.scenario,
            rate=args.rate,
            cursors=args.cursors,
            disconnect_after=args.disconnect_after,
            seed=args.seed,
        )
    except ValueError as exc:
        parser.error(str(exc))

    def announce() -> None:
        print(f"TUIO emulator ({args.scenario}, {args.rate:g} Hz) sending to {emulator.address}")
        print(f"Point the TUIO_drv element at it: <port>{args.port}</port>")
        print("Press Ctrl-C to stop.", flush=True)

    return run(emulator, duration=args.duration, announce=announce, check=ended(emulator))


if __name__ == "__main__":
    sys.exit(main())
