"""SDL virtual joysticks (``SDL_JoystickAttachVirtualEx``) that play scenarios.

A virtual joystick exists only inside the process that attaches it: SDL keeps it in the
process's own joystick list, and no other program (another ``gadgetctl monitor``, VR
Juggler) can see it. So this emulator is used *in the process that reads it*: tests attach
one and run an input manager beside it, and ``gadgetctl emulate SdlJoystick_drv`` runs a
self-contained demonstration: it attaches the joystick, reads it back through the driver's
own reader in the same process and prints what the driver decodes, once a second. It says
so when it starts; it cannot stand in for a joystick in another process.

Scenarios (``rate`` ticks a second):

* ``idle``: every axis centred, nothing pressed, set once;
* ``motion``: each axis sweeps a sine from -32768 to 32767 (:func:`axis_value`);
* ``buttons``: one button at a time pressed, then released (:func:`button_states`);
* ``hats``: each hat steps through the eight directions and centre (:func:`hat_value`);
* ``garbage``: motion, and every fourth tick a hat value no real hat gives (up and down at
  once, bits above 8): the driver counts each and reads centred, never faults;
  ``garbage_sent`` counts them;
* ``disconnect``: motion, detaching after ``disconnect_after`` ticks and attaching again
  ``down_time`` seconds later (SDL may give it another index; :attr:`index` follows).

Rumble: the joystick offers rumble; every request SDL passes on (strengths 0 to 65535, and
0, 0 when a rumble's duration ends) is kept in :attr:`SdlJoystickEmulator.rumbles`.
"""

from __future__ import annotations

import ctypes
import math
import sys
import threading
import time
from typing import Any

from gadgetctl.emulation import Console, emulator_parser, run
from gadgetctl.transport.sdl import SdlError, hub

from .standalone import AXIS_RANGE, SdlJoystickReader

SCENARIOS = ("idle", "motion", "buttons", "hats", "garbage", "disconnect")
PERIOD = 250  # ticks per motion cycle (2.5 s at 100 Hz)
HAT_STEPS = (0, 1, 3, 2, 6, 4, 12, 8, 9)  # centre, then clockwise from up
IMPOSSIBLE_HATS = (1 | 4, 2 | 8, 0x1F, 0xF0)  # up+down, right+left, all bits, high bits


def axis_value(tick: int, axis: int) -> int:
    """Axis ``axis`` at ``tick``: a sine over SDL's whole range (-32768 to 32767)."""
    s = math.sin(2.0 * math.pi * tick / PERIOD + axis)
    return max(-32768, min(32767, round(s * 32767.5 - 0.5)))


def button_states(tick: int, buttons: int) -> list[int]:
    """Button (tick // 2) % n pressed on even ticks, none on odd ones."""
    states = [0] * buttons
    if buttons and tick % 2 == 0:
        states[(tick // 2) % buttons] = 1
    return states


def hat_value(tick: int, hat: int) -> int:
    return HAT_STEPS[(tick + hat) % len(HAT_STEPS)]


def normalised(raw: int) -> float:
    """What Gadgeteer's analog proxy makes of raw axis value ``raw``."""
    low, high = AXIS_RANGE
    return (min(high, max(low, raw)) - low) / (high - low)


class SdlJoystickEmulator:
    """One SDL virtual joystick playing a scenario in a thread of this process."""

    def __init__(
        self,
        *,
        scenario: str = "motion",
        rate: float = 100.0,
        axes: int = 6,
        buttons: int = 12,
        hats: int = 1,
        name: str = "gadgetctl virtual joystick",
        disconnect_after: int = 50,
        down_time: float = 0.5,
        max_ticks: int | None = None,
        rumble: bool = True,
    ) -> None:
        if scenario not in SCENARIOS:
            raise ValueError(f"unknown scenario {scenario!r}; choose from {', '.join(SCENARIOS)}")
        if rate <= 0:
            raise ValueError("rate must be positive")
        if not (0 <= axes <= 64 and 0 <= buttons <= 256 and 0 <= hats <= 16):
            raise ValueError("counts out of range (axes 0-64, buttons 0-256, hats 0-16)")
        self.scenario, self.rate = scenario, rate
        self.num_axes, self.num_buttons, self.num_hats = axes, buttons, hats
        self.name = name
        self.disconnect_after, self.down_time = disconnect_after, down_time
        self.max_ticks = max_ticks
        self.offers_rumble = rumble
        self.tick = 0
        self.ticks_attached = 0  # ticks since the joystick was last attached
        self.attaches = 0
        self.detaches = 0
        self.garbage_sent = 0
        self.rumbles: list[tuple[int, int]] = []
        self.error: BaseException | None = None
        self.finished = threading.Event()
        self.console = Console()
        self.index: int | None = None
        self._instance: int | None = None
        self._handle: Any = None
        self._callbacks: Any = None
        self._held = False
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    # -- life cycle -------------------------------------------------------------------------

    def start(self) -> SdlJoystickEmulator:
        if self._thread is not None:
            return self
        hub().acquire()
        self._held = True
        try:
            self.attach()
            self.apply_tick(0)
        except BaseException:
            self.stop()
            raise
        self._stop.clear()
        self._thread = threading.Thread(target=self._run, name="sdl-emulator", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        thread, self._thread = self._thread, None
        if thread is not None:
            thread.join(timeout=5.0)
        if self._held:
            self.detach()
            self._held = False
            hub().release()

    def __enter__(self) -> SdlJoystickEmulator:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    @property
    def address(self) -> str:
        return f"SDL joystick index {self.index} (this process only)"

    @property
    def attached(self) -> bool:
        return self._handle is not None

    # -- plugging -----------------------------------------------------------------------------

    def attach(self) -> int:
        """Attach the virtual joystick (on the SDL thread); its device index."""
        with self._lock:
            if self._handle is None:
                hub().call(self._attach_on_hub)
                self.attaches += 1
            assert self.index is not None
            return self.index

    def detach(self) -> None:
        """Detach it: readers see it disconnected."""
        with self._lock:
            if self._handle is not None:
                hub().call(self._detach_on_hub)
                self.detaches += 1

    def _attach_on_hub(self) -> None:
        sdl = hub().sdl
        desc = sdl.SDL_VirtualJoystickDesc()
        desc.version = sdl.SDL_VIRTUAL_JOYSTICK_DESC_VERSION
        desc.type = sdl.SDL_JOYSTICK_TYPE_GAMECONTROLLER
        desc.naxes, desc.nbuttons, desc.nhats = self.num_axes, self.num_buttons, self.num_hats
        desc.name = self.name.encode()
        rumble = None
        if self.offers_rumble:
            rumble_type = dict(sdl.SDL_VirtualJoystickDesc._fields_)["Rumble"]
            rumble = rumble_type(self._on_rumble)
            desc.Rumble = rumble
        index = sdl.SDL_JoystickAttachVirtualEx(ctypes.byref(desc))
        if index < 0:
            raise SdlError(f"SDL cannot attach a virtual joystick: {sdl.SDL_GetError().decode()}")
        handle = sdl.SDL_JoystickOpen(index)
        if not handle:
            sdl.SDL_JoystickDetachVirtual(index)
            raise SdlError(f"SDL cannot open its virtual joystick: {sdl.SDL_GetError().decode()}")
        self._callbacks = (desc, rumble)  # SDL calls them for as long as it is attached
        self._handle, self.index = handle, index
        self._instance = sdl.SDL_JoystickInstanceID(handle)

    def _detach_on_hub(self) -> None:
        sdl = hub().sdl
        index = next(
            (
                i
                for i in range(sdl.SDL_NumJoysticks())
                if sdl.SDL_JoystickGetDeviceInstanceID(i) == self._instance
            ),
            None,
        )
        sdl.SDL_JoystickClose(self._handle)
        self._handle = None
        if index is not None:
            sdl.SDL_JoystickDetachVirtual(index)

    def _on_rumble(self, userdata: Any, low: int, high: int) -> int:
        self.rumbles.append((int(low), int(high)))
        return 0

    # -- values -------------------------------------------------------------------------------

    def set_axis(self, axis: int, value: int) -> bool:
        return self._set("SDL_JoystickSetVirtualAxis", axis, value)

    def set_button(self, button: int, value: int) -> bool:
        return self._set("SDL_JoystickSetVirtualButton", button, value)

    def set_hat(self, hat: int, value: int) -> bool:
        return self._set("SDL_JoystickSetVirtualHat", hat, value)

    def _set(self, function: str, unit: int, value: int) -> bool:
        """Set one value (SDL locks its joysticks; no pumping here). False when refused."""
        with self._lock:
            if self._handle is None:
                return False
            return getattr(hub().sdl, function)(self._handle, unit, value) == 0

    def apply_tick(self, tick: int) -> None:
        """Set every value the scenario has at ``tick``."""
        scenario = self.scenario
        moving = scenario in ("motion", "garbage", "disconnect")
        for axis in range(self.num_axes):
            self.set_axis(axis, axis_value(tick, axis) if moving else 0)
        pressed = (
            button_states(tick, self.num_buttons)
            if scenario == "buttons"
            else [0] * self.num_buttons
        )
        for button, state in enumerate(pressed):
            self.set_button(button, state)
        for hat in range(self.num_hats):
            value = hat_value(tick, hat) if scenario == "hats" else 0
            if scenario == "garbage" and tick % 4 == 3:
                value = IMPOSSIBLE_HATS[(tick // 4 + hat) % len(IMPOSSIBLE_HATS)]
                self.garbage_sent += 1
            self.set_hat(hat, value)

    # -- the scenario thread ------------------------------------------------------------------

    def _run(self) -> None:
        try:
            period = 1.0 / self.rate
            due = time.monotonic()
            while not self._stop.is_set():
                if self.max_ticks is not None and self.tick >= self.max_ticks:
                    break
                due += period
                self._stop.wait(max(0.0, due - time.monotonic()))
                if self._stop.is_set():
                    break
                self.tick += 1
                if self.scenario == "idle":
                    continue
                self.ticks_attached += 1
                if self.scenario == "disconnect" and self.ticks_attached >= self.disconnect_after:
                    self.ticks_attached = 0
                    self.console.stopped_sending(f"detached the joystick at tick {self.tick}")
                    self.detach()
                    if self._stop.wait(self.down_time):
                        break
                    self.attach()
                    self.console.say("attached the joystick again: sending")
                    self.console.resumed()
                    due = time.monotonic()
                self.apply_tick(self.tick)
        except BaseException as err:
            self.error = err
        finally:
            self.finished.set()


def main(argv: list[str] | None = None) -> int:
    """Command line: a one-process demonstration (see the module's description)."""
    parser = emulator_parser(
        "SdlJoystick_drv.emulator",
        "Attach an SDL virtual joystick and show what the SdlJoystick_drv reader decodes from "
        "it, in this one process (SDL virtual joysticks are invisible to other processes).",
        scenarios=SCENARIOS,
        default_scenario="motion",
        rate=100.0,
        rate_help="scenario ticks per second (default 100)",
    )
    parser.add_argument("--axes", type=int, default=6)
    parser.add_argument("--buttons", type=int, default=12)
    parser.add_argument("--hats", type=int, default=1)
    parser.add_argument(
        "--disconnect-after",
        type=int,
        default=200,
        metavar="N",
        help="ticks between detaching and attaching in the disconnect scenario",
    )
    args = parser.parse_args(argv)
    if args.rate <= 0 or args.disconnect_after <= 0:
        parser.error("--rate and --disconnect-after must be positive")
    try:
        emulator = SdlJoystickEmulator(
            scenario=args.scenario,
            rate=args.rate,
            axes=args.axes,
            buttons=args.buttons,
            hats=args.hats,
            disconnect_after=args.disconnect_after,
        )
    except ValueError as err:
        parser.error(str(err))
    demo = _Demo(emulator)

    def announce() -> None:
        print(
            f"SDL virtual joystick at index {emulator.index} ({args.scenario}, {args.rate:g} Hz, "
            f"{args.axes} axes, {args.buttons} buttons, {args.hats} hats)"
        )
        print(
            "note: it exists only in this process; no other program can open it. Below is "
            "what the SdlJoystick_drv reader decodes from it here, once a second.",
            flush=True,
        )

    return run(demo, duration=args.duration, announce=announce, check=demo.check)


class _Demo:
    """The emulator plus the driver's reader in one process, printing a line a second."""

    def __init__(self, emulator: SdlJoystickEmulator) -> None:
        self.emulator = emulator
        self.console = emulator.console  # run() prints its lines
        self.reader: SdlJoystickReader | None = None
        self._next = 0.0

    def start(self) -> None:
        self.emulator.start()

    def stop(self) -> None:
        if self.reader is not None:
            self.reader.close()
        self.emulator.stop()

    def check(self) -> int | None:
        if self.emulator.error is not None:
            print(f"error: {self.emulator.error}", file=sys.stderr)
            return 1
        reader = self.reader
        if reader is None and self.emulator.attached:
            reader = self.reader = SdlJoystickReader(self.emulator.index or 0)
            try:
                reader.open()
            except SdlError as err:
                print(f"reader: {err}")
                self.reader = None
                return None
        if reader is None:
            return None
        try:
            samples = reader.read(0.0)
        except SdlError as err:
            print(f"reader: {err}", flush=True)
            reader.close()
            self.reader = None
            return None
        now = time.monotonic()
        if samples and now >= self._next:
            self._next = now + 1.0
            last = samples[-1]
            axes = " ".join(f"{normalised(v):.2f}" for v in last.axes)
            buttons = "".join(str(b) for b in last.buttons)
            print(
                f"axes {axes} | buttons {buttons} | hats {list(last.hats)} | "
                f"polls {reader.polls} bad_hats {reader.bad_hats}",
                flush=True,
            )
        return None


if __name__ == "__main__":
    sys.exit(main())
