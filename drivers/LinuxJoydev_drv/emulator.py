"""A joystick device file emulated with a FIFO: the device's side of the joydev protocol.

Knows nothing of gadgetctl's input manager; the FIFO's life cycle and the command line come
from the shared emulator scaffolding, :mod:`gadgetctl.emulation`. The emulator creates a FIFO and waits for a reader to open it.
For every reader it writes the burst of initial states a real joydev sends on open (one
``JS_EVENT_BUTTON | JS_EVENT_INIT`` record per button, then one ``JS_EVENT_AXIS | JS_EVENT_INIT``
per axis) and then the live records of the chosen scenario at the chosen rate. When the reader
goes away it waits for the next one; the scenario is paused meanwhile.

Scenarios: ``idle`` (the initial burst only), ``motion`` (every axis follows a sine, see
:func:`motion_axis_value`), ``buttons`` (each button pressed and released, then each axis sent to
its low end, the middle, its high end and the middle), ``garbage`` (``motion`` with random bytes
or a cut-off record after every tick) and ``disconnect`` (``motion`` until ``disconnect_after``
live records, then the device is unplugged: the FIFO is replaced by a new one and closed, so the
reader sees end of file and can open the path again).

Run ``python emulator.py --help`` (or ``gadgetctl emulate LinuxJoydev_drv``) for the command line.
"""

from __future__ import annotations

import math
import os
import random
import shutil
import struct
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from pathlib import Path

from gadgetctl.emulation import Console, Fifo, emulator_parser, ended, run

EVENT_FORMAT = "=IhBB"  # native byte order, standard sizes, no padding
JS_EVENT_BUTTON = 0x01
JS_EVENT_AXIS = 0x02
JS_EVENT_INIT = 0x80
AXIS_LOW = -32767
AXIS_HIGH = 32767

SCENARIOS = ("idle", "motion", "buttons", "garbage", "disconnect")
DEFAULT_PATH = "/tmp/gadgetctl-js0"  # the command line's FIFO, named in example.jconf
MOTION_PERIOD = 64  # ticks per full sine period in the motion scenario

Event = tuple[int, int, int]  # (type, number, value)
Item = Event | bytes  # a record to send, or raw bytes (garbage)


def motion_axis_value(tick: int, axis: int, axes: int, period: int = MOTION_PERIOD) -> int:
    """The value of ``axis`` at ``tick`` in the motion scenario (phase-shifted sines)."""
    phase = tick / period + axis / max(axes, 1)
    return round(AXIS_HIGH * math.sin(2.0 * math.pi * phase))


def buttons_script(buttons: int, axes: int) -> list[list[Event]]:
    """One cycle of the buttons scenario, one list of records per tick."""
    steps: list[list[Event]] = []
    for b in range(buttons):
        steps.append([(JS_EVENT_BUTTON, b, 1)])
        steps.append([(JS_EVENT_BUTTON, b, 0)])
    for a in range(axes):
        for value in (AXIS_LOW, 0, AXIS_HIGH, 0):
            steps.append([(JS_EVENT_AXIS, a, value)])
    return steps


class JoydevEmulator:
    """Serves joydev records through a FIFO at ``address``.

    ``path`` names the FIFO; without it ``js0`` is created in ``directory`` (or in a new
    temporary directory, removed by :meth:`stop`). ``rate`` is in ticks per second.
    ``poll_interval`` is how often the emulator looks for a reader. ``time_base_ms`` is the
    record time of tick 0 (a kernel reports milliseconds since boot, so a large number).
    ``sent`` records every valid record written, as ``(time, value, type, number)``.
    """

    def __init__(
        self,
        path: str | os.PathLike[str] | None = None,
        *,
        directory: str | os.PathLike[str] | None = None,
        scenario: str = "motion",
        rate: float = 100.0,
        buttons: int = 12,
        axes: int = 6,
        disconnect_after: int = 20,
        seed: int = 0,
        time_base_ms: int = 18_000_000,
        poll_interval: float = 0.002,
    ) -> None:
        if scenario not in SCENARIOS:
            raise ValueError(f"unknown scenario {scenario!r}; choose from {', '.join(SCENARIOS)}")
        if rate <= 0:
            raise ValueError("rate must be positive")
        self._path = Path(path) if path is not None else None
        self._fifo: Fifo | None = None
        self._directory = Path(directory) if directory is not None else None
        self._tempdir: Path | None = None
        self.scenario = scenario
        self.rate = rate
        self.num_buttons = buttons
        self.num_axes = axes
        self.disconnect_after = disconnect_after
        self.time_base_ms = time_base_ms
        self.poll_interval = poll_interval
        self.buttons = [0] * buttons
        self.axes = [0] * axes
        self.sent: list[tuple[int, int, int, int]] = []
        self.connections = 0
        self.dropped_ticks = 0
        self.error: BaseException | None = None
        self.console = Console()
        self._rng = random.Random(seed)
        self._tick = 0
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._lock = threading.Lock()

    @property
    def address(self) -> str:
        """The FIFO path to give as ``port_name``."""
        if self._path is None:
            raise RuntimeError("the emulator has not been started")
        return str(self._path)

    # -- life cycle -------------------------------------------------------------------------

    def start(self) -> JoydevEmulator:
        """Create the FIFO and start serving it in a thread."""
        if self._thread is not None:
            return self
        if self._path is None:
            if self._directory is None:
                self._tempdir = Path(tempfile.mkdtemp(prefix="joydev-emu-"))
                self._directory = self._tempdir
            self._path = self._directory / "js0"
        self._fifo = Fifo(self._path).create()  # an existing FIFO is taken over, a file refused
        self._stop.clear()
        self._thread = threading.Thread(target=self._serve, name="joydev-emulator", daemon=True)
        self._thread.start()
        return self

    def stop(self, timeout: float = 2.0) -> None:
        """Stop serving and remove the FIFO (and the temporary directory, if one was made)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout)
            self._thread = None
        if self._fifo is not None:
            self._fifo.remove()
            self._fifo = None
        if self._tempdir is not None:
            shutil.rmtree(self._tempdir, ignore_errors=True)
            self._tempdir = None
            self._directory = None
            self._path = None

    def __enter__(self) -> JoydevEmulator:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def sent_events(self) -> list[tuple[int, int, int, int]]:
        """A copy of ``sent``, safe to take while the emulator runs."""
        with self._lock:
            return list(self.sent)

    # -- serving ------------------------------------------------------------------------------

    def _serve(self) -> None:
        try:
            ticks = self._script()
            while not self._stop.is_set():
                fd = self._wait_for_reader()
                if fd is None:
                    return
                self.console.client_connected(f"{self.address} opened for reading")
                why = "emulator stopping"
                try:
                    if self._serve_reader(fd, ticks):
                        why = "unplugged by the disconnect scenario"
                except BrokenPipeError:
                    why = "closed by the reader"  # wait for the next one
                finally:
                    os.close(fd)
                self.console.client_disconnected(self.address, why)
        except BaseException as exc:  # reported through .error, the thread must not die silently
            self.error = exc

    def _wait_for_reader(self) -> int | None:
        """Open the FIFO for writing once a reader has it open."""
        assert self._fifo is not None
        return self._fifo.open_writer(self._stop, self.poll_interval)

    def _serve_reader(self, fd: int, ticks: Iterator[list[Item]]) -> bool:
        """Serve one reader until it goes (raises BrokenPipeError), the emulator stops
        (False) or the disconnect scenario unplugs the device (True)."""
        self.connections += 1
        now = self._time_ms()
        burst = [(JS_EVENT_BUTTON | JS_EVENT_INIT, i, v) for i, v in enumerate(self.buttons)]
        burst += [(JS_EVENT_AXIS | JS_EVENT_INIT, i, v) for i, v in enumerate(self.axes)]
        self._write(fd, burst, now)
        live = 0
        deadline = time.monotonic()
        while not self._stop.is_set():
            deadline += 1.0 / self.rate
            delay = deadline - time.monotonic()
            if delay > 0 and self._stop.wait(delay):
                return False
            self._tick += 1
            items = next(ticks)
            if self.scenario == "disconnect":
                items = items[: self.disconnect_after - live]  # stop after exactly N records
            live += self._write(fd, items, self._time_ms())
            if self.scenario == "disconnect" and live >= self.disconnect_after:
                self.console.stopped_sending(f"unplugged after {live} events")
                self._unplug()
                return True
        return False

    def _write(self, fd: int, items: list[Item], time_ms: int) -> int:
        """Write one tick in a single write (atomic on a pipe); returns the records sent."""
        if not items:
            return 0
        chunks: list[bytes] = []
        records: list[tuple[int, int, int, int]] = []
        stamp = time_ms & 0xFFFFFFFF
        for item in items:
            if isinstance(item, bytes):
                chunks.append(item)
                continue
            kind, number, value = item
            chunks.append(struct.pack(EVENT_FORMAT, stamp, value, kind, number))
            records.append((stamp, value, kind, number))
        with self._lock:  # logged before the write, so a fast reader never gets ahead of the log
            first = len(self.sent)
            self.sent.extend(records)
        try:
            os.write(fd, b"".join(chunks))
        except BaseException as exc:
            with self._lock:
                del self.sent[first:]
            if isinstance(exc, BlockingIOError):
                self.dropped_ticks += 1  # the reader is not keeping up; a kernel drops too
                return 0
            raise
        for _t, value, kind, number in records:
            state = self.buttons if kind & JS_EVENT_BUTTON else self.axes
            state[number] = value
        return sum(1 for r in records if not r[2] & JS_EVENT_INIT)

    def _unplug(self) -> None:
        """Replace the FIFO by a new one, so the old reader gets EOF and a reopen finds the new one."""
        assert self._fifo is not None
        self._fifo.replace()

    def _time_ms(self) -> int:
        return self.time_base_ms + round(self._tick * 1000.0 / self.rate)

    # -- scenarios ----------------------------------------------------------------------------

    def _script(self) -> Iterator[list[Item]]:
        if self.scenario == "idle":
            while True:
                yield []
        elif self.scenario == "buttons":
            cycle = buttons_script(self.num_buttons, self.num_axes)
            while True:
                yield from (list(step) for step in cycle)
        else:
            yield from self._motion(garbage=self.scenario == "garbage")

    def _motion(self, garbage: bool) -> Iterator[list[Item]]:
        tick = 0
        while True:
            tick += 1
            items: list[Item] = []
            for a in range(self.num_axes):
                value = motion_axis_value(tick, a, self.num_axes)
                if value != self.axes[a]:
                    items.append((JS_EVENT_AXIS, a, value))
            if garbage:
                items.append(self._garbage_bytes(tick))
            yield items

    def _garbage_bytes(self, tick: int) -> bytes:
        """Random bytes, or the first 1..7 bytes of a record, never a whole record."""
        if tick % 2:
            return self._rng.randbytes(self._rng.randint(1, 7))
        fake = struct.pack(
            EVENT_FORMAT,
            self._time_ms() & 0xFFFFFFFF,
            self._rng.randint(AXIS_LOW, AXIS_HIGH),
            self._rng.choice((JS_EVENT_AXIS, JS_EVENT_BUTTON)),
            self._rng.randrange(max(self.num_axes, 1)),
        )
        return fake[: self._rng.randint(1, 7)]


def main(argv: list[str] | None = None) -> int:
    """Command line: serve a FIFO until Ctrl-C, SIGTERM, SIGHUP or ``--duration`` seconds."""
    parser = emulator_parser(
        "LinuxJoydev_drv.emulator",
        "Emulate a Linux joystick with a FIFO.",
        scenarios=SCENARIOS,
        default_scenario="motion",
        rate=100.0,
        rate_help="ticks per second (default 100)",
    )
    parser.add_argument(
        "--path",
        default=DEFAULT_PATH,
        help=f"FIFO to create (default {DEFAULT_PATH}, where example.jconf points)",
    )
    parser.add_argument("--buttons", type=int, default=12)
    parser.add_argument("--axes", type=int, default=6)
    parser.add_argument(
        "--disconnect-after",
        type=int,
        default=20,
        metavar="N",
        help="live records per connection in the disconnect scenario",
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of the garbage scenario")
    args = parser.parse_args(argv)
    if args.rate <= 0 or args.buttons < 0 or args.axes < 0 or args.buttons + args.axes > 255:
        parser.error("--rate must be positive; --buttons and --axes between 0 and 255")
    emulator = JoydevEmulator(
        args.path,
        scenario=args.scenario,
        rate=args.rate,
        buttons=args.buttons,
        axes=args.axes,
        disconnect_after=args.disconnect_after,
        seed=args.seed,
    )

    def announce() -> None:
        print(
            f"Linux joystick emulator ({args.scenario}, {args.rate:g} Hz, "
            f"{args.buttons} buttons, {args.axes} axes)"
        )
        print(f"Point the linux_joydev element at it: <port_name>{emulator.address}</port_name>")
        print("Press Ctrl-C to stop.", flush=True)

    return run(emulator, duration=args.duration, announce=announce, check=ended(emulator))


if __name__ == "__main__":
    sys.exit(main())
