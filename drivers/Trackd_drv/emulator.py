"""A stand-in for trackd: creates the tracker and controller segments in System V shared
memory, writes them at ``rate`` ticks a second, and removes them when it stops (also on
Ctrl-C, SIGTERM and SIGHUP, through :func:`gadgetctl.emulation.run`).

Scenarios:

* ``idle``: the tick-0 state, written once;
* ``motion``: sensors circle, valuators swing (:func:`sensor_pose`, :func:`valuator_value`);
* ``buttons``: one button at a time pressed, then released;
* ``garbage``: motion, with every other tick a header that claims more sensors and buttons
  than the segments hold (a bad record for the reader, never a fault);
* ``disconnect``: motion, removing both segments after ``disconnect_after`` ticks with a
  reader attached and making them again ``down_time`` seconds later.

The keys default to the ones in ``example.jconf`` (4148 for the sensors, 4147 for the
controller, as in VR Juggler's ``sim.trackd.jconf``).
"""

from __future__ import annotations

import math
import sys
import threading

from gadgetctl.emulation import Console, emulator_parser, ended, run

from .standalone import _sysv_ipc, encode_controller, encode_tracker

SCENARIOS = ("idle", "motion", "buttons", "garbage", "disconnect")
SENSOR_KEY = 4148
CONTROLLER_KEY = 4147
PERIOD = 100  # ticks per motion cycle


def sensor_pose(tick: int, sensor: int) -> tuple[float, float, float, float, float, float]:
    """Sensor ``sensor`` at ``tick``: x, y, z (feet), azim, elev, roll (degrees)."""
    phase = 2.0 * math.pi * tick / PERIOD
    return (
        sensor + math.cos(phase),
        5.0 + 0.5 * sensor,
        math.sin(phase),
        (30.0 * sensor + 3.6 * tick) % 360.0 - 180.0,
        10.0 * math.sin(phase),
        5.0 * sensor,
    )


def valuator_value(tick: int, valuator: int) -> float:
    """Valuator ``valuator`` at ``tick``, between -1 and 1."""
    return math.sin(2.0 * math.pi * tick / PERIOD + valuator)


def button_states(tick: int, buttons: int) -> list[int]:
    """The buttons scenario at ``tick``: button (tick // 2) % n pressed on even ticks."""
    states = [0] * buttons
    if buttons and tick % 2 == 0:
        states[(tick // 2) % buttons] = 1
    return states


class TrackdEmulator:
    """Writes trackd segments under ``sensor_key`` and ``controller_key`` in a thread."""

    def __init__(
        self,
        sensor_key: int = SENSOR_KEY,
        controller_key: int = CONTROLLER_KEY,
        *,
        scenario: str = "motion",
        rate: float = 60.0,
        sensors: int = 2,
        buttons: int = 4,
        valuators: int = 2,
        disconnect_after: int = 20,
        down_time: float = 0.5,
    ) -> None:
        if scenario not in SCENARIOS:
            raise ValueError(f"unknown scenario {scenario!r}; choose from {', '.join(SCENARIOS)}")
        if rate <= 0:
            raise ValueError("rate must be positive")
        self._ipc = _sysv_ipc()
        self.sensor_key, self.controller_key = sensor_key, controller_key
        self.scenario, self.rate = scenario, rate
        self.num_sensors, self.num_buttons, self.num_valuators = sensors, buttons, valuators
        self.disconnect_after, self.down_time = disconnect_after, down_time
        self.tick = 0
        self.writes = 0
        self.bad_writes = 0
        self.removals = 0
        self.error: BaseException | None = None
        self._segments: list = []
        self._stop = threading.Event()
        self.console = Console()
        self._attached = False  # a reader has the sensor segment attached
        self._thread: threading.Thread | None = None
        self._lock = threading.Lock()

    # -- life cycle -------------------------------------------------------------------------

    def start(self) -> TrackdEmulator:
        if self._thread is None:
            self._create()
            self._write()
            self._stop.clear()
            self._thread = threading.Thread(target=self._serve, name="trackd-emulator", daemon=True)
            self._thread.start()
        return self

    def stop(self) -> None:
        """Stop writing and remove the segments."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(5.0)
            self._thread = None
        with self._lock:
            self._remove()

    def __enter__(self) -> TrackdEmulator:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def _sizes(self) -> tuple[int, int]:
        return (
            len(encode_tracker([(0.0,) * 6] * self.num_sensors)),
            len(encode_controller([0] * self.num_buttons, [0.0] * self.num_valuators)),
        )

    def _create(self) -> None:
        ipc = self._ipc
        for key, size in zip((self.sensor_key, self.controller_key), self._sizes(), strict=True):
            try:  # a segment left by an emulator that was killed: ours to replace
                ipc.remove_shared_memory(ipc.SharedMemory(key).id)
            except ipc.ExistentialError:
                pass
            self._segments.append(ipc.SharedMemory(key, ipc.IPC_CREX, 0o644, size))

    def _remove(self) -> None:
        for memory in self._segments:
            try:
                memory.detach()
            except self._ipc.Error:
                pass
            try:
                memory.remove()
            except self._ipc.Error:
                pass
        self._segments = []

    # -- writing ----------------------------------------------------------------------------

    def _state(self) -> tuple[bytes, bytes]:
        tick = self.tick
        stamp = (tick // 1000, (tick % 1000) * 1000)
        motion = self.scenario in ("motion", "garbage", "disconnect")
        t = tick if motion else 0
        sensors = [sensor_pose(t, i) for i in range(self.num_sensors)]
        valuators = [valuator_value(t, j) for j in range(self.num_valuators)]
        if self.scenario == "buttons":
            buttons = button_states(tick, self.num_buttons)
        else:
            buttons = [1 if j == 0 else 0 for j in range(self.num_buttons)]
        bad = self.scenario == "garbage" and tick % 2 == 1
        tracker = encode_tracker(sensors, stamp, claimed=self.num_sensors + 3 if bad else None)
        controller = encode_controller(
            buttons, valuators, stamp, claimed_buttons=self.num_buttons + 50 if bad else None
        )
        return tracker, controller

    def _write(self) -> None:
        tracker, controller = self._state()
        with self._lock:
            if not self._segments:
                return
            self._segments[0].write(tracker)
            self._segments[1].write(controller)
            self.writes += 1
            if self.scenario == "garbage" and self.tick % 2 == 1:
                self.bad_writes += 1

    def _watch_readers(self) -> None:
        """Say when a reader attaches a segment and when the last one detaches."""
        with self._lock:
            try:
                others = max((m.number_attached - 1 for m in self._segments), default=0)
            except self._ipc.Error:
                others = 0
        where = f"shared memory keys {self.sensor_key}, {self.controller_key}"
        if others > 0 and not self._attached:
            self._attached = True
            self.console.client_connected(f"{where} attached")
        elif others <= 0 and self._attached:
            self._attached = False
            self.console.client_disconnected(where, "detached or removed")

    def _serve(self) -> None:
        try:
            live = 0
            while not self._stop.wait(1.0 / self.rate):
                self._watch_readers()
                if self.scenario == "idle":
                    continue
                self.tick += 1
                self._write()
                # the disconnect scenario counts what a reader had the chance to see: the
                # segments go only after ``disconnect_after`` writes with a reader attached
                live += self._attached
                if self.scenario == "disconnect" and live >= self.disconnect_after:
                    self.console.stopped_sending(f"removed the segments after {live} writes")
                    with self._lock:
                        self._remove()
                        self.removals += 1
                    self._watch_readers()
                    if self._stop.wait(self.down_time):
                        return
                    with self._lock:
                        self._create()
                    self.console.say("segments made again: sending")
                    self.console.resumed()
                    live = 0
        except BaseException as exc:  # reported through .error, the thread must not die silently
            self.error = exc


def main(argv: list[str] | None = None) -> int:
    """Command line: serve the segments until Ctrl-C, SIGTERM, SIGHUP or ``--duration``."""
    parser = emulator_parser(
        "Trackd_drv.emulator",
        "Emulate trackd's shared-memory segments.",
        scenarios=SCENARIOS,
        default_scenario="motion",
        rate=60.0,
        rate_help="writes per second (default 60)",
    )
    parser.add_argument("--sensor-key", type=int, default=SENSOR_KEY)
    parser.add_argument("--controller-key", type=int, default=CONTROLLER_KEY)
    parser.add_argument("--sensors", type=int, default=2)
    parser.add_argument("--buttons", type=int, default=4)
    parser.add_argument("--valuators", type=int, default=2)
    parser.add_argument(
        "--disconnect-after",
        type=int,
        default=20,
        metavar="N",
        help="ticks with a reader attached between removals in the disconnect scenario",
    )
    args = parser.parse_args(argv)
    if args.rate <= 0 or min(args.sensors, args.buttons, args.valuators) < 0:
        parser.error("--rate must be positive; counts 0 or more")
    emulator = TrackdEmulator(
        args.sensor_key,
        args.controller_key,
        scenario=args.scenario,
        rate=args.rate,
        sensors=args.sensors,
        buttons=args.buttons,
        valuators=args.valuators,
        disconnect_after=args.disconnect_after,
    )

    def announce() -> None:
        print(
            f"trackd emulator ({args.scenario}, {args.rate:g} Hz, {args.sensors} sensors, "
            f"{args.buttons} buttons, {args.valuators} valuators)"
        )
        print(f"trackd_sensor: <shared_memory_key>{args.sensor_key}</shared_memory_key>")
        print(f"trackd_controller: <shared_memory_key>{args.controller_key}</shared_memory_key>")
        print("Press Ctrl-C to stop.", flush=True)

    return run(emulator, duration=args.duration, announce=announce, check=ended(emulator))


if __name__ == "__main__":
    sys.exit(main())
