"""SDL2's joystick subsystem for a whole process, through PySDL2 (the maintained binding; its
SDL2 library comes from the ``pysdl2-dll`` package or the system).

SDL keeps one joystick state per process and wants it updated from one thread. So every SDL
call that initialises, opens, updates, closes or quits goes through one :class:`SdlHub` per
process: a daemon thread that initialises the joystick subsystem when its first user comes
(``acquire``), runs other threads' requests (``call``), updates the joysticks on a fixed
grid of ``rate`` polls a second and hands each open joystick's state to its
:class:`OpenJoystick`, and quits the subsystem when its last user leaves (``release``). Two
devices of one process therefore share one SDL: stopping one does not pull SDL from under
the other (upstream Gadgeteer called ``SDL_Quit`` from each device's thread).

SDL is told not to install its own SIGINT/SIGTERM handlers (they would turn Ctrl-C into an
SDL event nobody reads) and to ignore joystick events: the hub reads state, as Gadgeteer's
driver did, so no event queue grows.

Imports nothing else from gadgetctl, so a driver's standalone half may use it.
"""

from __future__ import annotations

import ctypes
import math
import queue
import threading
import time
import warnings
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

INSTALL_HINT = "pip install PySDL2 pysdl2-dll"
_MAX_BACKLOG = 2000  # readings kept per joystick for a reader that falls behind


class SdlUnavailable(ImportError):
    """PySDL2 or its SDL2 library cannot be loaded (one line, naming what to install)."""


class SdlError(RuntimeError):
    """SDL refused a request; the message carries SDL_GetError()."""


class SdlJoystickMissing(SdlError):
    """No joystick at the device index asked for."""


class SdlJoystickLost(SdlError):
    """The joystick went away (unplugged, or a virtual joystick detached)."""


_sdl_module: Any = None


def load_sdl() -> Any:
    """The ``sdl2`` module; raises :class:`SdlUnavailable` with one line when PySDL2 or an
    SDL2 library is missing. PySDL2's note about which library it found is silenced."""
    global _sdl_module
    if _sdl_module is not None:
        return _sdl_module
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            import sdl2
    except ImportError:
        raise SdlUnavailable(f"SDL joysticks need the PySDL2 package: {INSTALL_HINT}") from None
    except Exception as err:  # PySDL2 raises RuntimeError when it finds no SDL2 library
        first = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
        raise SdlUnavailable(
            f"PySDL2 found no usable SDL2 library ({first}): {INSTALL_HINT}"
        ) from None
    _sdl_module = sdl2
    return sdl2


def sdl_version() -> str:
    sdl = load_sdl()
    version = sdl.SDL_version()
    sdl.SDL_GetVersion(ctypes.byref(version))
    return f"{version.major}.{version.minor}.{version.patch}"


def _error(sdl: Any) -> str:
    text = sdl.SDL_GetError()
    return text.decode("utf-8", "replace") if text else "no reason given"


def _text(raw: bytes | None) -> str:
    return raw.decode("utf-8", "replace") if raw else ""


@dataclass(frozen=True, slots=True)
class JoystickInfo:
    """What SDL says about the joystick at a device index."""

    index: int
    name: str
    instance_id: int
    virtual: bool


@dataclass(frozen=True, slots=True)
class JoystickReading:
    """One poll of an open joystick: raw SDL values."""

    timestamp: float  # time.perf_counter() seconds
    axes: tuple[int, ...]  # -32768 .. 32767
    buttons: tuple[int, ...]  # 0 or 1
    hats: tuple[int, ...]  # SDL_HAT_* bits, as SDL reports them (unchecked)


class OpenJoystick:
    """A joystick opened through the hub. Readings queue up until :meth:`read` takes them."""

    def __init__(
        self,
        hub: SdlHub,
        index: int,
        handle: Any,
        info: JoystickInfo,
        counts: tuple[int, int, int],
        has_rumble: bool,
        rate: float,
    ) -> None:
        self.hub = hub
        self.index = index
        self.info = info
        self.name = info.name
        self.num_axes, self.num_buttons, self.num_hats = counts
        self.has_rumble = has_rumble
        self.rate = rate
        self.polls = 0
        self.overflowed = 0  # readings dropped because the reader fell behind
        self._handle = handle
        self._cond = threading.Condition()
        self._readings: deque[JoystickReading] = deque()
        self._lost: str | None = None
        self._closed = False

    # -- the reader's side ----------------------------------------------------------------

    def read(self, timeout: float) -> list[JoystickReading]:
        """Every reading since the previous call, waiting up to ``timeout`` seconds for one.
        Raises :class:`SdlJoystickLost` once the joystick is gone (after the last readings)."""
        with self._cond:
            if not self._readings and self._lost is None and not self._closed:
                self._cond.wait(timeout)
            taken = list(self._readings)
            self._readings.clear()
            if not taken:
                if self._lost is not None:
                    raise SdlJoystickLost(self._lost)
                if self._closed:
                    raise SdlJoystickLost(f"SDL joystick {self.index} is closed")
            return taken

    def rumble(self, low: float, high: float, duration: float) -> bool:
        """Rumble the low- and high-frequency motors (0 to 1) for ``duration`` seconds
        (``math.inf``, or longer than SDL takes: as long as SDL takes; 0 or less, or strengths
        0, stop the motors: SDL would read 0 ms as no end); False when the joystick has no
        rumble, SDL refused, or a strength or the duration is NaN."""
        if not self.has_rumble or self._lost is not None or self._closed:
            return False
        if math.isnan(low) or math.isnan(high) or math.isnan(duration):
            return False
        ms = round(min(float(0xFFFFFFFF), duration * 1000.0)) if duration > 0.0 else 0
        lo = round(max(0.0, min(1.0, low)) * 0xFFFF) if ms else 0
        hi = round(max(0.0, min(1.0, high)) * 0xFFFF) if ms else 0
        return self.hub.call(self._rumble_on_hub, lo, hi, ms) == 0

    def close(self) -> None:
        """Close the joystick (SDL counts opens, so another user of it keeps it)."""
        if not self._closed:
            self.hub.call(self.hub._close, self)

    @property
    def lost(self) -> str | None:
        return self._lost

    # -- the hub's side -------------------------------------------------------------------

    def _rumble_on_hub(self, low: int, high: int, ms: int) -> int:
        if self._handle is None:
            return -1
        return int(self.hub.sdl.SDL_JoystickRumble(self._handle, low, high, ms))

    def _poll(self, sdl: Any, now: float) -> bool:
        """Read the state; False once the joystick is detached."""
        handle = self._handle
        if not sdl.SDL_JoystickGetAttached(handle):
            self._mark_lost(f"SDL joystick {self.index} ({self.name}) was disconnected")
            return False
        reading = JoystickReading(
            now,
            tuple(sdl.SDL_JoystickGetAxis(handle, i) for i in range(self.num_axes)),
            tuple(sdl.SDL_JoystickGetButton(handle, i) for i in range(self.num_buttons)),
            tuple(sdl.SDL_JoystickGetHat(handle, i) for i in range(self.num_hats)),
        )
        self.polls += 1
        with self._cond:
            if len(self._readings) >= _MAX_BACKLOG:
                self._readings.popleft()
                self.overflowed += 1
            self._readings.append(reading)
            self._cond.notify_all()
        return True

    def _mark_lost(self, reason: str) -> None:
        with self._cond:
            self._lost = reason
            self._cond.notify_all()

    def _mark_closed(self) -> None:
        with self._cond:
            self._closed = True
            self._handle = None
            self._cond.notify_all()


class SdlHub:
    """The one thread of a process that talks to SDL's joystick subsystem."""

    default_rate = 100.0  # polls a second when no open joystick asks for more

    def __init__(self) -> None:
        self.sdl: Any = None
        self._lock = threading.Lock()
        self._users = 0
        self._thread: threading.Thread | None = None
        self._requests: queue.SimpleQueue = queue.SimpleQueue()
        self._wake = threading.Event()
        self._stop = False
        self._open: list[OpenJoystick] = []
        self.polls = 0

    # -- users ----------------------------------------------------------------------------

    def acquire(self) -> None:
        """Become a user: the first one starts the thread and initialises SDL's joysticks.
        Raises :class:`SdlUnavailable` or :class:`SdlError`."""
        sdl = load_sdl()
        with self._lock:
            if self._thread is None:
                self.sdl = sdl
                self._stop = False
                started: queue.SimpleQueue = queue.SimpleQueue()
                thread = threading.Thread(
                    target=self._main, args=(started,), name="gadgetctl-sdl", daemon=True
                )
                thread.start()
                failure = started.get()
                if failure is not None:
                    thread.join()
                    raise failure
                self._thread = thread
            self._users += 1

    def release(self) -> None:
        """Stop being a user; the last one closes what is open, quits SDL's joystick
        subsystem and ends the thread."""
        with self._lock:
            if self._users == 0:
                return
            self._users -= 1
            if self._users or self._thread is None:
                return
            thread, self._thread = self._thread, None
            self._stop = True
            self._wake.set()
            # joined under the lock, so a new first user waits until SDL is really quit
            # (the thread never takes the lock)
            thread.join(timeout=5.0)

    def call(self, fn: Callable[..., Any], *args: Any, timeout: float = 5.0) -> Any:
        """Run ``fn(*args)`` on the hub's thread and return its result (or raise its error)."""
        if threading.current_thread() is self._thread:
            return fn(*args)
        if self._thread is None:
            raise SdlError("SDL is not initialised (no user holds the hub)")
        done = threading.Event()
        box: list[Any] = [None, None]
        self._requests.put((fn, args, box, done))
        self._wake.set()
        if not done.wait(timeout):
            raise SdlError(f"the SDL thread did not answer within {timeout:g} s")
        if box[1] is not None:
            raise box[1]
        return box[0]

    # -- requests usable through call() ----------------------------------------------------

    def joysticks(self) -> list[JoystickInfo]:
        """Every joystick SDL sees now (call on the hub thread)."""
        sdl = self.sdl
        sdl.SDL_JoystickUpdate()
        found = []
        for index in range(max(0, sdl.SDL_NumJoysticks())):
            found.append(
                JoystickInfo(
                    index,
                    _text(sdl.SDL_JoystickNameForIndex(index)),
                    int(sdl.SDL_JoystickGetDeviceInstanceID(index)),
                    bool(sdl.SDL_JoystickIsVirtual(index)),
                )
            )
        return found

    def open(self, index: int, rate: float | None = None) -> OpenJoystick:
        """Open the joystick at device ``index``, polled ``rate`` times a second."""
        return self.call(self._open_on_hub, index, rate or self.default_rate)

    def _open_on_hub(self, index: int, rate: float) -> OpenJoystick:
        sdl = self.sdl
        present = self.joysticks()
        if not 0 <= index < len(present):
            seen = ", ".join(f"{j.index}: {j.name}" for j in present) or "none"
            raise SdlJoystickMissing(f"no SDL joystick {index} (SDL sees {len(present)}: {seen})")
        handle = sdl.SDL_JoystickOpen(index)
        if not handle:
            raise SdlError(f"SDL cannot open joystick {index}: {_error(sdl)}")
        counts = (
            max(0, sdl.SDL_JoystickNumAxes(handle)),
            max(0, sdl.SDL_JoystickNumButtons(handle)),
            max(0, sdl.SDL_JoystickNumHats(handle)),
        )
        has_rumble = bool(sdl.SDL_JoystickHasRumble(handle))
        joystick = OpenJoystick(self, index, handle, present[index], counts, has_rumble, rate)
        joystick._poll(sdl, time.perf_counter())  # the state at opening is the first reading
        self._open.append(joystick)
        return joystick

    def _close(self, joystick: OpenJoystick) -> None:
        if joystick in self._open:
            self._open.remove(joystick)
        handle = joystick._handle
        joystick._mark_closed()
        if handle is not None:
            self.sdl.SDL_JoystickClose(handle)

    # -- the thread -----------------------------------------------------------------------

    def _init(self) -> None:
        sdl = self.sdl
        sdl.SDL_SetHint(sdl.SDL_HINT_NO_SIGNAL_HANDLERS, b"1")
        sdl.SDL_SetHint(sdl.SDL_HINT_JOYSTICK_ALLOW_BACKGROUND_EVENTS, b"1")
        if sdl.SDL_InitSubSystem(sdl.SDL_INIT_JOYSTICK) != 0:
            raise SdlError(f"SDL cannot initialise its joysticks: {_error(sdl)}")
        sdl.SDL_JoystickEventState(sdl.SDL_IGNORE)

    def _main(self, started: queue.SimpleQueue) -> None:
        try:
            self._init()
        except BaseException as err:
            started.put(err)
            return
        started.put(None)
        next_poll = time.monotonic()
        try:
            while not self._stop:
                self._wake.clear()  # before the requests: a later call() wakes the wait below
                self._run_requests()
                if self._open:
                    now = time.monotonic()
                    if now >= next_poll:
                        self._poll_all()
                        step = 1.0 / max(j.rate for j in self._open) if self._open else 0.01
                        next_poll = max(next_poll + step, now - 0.05)
                    self._wake.wait(max(0.0, next_poll - time.monotonic()))
                else:
                    self._wake.wait(0.05)
                    next_poll = time.monotonic()
        finally:
            self._run_requests()
            for joystick in list(self._open):
                self._close(joystick)
            self.sdl.SDL_QuitSubSystem(self.sdl.SDL_INIT_JOYSTICK)

    def _poll_all(self) -> None:
        sdl = self.sdl
        sdl.SDL_JoystickUpdate()
        now = time.perf_counter()
        self.polls += 1
        for joystick in list(self._open):
            if not joystick._poll(sdl, now):
                self._close(joystick)

    def _run_requests(self) -> None:
        while True:
            try:
                fn, args, box, done = self._requests.get_nowait()
            except queue.Empty:
                return
            try:
                box[0] = fn(*args)
            except BaseException as err:
                box[1] = err
            done.set()


_hub = SdlHub()


def hub() -> SdlHub:
    """The process's SDL hub."""
    return _hub
