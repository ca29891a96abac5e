"""A TUIO touch source emulated on loopback: the sender's side of TUIO 1.1 cursors. Knows nothing
of gadgetctl's input manager (the command line comes from the shared emulator scaffolding,
:mod:`gadgetctl.emulation`). Bundles go as UDP datagrams to ``127.0.0.1:port`` only. OSC is
written here in a few lines (:func:`osc_message`, :func:`osc_bundle`), independently of the
driver's decoder and of python-osc (which the conformance tests use as a third opinion).

Each frame is one OSC bundle per source, as TUIO 1.1 trackers send them:
``/tuio/2Dcur source NAME@ADDRESS``, ``alive ...``, a ``set`` per cursor, ``fseq n``. With
``sources`` above 1 every source sends its own bundle each frame, with its own session ids
(the same numbers in each source, which a client must keep apart) and its own frame numbers.
``late_every`` N > 0 sends, after every Nth frame, a late bundle: an older ``fseq`` saying
every finger lifted, which a client must drop as the reference TuioClient does.

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
import struct
import sys

from gadgetctl.emulation import emulator_parser, run
from gadgetctl.emulation.command import ended
from gadgetctl.emulation.network import STANDARD_SCENARIOS, UdpFrameSender

SCENARIOS = STANDARD_SCENARIOS
ADDRESS = "/tuio/2Dcur"
PHASE = 20  # frames a finger stays down or up in the buttons scenario
#: OSC's time tag meaning "at once".
IMMEDIATELY = b"\x00\x00\x00\x00\x00\x00\x00\x01"
#: How far back a late bundle's frame number is.
LATE_BY = 3


def _padded(raw: bytes) -> bytes:
    return raw + b"\x00" * (4 - len(raw) % 4)


def osc_message(address: str, *args: object) -> bytes:
    """One OSC message: ints as ``i``, floats as ``f``, strings as ``s``."""
    tags, data = ",", b""
    for value in args:
        if isinstance(value, str):
            tags, data = tags + "s", data + _padded(value.encode("ascii"))
        elif isinstance(value, float):
            tags, data = tags + "f", data + struct.pack(">f", value)
        else:
            tags, data = tags + "i", data + struct.pack(">i", value)
    return _padded(address.encode("ascii")) + _padded(tags.encode("ascii")) + data


def osc_bundle(*elements: bytes) -> bytes:
    """An OSC bundle of ``elements`` (messages or bundles), to be done at once."""
    return b"#bundle\x00" + IMMEDIATELY + b"".join(struct.pack(">i", len(e)) + e for e in elements)


def message(*args: object) -> bytes:
    """A ``/tuio/2Dcur`` message."""
    return osc_message(ADDRESS, *args)


def source_name(index: int) -> str:
    """The TUIO 1.1 source name of source ``index``."""
    return f"gadgetctl-tuio-{index}@127.0.0.1"


def cursor_position(frame: int, index: int, moving: bool, source: int = 0) -> tuple[float, float]:
    """x, y (0 to 1) of cursor ``index`` of source ``source``."""
    t = frame if moving else 0
    x = 0.05 + 0.09 * index + 0.02 * math.sin(0.1 * t)
    return (x, 0.5 + 0.2 * math.cos(0.1 * t) - 0.3 * source)


def sessions(frame: int, cursors: int, scenario: str) -> list[tuple[int, int]]:
    """(session id, cursor index) of the fingers down in ``frame``."""
    if scenario != "buttons":
        return [(k + 1, k) for k in range(cursors)]
    phase = frame // PHASE
    if frame % PHASE >= PHASE - 5:  # every finger lifted at the end of a phase
        return []
    return [(1000 * phase + k + 1, k) for k in range(cursors) if (phase + k) % 2 == 0]


def frame_bundle(
    frame: int,
    cursors: int,
    scenario: str,
    source: int | None = 0,
    fseq: int | None = None,
) -> bytes:
    """One TUIO frame of source ``source`` (None: no ``source`` message, as TUIO 1.0) as an
    OSC bundle, numbered ``fseq`` (default: ``frame``)."""
    moving = scenario not in ("idle", "buttons")
    down = sessions(frame, cursors, scenario)
    contents = [] if source is None else [message("source", source_name(source))]
    contents.append(message("alive", *(s for s, _ in down)))
    for session, index in down:
        x, y = cursor_position(frame, index, moving, source or 0)
        contents.append(message("set", session, x, y, 0.0, 0.0, 0.0))
    contents.append(message("fseq", frame if fseq is None else fseq))
    return osc_bundle(*contents)


def late_bundle(frame: int, source: int = 0) -> bytes:
    """A bundle of source ``source`` numbered ``LATE_BY`` frames before ``frame``, saying that
    every finger lifted: late, it must change nothing."""
    return osc_bundle(
        message("source", source_name(source)),
        message("alive"),
        message("fseq", max(1, frame - LATE_BY)),
    )


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
        sources: int = 1,
        late_every: int = 0,
    ) -> None:
        if cursors < 0:
            raise ValueError("cursors must not be negative")
        if not 1 <= sources <= 16:
            raise ValueError("sources must be between 1 and 16")
        if late_every < 0:
            raise ValueError("late_every must not be negative")
        super().__init__(
            port,
            scenario=scenario,
            rate=rate,
            disconnect_after=disconnect_after,
            max_frames=max_frames,
            first_frame=first_frame,
        )
        self.cursors = cursors
        self.sources = sources
        self.late_every = late_every
        self.late_sent = 0
        self.frames_sent = 0
        self.garbage = {"bad_datagrams": 0, "unknown_sessions": 0, "bare_messages": 0}
        self._rng = random.Random(seed)

    def send_frame(self, n: int) -> None:
        for source in range(self.sources):
            self.send_raw(frame_bundle(n, self.cursors, self.scenario, source))
        self.frames_sent += 1
        if self.late_every and n % self.late_every == 0 and n > LATE_BY:
            for source in range(self.sources):
                self.send_raw(late_bundle(n, source))
            self.late_sent += 1
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
            return osc_bundle(message("set", 999_999, 0.5, 0.5, 0.0, 0.0, 0.0))
        # a bare message, no bundle (upstream threw): the current alive list, valid
        self.garbage["bare_messages"] += 1
        alive = sessions(n, self.cursors, self.scenario)
        return message("alive", *(s for s, _ in alive))


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
    parser.add_argument(
        "--sources", type=int, default=1, help="TUIO sources, each its own bundles (default 1)"
    )
    parser.add_argument(
        "--late-every",
        type=int,
        default=0,
        metavar="N",
        help="after every Nth frame, a late bundle (an older fseq) that lifts every finger",
    )
    args = parser.parse_args(argv)
    try:
        emulator = TuioEmulator(
            args.port,
            scenario=args.scenario,
            rate=args.rate,
            cursors=args.cursors,
            disconnect_after=args.disconnect_after,
            seed=args.seed,
            sources=args.sources,
            late_every=args.late_every,
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
