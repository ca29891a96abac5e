"""``waveform_device``: gadgetctl's own synthetic device, for demos, tests and benchmarks.

Analog channels follow a sine, triangle, square or noise wave; buttons are square waves;
positions move on a circle, spin in place or follow a figure-eight; with an event period,
a hat switch steps through its directions and command and string samples arrive once per
period. Sample k is taken at ``start + k / rate`` exactly, and its values depend only on
k and the configuration (noise is a seeded stream that can be entered at any k), so a
device is deterministic for a given seed.

Samples are published as numpy batches cut from a block computed ahead (never a sample
whose time has not come), by whichever comes first: each frame publishes, just before its
swap, every sample that has come due (so a frame carries samples up to its own instant,
however fast frames run), and the shared scheduler publishes what is due when no frame did
for ``FRAME_GRACE`` seconds, counted from its start before the first frame (so a stalled
frame loop still finds every sample, or the store's count of those dropped over its cap).
While frames run, the scheduler leaves the devices alone: it looks in on a grid of instants
shared by every device (one pass), and standing in takes at most about ``STAND_IN_SHARE``
of a core (:class:`_StandIn`): with 10,000 devices a pass cost about a second, and a pass
every ``FRAME_GRACE`` while a long first frame was written slowed that frame, which let
more passes in.

The input manager updates the waveform devices of a frame together (:attr:`FRAME_GROUP`):
one clock reading, then, with numpy over all of them at once, each device's window of its
block that came due; those windows go to the group's
:class:`~gadgetctl.input.samples.SharedWindows` (each store makes its frame from it when
read). Devices configured alike whose block ran out (or who have none yet: the first frame)
get their next blocks together, from one cut of their shared values, and their frame stays
the usual one. Only a device whose frame is not that usual one (its values are its own and
its block runs out, no sample came due, it is not running, its window holds an event) is
updated alone: with an event period, a device's frame is its own only when one of its events
comes due, not for the whole block that holds one.
"""

from __future__ import annotations

import bisect
import math
import threading
import time
import weakref
import zlib
from collections.abc import Sequence
from dataclasses import dataclass
from enum import StrEnum

import numpy as np

from gadgetctl.input.clock import now
from gadgetctl.input.device import DeviceState, SamplingMode
from gadgetctl.input.devicetypes import Analog, Command, Digital, Hat, HatState, Position, String
from gadgetctl.input.errors import DeviceConfigError
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.samples import FEW_SLOTS, SharedWindows
from gadgetctl.jccl.access import ElementAccess, read_float

MAX_RATE = 100_000.0
BLOCK_SECONDS = 0.5
#: Seconds without a frame after which the scheduler publishes again (frames publish first).
#: Long enough that a frame loop falling behind under load is not also fighting the
#: scheduler thread for the GIL; a frame publishes, and counts over the cap, what came due.
FRAME_GRACE = 0.25
#: At most this share of a core goes to standing in for frames (see :class:`_StandIn`).
STAND_IN_SHARE = 0.1
#: The longest time between two passes standing in for frames.
STAND_IN_MAX_SPACING = 5.0
#: Seconds of publishing the scheduler may do at once while standing in (a few hundred
#: devices), before :data:`STAND_IN_SHARE` paces it.
STAND_IN_BURST = 0.05
#: Seconds before a device's block ends when the next block is computed ahead, between frames.
AHEAD_SECONDS = 0.1
#: Blocks computed ahead between two frames: at most one per this many seconds since the
#: previous time (one per frame at 1 kHz, more at lower frame rates), so that the work done
#: ahead does not make the next frame late.
PREPARE_PACE = 0.001
_RUNNING = DeviceState.RUNNING
#: Before any moment: one float shared by every device not yet published by a frame
#: (``-math.inf`` written in a method makes a new float each time: 10,000 of them).
_NEVER = -math.inf
#: Held while a waveform device publishes (its frame, the scheduler's stand-in) and while a
#: frame group is updated: one lock for all of them, so that a group frame takes it once.
_PUBLISHING = threading.Lock()
HAT_SEQUENCE = (HatState.CENTERED, HatState.UP, HatState.RIGHT, HatState.DOWN, HatState.LEFT)
#: The sequence as one unit's column: a block's hat values are taken from it in one array.
_HAT_COLUMN = np.asarray(HAT_SEQUENCE, dtype=np.int8)[:, None]


class _StandIn:
    """What the scheduler of one input manager may spend standing in for its waveform devices.

    Publishing is paid from a budget that fills at ``STAND_IN_SHARE`` of a second per second
    up to ``STAND_IN_BURST``: a device looked in on when it is spent is left to the next
    frame, or to a later look, which publishes the same samples (they depend on time alone).
    The looks themselves are on a grid of instants shared by every device, ``FRAME_GRACE``
    apart, or further while the looks and what they publish take more than that share of
    a core (measured over windows of one spacing). One for the devices of each input
    manager (:func:`_stand_in_for`); its scheduler thread calls :meth:`spent`."""

    def __init__(self) -> None:
        self.spacing = FRAME_GRACE
        self.window = -math.inf  # when the current measuring window began
        self.cost = 0.0  # seconds spent looking in since then
        self.budget = STAND_IN_BURST
        self.filled = -math.inf  # when the budget was last filled

    def next_look(self, last: float) -> float:
        """The first grid instant at least one spacing after ``last``."""
        spacing = self.spacing
        return (math.floor(last / spacing) + 2) * spacing

    def may_publish(self, moment: float) -> bool:
        """Whether the budget allows a device to publish at ``moment``."""
        if self.filled != -math.inf:
            refill = (moment - self.filled) * STAND_IN_SHARE
            self.budget = min(STAND_IN_BURST, self.budget + max(0.0, refill))
        self.filled = moment
        return self.budget > 0.0

    def spent(self, moment: float, seconds: float, *, published: bool) -> None:
        """A device was looked in on at ``moment`` for ``seconds`` (and published)."""
        if published:
            self.budget -= seconds
        if self.window == -math.inf:
            self.window = moment
        self.cost += seconds
        elapsed = moment + seconds - self.window
        if elapsed >= self.spacing:
            share = self.cost / elapsed
            wanted = self.spacing * share / STAND_IN_SHARE
            self.spacing = min(STAND_IN_MAX_SPACING, max(FRAME_GRACE, wanted))
            self.window, self.cost = moment + seconds, 0.0


#: Devices outside any input manager (no context) share this one.
_STAND_IN = _StandIn()
_STAND_INS: weakref.WeakKeyDictionary[object, _StandIn] = weakref.WeakKeyDictionary()


def _stand_in_for(context: object | None) -> _StandIn:
    """The stand-in budget and grid of the devices of one input manager (its context)."""
    if context is None:
        return _STAND_IN
    found = _STAND_INS.get(context)
    if found is None:
        found = _STAND_INS[context] = _StandIn()
    return found


class Wave(StrEnum):
    SINE = "sine"
    TRIANGLE = "triangle"
    SQUARE = "square"
    NOISE = "noise"


class Path(StrEnum):
    CIRCLE = "circle"
    SPIN = "spin"
    FIGURE_EIGHT = "figure_eight"


@dataclass(frozen=True)
class AnalogChannel:
    wave: Wave
    frequency: float


@dataclass(frozen=True)
class PositionChannel:
    path: Path
    period: float
    radius: float


#: The events of a block without any (shared: an empty list for each block of 10,000
#: devices was half a megabyte).
_NO_EVENTS: tuple[tuple[int, int], ...] = ()

#: The sample index of "no event to come" (past every sample a block can hold).
NO_EVENT = np.iinfo(np.int64).max


class Block:
    """Samples ``start`` .. ``end - 1`` computed ahead: their ``timestamps``, per kind their
    values (``items``: (kind, array) pairs) and ``events`` ((sample index, event number)).
    Slotted, the values not kept in a dict too: every device holds one or two."""

    __slots__ = ("end", "events", "items", "start", "timestamps")

    def __init__(
        self,
        start: int,
        timestamps: np.ndarray,
        data: dict[DeviceKind, np.ndarray] | tuple[tuple[DeviceKind, np.ndarray], ...],
        events: Sequence[tuple[int, int]],
    ) -> None:
        self.start = start
        self.timestamps = timestamps
        # (the pairs themselves when given as such: blocks of devices alike share them)
        self.items = data if type(data) is tuple else tuple(data.items())
        self.events = events if events else _NO_EVENTS  # (most blocks have none)
        self.end = start + len(timestamps)

    def event_after(self, index: int) -> int:
        """The sample index of the first event at or after sample ``index`` (:data:`NO_EVENT`
        when there is none): a window that ends at or before it holds no event."""
        events = self.events
        if not events:
            return NO_EVENT
        found = bisect.bisect_left(events, (index,))  # (events are in the order of their samples)
        return events[found][0] if found < len(events) else NO_EVENT

    @property
    def data(self) -> dict[DeviceKind, np.ndarray]:
        """The values of each kind."""
        return dict(self.items)


def _per_channel(access: ElementAccess, prop: str, count: int) -> list[float]:
    """One number per channel: the written ones, then the property's default."""
    return [read_float(access.string(prop, i)) for i in range(count)]


def _enum(kind: type[StrEnum], text: str, prop: str) -> StrEnum:
    try:
        return kind(text)
    except ValueError:
        allowed = ", ".join(m.value for m in kind)
        raise DeviceConfigError(f"{prop} {text!r} is not one of {allowed}") from None


def _positive(value: float, what: str) -> float:
    if not value > 0.0:
        raise DeviceConfigError(f"{what} must be greater than 0, not {value:g}")
    return value


#: The properties :meth:`WaveformDevice.config` reads itself, but for the seed.
_SIGNAL_PROPERTIES = frozenset(
    {
        "rate",
        "analog_waveform",
        "analog_frequency",
        "button_period",
        "position_path",
        "position_period",
        "position_radius",
        "position_center",
        "event_period",
    }
)
#: What :meth:`WaveformDevice.config` read, by the texts written for those properties: the
#: definitions it was read with, and the values (10,000 devices written alike but for their
#: names and seeds read the same values 10,000 times, a fifth of configuring them).
_READ: dict[tuple, tuple[object, tuple]] = {}
#: At most this many ways of writing them are remembered.
_READ_MOST = 256


class WaveformDevice(Analog, Digital, Position, Hat, Command, String):
    ELEMENT_TYPE = "waveform_device"
    SAMPLING = SamplingMode.SCHEDULED
    sample_interval = 0.0015
    #: The scheduler's sample() and the frames publish one at a time (one lock for all).
    _publishing = _PUBLISHING
    #: Per noise channel, its generator and the sample it is at; made by the first noise
    #: block (an instance attribute only then: see :class:`~gadgetctl.input.device.Input`).
    _noise_streams: dict[int, tuple[np.random.Generator, int]] | None = None
    #: The frame group updating it (an instance attribute from ``__init__`` on; read through
    #: the class while ``Input.__init__`` sets the first state: reading the instance's
    #: ``__dict__`` there made Python build a dict for each of 10,000 devices).
    _group: _FrameGroup | None = None

    def __init__(self) -> None:
        super().__init__()
        self.rate = 100.0
        self.seed = 0
        self.analog: list[AnalogChannel] = []
        self.button_periods: list[float] = []
        self.positions: list[PositionChannel] = []
        self.center = (0.0, 1.5, 0.0)
        self.event_period = 0.0
        self.t0 = 0.0
        self._group: _FrameGroup | None = None  # the frame group updating it, once it runs
        self._slot = 0  # its place in the group's arrays
        self._next = 0
        self._block: Block | None = None
        self._ahead: Block | None = None  # the next block, computed ahead between frames
        self._ahead_tried = False  # a next block was computed ahead (it may have events)
        self._frame_published = _NEVER  # when a frame last published (input-manager clock)
        self._stand_in = _STAND_IN  # its manager's, once it starts

    @property
    def next_index(self) -> int:
        """The number of the next sample to publish (kept in the group's arrays while grouped)."""
        group = self._group
        return int(group.next[self._slot]) if group is not None else self._next

    @next_index.setter
    def next_index(self, value: int) -> None:
        group = self._group
        if group is not None:
            group.next[self._slot] = value
        else:
            self._next = value

    # -- configuration ------------------------------------------------------------------

    def config(self, access: ElementAccess) -> None:
        super().config(access)
        written = access.written(_SIGNAL_PROPERTIES)
        if written is not None:
            written = (written, self.center)  # what an unwritten center leaves
        found = _READ.get(written) if written is not None else None
        if found is not None and found[0] is access.definitions:
            # an element written alike was read before: the same values (only the seed differs)
            self.seed = access.integer("seed")
            rate, analog, buttons, positions, self.center, self.event_period = found[1]
            self.rate = rate
            # the lists themselves, shared (read-only: a configuration makes new ones; a copy
            # each was 1.7 MB for 10,000 devices)
            self.analog, self.button_periods, self.positions = analog, buttons, positions
            return
        self._read(access)
        if written is not None and len(_READ) < _READ_MOST:
            _READ[written] = (
                access.definitions,
                (
                    self.rate,
                    self.analog,
                    self.button_periods,
                    self.positions,
                    self.center,
                    self.event_period,
                ),
            )

    def _read(self, access: ElementAccess) -> None:
        """What :meth:`config` reads of its own properties."""
        self.rate = _positive(access.float("rate"), "rate")
        if self.rate > MAX_RATE:
            raise DeviceConfigError(
                f"rate {self.rate:g} Hz is above the {MAX_RATE:g} Hz gadgetctl supports"
            )
        self.seed = access.integer("seed")
        waves = access.strings("analog_waveform")
        frequencies = _per_channel(access, "analog_frequency", len(waves))
        self.analog = [
            AnalogChannel(_enum(Wave, w, "analog_waveform"), _positive(f, "analog_frequency"))
            for w, f in zip(waves, frequencies, strict=True)
        ]
        self.button_periods = [
            _positive(p, "button_period") for p in access.floats("button_period")
        ]
        paths = access.strings("position_path")
        periods = _per_channel(access, "position_period", len(paths))
        radii = _per_channel(access, "position_radius", len(paths))
        self.positions = [
            PositionChannel(_enum(Path, p, "position_path"), _positive(t, "position_period"), r)
            for p, t, r in zip(paths, periods, radii, strict=True)
        ]
        center = access.floats("position_center")
        self.center = (*center, 0.0, 0.0, 0.0)[:3] if center else self.center
        self.event_period = max(0.0, access.float("event_period"))

    def configured_kinds(self) -> tuple[DeviceKind, ...]:
        """The kinds its configuration makes: events (hat, command, string) only with an
        ``event_period``."""
        made = {
            DeviceKind.ANALOG: bool(self.analog),
            DeviceKind.DIGITAL: bool(self.button_periods),
            DeviceKind.POSITION: bool(self.positions),
        }
        events = self.event_period > 0
        return tuple(k for k in self.kinds() if made.get(k, events))

    # -- sampling -----------------------------------------------------------------------

    def start_sampling(self) -> None:
        with self._publishing:
            self._stand_in = _stand_in_for(self.context)
            self.t0 = now()
            self.next_index = 0
            self._block = None
            self._ahead, self._ahead_tried = None, False
            self._frame_published = _NEVER
            self._mirror()

    def _last_frame(self) -> float:
        """When a frame last published this device's samples (its start before the first)."""
        group = self._group
        last = self._frame_published if group is None else max(self._frame_published, group.moment)
        return max(last, self.t0)

    def next_sample_due(self) -> float:
        # the scheduler only stands in when frames stop (or have not begun); it looks again
        # at instants on a grid shared by every device (one scheduler pass for all of them)
        due = self.t0 + self.next_index / self.rate
        return max(due, self._stand_in.next_look(self._last_frame()))

    def sample(self) -> None:
        began = time.perf_counter()
        with self._publishing:
            moment = now()
            stand_in = self._stand_in
            # else frames publish, or the budget is spent: the next frame or look does
            published = moment - self._last_frame() >= FRAME_GRACE and stand_in.may_publish(moment)
            if published:
                self._publish_due(moment)
                self._mirror()
            stand_in.spent(moment, time.perf_counter() - began, published=published)

    FRAME_GROUP = True

    @classmethod
    def update_frame_group(cls, devices: Sequence[WaveformDevice], frame: int) -> None:
        """Every waveform device's frame at one instant (see the module documentation)."""
        if not devices:
            return
        group = devices[0]._group
        if group is None or group.devices is not devices:
            group = _FrameGroup(devices)
        group.update(frame)

    def update_for_frame(self, frame: int) -> None:
        group = self._group
        if group is not None:
            if group.frame == frame:
                return  # its group updated it this frame
            group.alone[self._slot] = frame  # the group leaves it alone this frame
            group.alone_frame = frame
        super().update_for_frame(frame)

    @property
    def state(self) -> DeviceState:
        return self._state

    @state.setter
    def state(self, value: DeviceState) -> None:
        self._state = value
        group = self._group  # (the class's None while Input.__init__ sets the first state)
        if group is not None:
            group.running[self._slot] = value is _RUNNING
            group.prepare_after = 0.0  # a device that runs again may need a block ahead

    @classmethod
    def prepare_frame_group(cls, devices: Sequence[WaveformDevice]) -> None:
        """Between frames: the next blocks of the devices whose blocks end soon."""
        group = devices[0]._group if devices else None
        if group is not None and group.devices is devices:
            group.prepare()

    def _next_block_size(self, backlog: int) -> int:
        """Samples of the block that follows the current one (or the first), made when
        ``backlog`` samples are due already: a shorter first block spreads the devices'
        block computations out, and a backlog (the first frame after a long start-up, a
        stalled frame loop) goes in one block with it, up to the store's cap (a block per
        half second of it cost 10,000 devices 1.5 s of start-up each second it lasted)."""
        size = max(1, math.ceil(self.rate * BLOCK_SECONDS))
        if self._block is None:
            size = max(1, size - zlib.crc32(self.name.encode()) % size)
        return size + min(backlog, self.store.cap)

    def _compute_ahead(self) -> None:
        """The block after the current one, starting some samples before its end (the caller
        holds the publishing lock)."""
        block = self._block
        size = max(1, math.ceil(self.rate * BLOCK_SECONDS))
        overlap = min(size - 1, max(64, math.ceil(self.rate * 0.05)))
        ahead = self.compute(max(block.start, block.end - overlap), size)
        self._ahead, self._ahead_tried = ahead, True

    def _take_ahead(self) -> None:
        """Make the block computed ahead the current one (the caller holds the publishing
        lock; the group saw that this frame's window lies in it)."""
        self.store.sync()  # the pending window of the current block is taken first
        self._block, self._ahead, self._ahead_tried = self._ahead, None, False
        self._mirror()

    def update_data(self) -> None:
        """Publish what has come due, then swap: the frame gets samples up to its instant."""
        with self._publishing:
            self._update_at(now())
            self._mirror()

    def _mirror(self) -> None:
        if self._group is not None:
            self._group.mirror(self._slot)

    def _update_at(self, moment: float) -> None:
        """The frame of this device alone (the caller holds the publishing lock)."""
        if self.state is _RUNNING:
            self._frame_published = moment
            end = int((moment - self.t0) * self.rate) + 1  # samples whose time has come
            first = self.next_index
            block = self._block
            if (
                block is not None
                and block.start <= first < end <= block.end
                and end <= block.event_after(first)
            ):
                # the usual frame: one more window of the current block, and the swap
                self.next_index = end
                self.store.add_slices_and_swap(
                    block.timestamps, block.items, first - block.start, end - block.start, moment
                )
                return
            self._publish_due(moment)
        self.store.swap(moment)

    def _publish_due(self, moment: float) -> None:
        end = int((moment - self.t0) * self.rate) + 1  # samples whose time has come
        while self.next_index < end:
            block = self._block
            ahead = self._ahead
            if (
                (block is None or not block.start <= self.next_index < block.end)
                and ahead is not None
                and ahead.start <= self.next_index < ahead.end
            ):
                block = self._block = ahead
                self._ahead, self._ahead_tried = None, False
            if block is None or not block.start <= self.next_index < block.end:
                self._ahead, self._ahead_tried = None, False
                size = self._next_block_size(end - self.next_index)
                block = self._block = self.compute(self.next_index, size)
            stop = min(end, block.end)
            self.publish(block, self.next_index - block.start, stop - block.start)
            self.next_index = stop

    def publish(self, block: Block, first: int, last: int) -> None:
        self.store.add_slices(block.timestamps, block.items, first, last)
        for index, number in block.events:
            if block.start + first <= index < block.start + last:
                stamp = float(block.timestamps[index - block.start])
                self.add_command_sample([number], stamp)
                self.add_string_sample([f"event {number}"], stamp)

    # -- the signals --------------------------------------------------------------------

    def compute(self, start: int, count: int) -> Block:
        """Samples ``start`` .. ``start + count - 1`` (timestamps relative to the device start)."""
        shared = _SIGNALS.values(self, start, count)
        if shared is not None:  # the read-only values of every device configured alike
            t, items, events = shared
            return Block(start, self.t0 + t, items, events)
        return self._compute(start, count)

    def signal_key(self) -> tuple | None:
        """What its values depend on, when that is the same for every device configured
        alike (:class:`_SharedSignals`); None for a device whose values are its own (noise
        is seeded per device; position filters are left out)."""
        if (
            type(self) is not WaveformDevice
            or self.position_filters.filters
            or any(c.wave is Wave.NOISE for c in self.analog)
        ):
            return None
        return (
            self.rate,
            tuple(self.analog),
            (self.analog_min, self.analog_max) if self.analog else None,
            tuple(self.button_periods),
            tuple(self.positions),
            tuple(self.center) if self.positions else None,
            self.event_period,
        )

    def _compute(self, start: int, count: int) -> Block:
        """:meth:`compute` for this device alone (its own arrays)."""
        k = np.arange(start, start + count, dtype=np.float64)
        t = k / self.rate
        data: dict[DeviceKind, np.ndarray] = {}
        if self.analog:
            data[DeviceKind.ANALOG] = np.stack(
                [self._analog(i, c, t, start) for i, c in enumerate(self.analog)], axis=1
            )
        if self.button_periods:
            data[DeviceKind.DIGITAL] = np.stack(
                [(np.mod(t, p) < p / 2).astype(np.int8) for p in self.button_periods], axis=1
            )
        if self.positions:
            if len(self.positions) == 1:  # what np.stack makes of one, without its cost
                matrices = self._path(self.positions[0], t)[:, None]
            else:
                matrices = np.stack([self._path(c, t) for c in self.positions], axis=1)
            data[DeviceKind.POSITION] = self.position_filters.apply(matrices)
        events: list[tuple[int, int]] = []
        if self.event_period > 0:
            steps = np.floor(t / self.event_period).astype(np.int64)
            data[DeviceKind.HAT] = _HAT_COLUMN.take(steps % len(HAT_SEQUENCE), axis=0)
            # event n falls on the first sample at or after its time, n * event_period: the
            # numbers that may fall in these samples, one more either side (rounding), and
            # those whose sample is among them (an event on a block's first sample belongs to
            # that block: with + 1 on the first number it belonged to none, and was lost)
            per_event = self.rate * self.event_period
            first = max(1, math.floor(start / per_event))
            last = math.floor((start + count - 1) / per_event) + 1
            for number in range(first, last + 1):
                index = math.ceil(number * per_event - 1e-9)
                if start <= index < start + count:
                    events.append((index, number))
        return Block(start, self.t0 + t, data, events)

    def _analog(self, channel: int, spec: AnalogChannel, t: np.ndarray, start: int) -> np.ndarray:
        phase = spec.frequency * t
        if spec.wave is Wave.SINE:
            wave = np.sin(2 * np.pi * phase)
        elif spec.wave is Wave.TRIANGLE:
            wave = 1.0 - 4.0 * np.abs(np.mod(phase + 0.25, 1.0) - 0.5)
        elif spec.wave is Wave.SQUARE:
            wave = np.where(np.mod(phase, 1.0) < 0.5, 1.0, -1.0)
        else:
            wave = self._noise(channel, start, len(t)) * 2.0 - 1.0
        middle = (self.analog_max + self.analog_min) / 2
        half = (self.analog_max - self.analog_min) / 2
        return middle + half * wave

    def _noise(self, channel: int, start: int, count: int) -> np.ndarray:
        """Uniform [0, 1) numbers ``start`` .. ``start + count - 1`` of the channel's seeded stream."""
        streams = self._noise_streams
        if streams is None:
            streams = self._noise_streams = {}
        cached = streams.get(channel)
        if cached is None or cached[1] != start:  # not where the previous block ended: seek
            bits = np.random.PCG64(np.random.SeedSequence([self.seed, channel]))
            bits.advance(start)
            cached = (np.random.Generator(bits), start)
        generator = cached[0]
        streams[channel] = (generator, start + count)
        return generator.random(count)

    def _path(self, spec: PositionChannel, t: np.ndarray) -> np.ndarray:
        angle = 2 * np.pi * t / spec.period
        matrices = np.empty((len(t), 4, 4))
        matrices[:] = self._pose_template  # identity, at the center: then what moves
        cx, _, cz = self.center
        r = spec.radius
        if spec.path is Path.CIRCLE:
            matrices[:, 0, 3], matrices[:, 2, 3] = cx + r * np.cos(angle), cz + r * np.sin(angle)
        elif spec.path is Path.FIGURE_EIGHT:
            sine = np.sin(angle)
            matrices[:, 0, 3], matrices[:, 2, 3] = cx + r * sine, cz + r * sine * np.cos(angle)
        else:  # spin: turn about +Y in place
            c, s = np.cos(angle), np.sin(angle)
            matrices[:, 0, 0], matrices[:, 0, 2], matrices[:, 2, 0], matrices[:, 2, 2] = c, s, -s, c
        return matrices

    @property
    def _pose_template(self) -> np.ndarray:
        """The identity moved to :attr:`center`: every sample's matrix before it moves."""
        template = np.eye(4)
        template[:3, 3] = self.center
        return template


class _SharedSignals:
    """The values of the first :data:`SHARED_SAMPLES` samples of waveform devices configured
    alike (:meth:`WaveformDevice.signal_key`), computed once and shared read-only: a sample's
    values depend only on its number and the configuration, so 10,000 devices of one
    configuration had 10,000 copies of the same matrices (about 14 MB in their first
    blocks), each computed on its own. Past them, the values of a configuration that more
    than one device asked for are shared in windows of :data:`SHARED_SAMPLES` samples, one
    beginning every :data:`WINDOW_STRIDE` (so a block of up to that many samples lies in one
    window), the :data:`WINDOWS_KEPT` used last of a configuration and at most
    :data:`WINDOW_BYTES` in all (a configuration whose window would not fit is not shared):
    a hundred 1 kHz devices alike computed a hundred copies of each half-second block, and
    their server converted each copy's rotations to quaternions on its own. Other blocks,
    and devices whose values are their own, are computed as before. At most
    :data:`SHARED_CONFIGURATIONS` configurations are kept.

    The cuts of those values a block is made of (its ``t``, its per-kind views and events)
    are shared too, by configuration and sample range, up to :data:`SHARED_CUTS` of them:
    10,000 devices alike cut their blocks at a few hundred ranges, and the views and tuples
    of each block were about 400 bytes a device, one or two blocks each."""

    SHARED_SAMPLES = 4096
    SHARED_CONFIGURATIONS = 16
    SHARED_CUTS = 4096
    WINDOW_STRIDE = SHARED_SAMPLES // 2
    WINDOWS_KEPT = 8
    WINDOW_BYTES = 32 << 20

    def __init__(self) -> None:
        #: signal key -> (samples covered, t = k / rate, per kind the values, the events'
        #: sample indices, the events), the arrays read-only
        self._values: dict[
            tuple,
            tuple[int, np.ndarray, dict[DeviceKind, np.ndarray], list[int], list[tuple[int, int]]],
        ] = {}
        #: (signal key, start, stop) -> what :meth:`values` gives for it (read-only)
        self._cuts: dict[tuple, _Cut] = {}
        #: (signal key, first sample) -> a window past the first samples: (first sample,
        #: t, per kind the values, the events' sample indices, the events), oldest first
        self._windows: dict[tuple, tuple] = {}
        self._window_bytes = 0
        #: signal key -> the id of the one device that asked for it, True once another did,
        #: False when its window does not fit :data:`WINDOW_BYTES`
        self._askers: dict[tuple, int | bool] = {}

    def values(self, device: WaveformDevice, start: int, count: int) -> _Cut | None:
        """``t`` (sample number / rate), the values of samples ``start`` ..
        ``start + count - 1`` of ``device`` as (kind, view of the shared array) pairs, and
        the events among them; None when they are not shared. Devices alike get the same
        objects for the same samples: none of them may be changed."""
        stop = start + count
        if count < 1 or start < 0:
            return None
        key = device.signal_key()
        if key is None:
            return None
        cut = self._cuts.get((key, start, stop))
        if cut is not None:
            return cut
        if stop > self.SHARED_SAMPLES:
            window = self._window(device, key, start, stop)
            if window is None:
                return None
            first, t, data, indices, events = window
            return self._cut(key, start, stop, first, t, data, indices, events)
        found = self._values.get(key)
        if found is None or found[0] < stop:
            if found is None and len(self._values) >= self.SHARED_CONFIGURATIONS:
                return None
            covered = min(self.SHARED_SAMPLES, max(stop, 64, 2 * found[0] if found else 0))
            block = device._compute(0, covered)
            data = block.data
            for kind, array in (*data.items(),):
                if array.base is not None:  # owned here, so that nothing can write it
                    array = data[kind] = array.copy()
                array.flags.writeable = False
            t = np.arange(covered, dtype=np.float64) / device.rate
            t.flags.writeable = False
            indices = [index for index, _ in block.events]
            found = self._values[key] = (covered, t, data, indices, block.events)
            self._cuts.clear()  # (cut from the arrays just replaced)
        _, t, data, indices, events = found
        return self._cut(key, start, stop, 0, t, data, indices, events)

    def _cut(
        self,
        key: tuple,
        start: int,
        stop: int,
        first: int,
        t: np.ndarray,
        data: dict[DeviceKind, np.ndarray],
        indices: list[int],
        events: list[tuple[int, int]],
    ) -> _Cut:
        """Samples ``start`` .. ``stop - 1`` of values whose first sample is ``first``."""
        within = events[bisect.bisect_left(indices, start) : bisect.bisect_left(indices, stop)]
        begin, end = start - first, stop - first
        cut = (
            t[begin:end],
            tuple([(kind, values[begin:end]) for kind, values in data.items()]),
            within if within else _NO_EVENTS,
        )
        if len(self._cuts) >= self.SHARED_CUTS:
            self._cuts.clear()
        self._cuts[(key, start, stop)] = cut
        return cut

    def _window(self, device: WaveformDevice, key: tuple, start: int, stop: int) -> tuple | None:
        """The window past the first samples that holds ``start`` .. ``stop - 1``, computed
        when missing; None when no other device asked for this configuration, the samples
        lie in no window, or the window would not fit :data:`WINDOW_BYTES`."""
        asker = self._askers.get(key)
        if asker is not True:
            if asker is False or (asker is None and len(self._askers) >= self.SHARED_CUTS):
                return None
            if asker is None or asker == id(device):
                self._askers[key] = id(device)
                return None  # a device alone computes its own blocks, as before
            self._askers[key] = True
        size = self.SHARED_SAMPLES
        first = start // self.WINDOW_STRIDE * self.WINDOW_STRIDE
        if stop > first + size:
            return None
        window = self._windows.pop((key, first), None)
        if window is not None:
            self._windows[(key, first)] = window  # the most recently used last
            return window
        if sum(1 for kept in self._windows if kept[0] == key) >= self.WINDOWS_KEPT:
            self._drop(next(kept for kept in self._windows if kept[0] == key))
        block = device._compute(first, size)
        data = block.data
        for kind, array in (*data.items(),):
            if array.base is not None:  # owned here, so that nothing can write it
                array = data[kind] = array.copy()
            array.flags.writeable = False
        t = np.arange(first, first + size, dtype=np.float64) / device.rate
        t.flags.writeable = False
        nbytes = t.nbytes + sum(array.nbytes for array in data.values())
        if nbytes > self.WINDOW_BYTES:
            self._askers[key] = False  # not computed again for every block
            return None
        while self._windows and self._window_bytes + nbytes > self.WINDOW_BYTES:
            self._drop(next(iter(self._windows)))
        indices = [index for index, _ in block.events]
        window = self._windows[(key, first)] = (first, t, data, indices, block.events)
        self._window_bytes += nbytes
        return window

    def _drop(self, kept: tuple) -> None:
        _, t, data, _, _ = self._windows.pop(kept)
        self._window_bytes -= t.nbytes + sum(array.nbytes for array in data.values())
        self._cuts.clear()  # (some were cut from the window dropped)

    def clear(self) -> None:
        self._values.clear()
        self._cuts.clear()
        self._windows.clear()
        self._window_bytes = 0
        self._askers.clear()


#: What :meth:`_SharedSignals.values` gives: ``t``, the (kind, values) pairs, the events.
_Cut = tuple[np.ndarray, tuple[tuple[DeviceKind, np.ndarray], ...], Sequence[tuple[int, int]]]


_SIGNALS = _SharedSignals()
_COMPUTE = WaveformDevice.compute


class _FrameGroup:
    """The waveform devices a manager updates together, their sampling state side by side in
    arrays (the devices' own ``next_index`` lives here while they belong to it), and the
    :class:`SharedWindows` their usual frames go to.

    A device's ``t0``, ``rate``, state and current block are mirrored here (:meth:`mirror`)
    whenever they change outside the usual frame (its own update, the scheduler's stand-in, a
    restart): the usual frame then needs no Python per device. Between frames
    (:meth:`prepare`) the next block of a device whose block ends soon is computed ahead,
    starting ``overlap`` samples before the current one ends: the frame whose window reaches
    past the end takes the window from the next block (the same samples) and stays usual."""

    def __init__(self, devices: Sequence[WaveformDevice]) -> None:
        with _PUBLISHING:
            self.devices = devices
            count = len(devices)
            self.next = np.array([d.next_index for d in devices], dtype=np.int64)
            self.t0 = np.zeros(count)
            self.rate = np.ones(count)
            self.first = np.zeros(count, dtype=np.int64)  # the current block's first sample
            self.last = np.zeros(count, dtype=np.int64)  # one past its last
            self.ahead_first = np.zeros(count, dtype=np.int64)  # the block computed ahead's
            self.ahead_last = np.zeros(count, dtype=np.int64)
            self.ahead = np.zeros(count, dtype=bool)  # a next block was computed (or tried)
            # the sample of the current block's next event (a window that reaches it is the
            # device's own frame, which publishes the event; the others stay usual)
            self.event_next = np.full(count, NO_EVENT, dtype=np.int64)
            self.cap = np.array([d.store.cap for d in devices], dtype=np.int64)
            self.usual = np.zeros(count, dtype=bool)  # the usual frame may be taken
            self.running = np.zeros(count, dtype=bool)
            self.alone = np.full(count, -1, dtype=np.int64)  # frame a device was updated alone
            self.alone_frame = -1  # the latest of them
            # what the values of a device configured alike with others depend on (None: values
            # of its own): its blocks are renewed together with theirs (:meth:`_renew`)
            alike: dict[tuple, tuple] = {}  # one key for devices alike (a copy each: MBs)
            self.keys = [
                key if (key := d.signal_key()) is None else alike.setdefault(key, key)
                for d in devices
            ]
            self.renewable = np.array([key is not None for key in self.keys], dtype=bool)
            self.moment = -math.inf  # when the group last published
            self.frame = -1  # the frame it last updated
            self.prepare_after = 0.0  # no block to compute ahead before then (a hint)
            self.prepared_at = now()
            self.windows = SharedWindows([d.store for d in devices])
            for slot, device in enumerate(devices):
                device._group, device._slot = self, slot
                self.running[slot] = device.state is _RUNNING
                self.mirror(slot)

    def mirror(self, slot: int) -> None:
        """Take device ``slot``'s sampling state (the caller holds the publishing lock)."""
        device = self.devices[slot]
        store = device.store
        store.sync()  # its pending window is taken before its arrays change
        self.t0[slot] = device.t0
        self.rate[slot] = device.rate
        self.prepare_after = 0.0
        ahead = device._ahead
        self.ahead[slot] = device._ahead_tried
        if ahead is not None:
            self.ahead_first[slot], self.ahead_last[slot] = ahead.start, ahead.end
        else:
            self.ahead_first[slot] = self.ahead_last[slot] = 0
        block = device._block
        if block is None or store._waiting:
            self.usual[slot] = False
            return
        self.first[slot], self.last[slot] = block.start, block.end
        self.event_next[slot] = block.event_after(device.next_index)
        self.windows.set_arrays(slot, block.timestamps, block.items)
        self.usual[slot] = True

    def update(self, frame: int) -> None:
        """One frame of every device: with numpy for all of them, the samples that came due
        and whether they are one window of the device's current block, or of the block
        computed ahead (the usual frame); the others are updated alone, a device that raises
        is faulted alone."""
        devices = self.devices
        with _PUBLISHING:
            moment = now()
            if len(devices) <= FEW_SLOTS and self._usual_small(frame, moment):
                return
            # (bool arrays are counted with count_nonzero and indexed with nonzero(): all(),
            # any() and flatnonzero() are Python functions of numpy's, a few times the cost)
            ends = ((moment - self.t0) * self.rate).astype(np.int64)
            ends += 1  # samples whose time has come
            nexts = self.next
            count = len(devices)
            ready = self.usual & self.running
            ready &= ends - nexts <= self.cap
            if self.alone_frame == frame:  # some device was updated alone this frame
                ready &= self.alone != frame
            empty = ready & (ends <= nexts)  # nothing came due: an empty frame
            ready ^= empty  # (empty is part of ready)
            usual = ready & (self.first <= nexts)
            usual &= ends <= self.last
            emptied = np.count_nonzero(empty)  # (usual and empty never share a slot)
            if np.count_nonzero(usual) + emptied != count:
                switch = ready & ~usual & (self.ahead_first <= nexts) & (ends <= self.ahead_last)
                if np.count_nonzero(switch):
                    for slot in switch.nonzero()[0].tolist():
                        devices[slot]._take_ahead()
                    usual |= switch
            usual &= ends <= self.event_next  # a window with an event: the device's own frame
            if np.count_nonzero(usual) + emptied != count:
                # a block ran out (or there is none yet) of devices whose values are shared:
                # their next blocks computed together, from the samples now due
                renew = (
                    ~(usual | empty)
                    & self.renewable
                    & self.running
                    & (self.alone != frame)
                    & (nexts < ends)
                    & (ends - nexts <= self.cap)
                )
                if np.count_nonzero(renew):  # (a window with an event is still its own frame)
                    usual |= self._renew(renew.nonzero()[0].tolist(), ends) & (
                        ends <= self.event_next
                    )
                for slot in (~(usual | empty)).nonzero()[0].tolist():
                    device = devices[slot]
                    if device._updated_frame == frame:
                        continue
                    device._updated_frame = frame
                    try:
                        device._update_at(moment)
                    except Exception as err:  # a faulty device must not stop the frame loop
                        device.frame_fault(err)
                    self.mirror(slot)
            windows = self.windows
            if np.count_nonzero(usual) == count:  # the usual frame of every device
                slots, taken = windows.every, slice(None)
            else:
                slots = taken = usual.nonzero()[0]
            first = self.first[taken]
            windows.publish(
                moment,
                slots,
                nexts[taken] - first,
                ends[taken] - first,
                empty.nonzero()[0] if emptied else None,
            )
            nexts[taken] = ends[taken]
            self.moment = moment
            self.frame = frame

    def _renew(self, slots: list[int], ends: np.ndarray) -> np.ndarray:
        """Make the next block of each device of ``slots`` (running, values shared, samples
        ``next`` .. ``ends - 1`` due, at most its store's cap) its current one, starting at
        its next sample and sized as :meth:`WaveformDevice._publish_due` sizes it, so that
        this frame's samples are one window of it: the devices configured alike that need the
        same samples share one cut of the values (events included), their timestamps are
        computed in one array, and their state is mirrored with numpy. Returns which slots
        were renewed (a device whose store holds samples of its own, or whose values are not
        shared for these samples, is left to its own frame, as is one whose window holds an
        event). The caller holds the lock."""
        devices, keys = self.devices, self.keys
        nexts = self.next.tolist()
        wanted: dict[tuple, list[int]] = {}
        for slot in slots:
            device = devices[slot]
            if getattr(device.compute, "__func__", None) is not _COMPUTE:
                continue  # its blocks are what its own compute() makes (one set on it)
            store = device.store
            store.sync()  # its pending window is taken before its arrays change
            if store._waiting:
                continue
            start = nexts[slot]
            size = device._next_block_size(int(ends[slot]) - start)  # (within the cap)
            found = wanted.get((keys[slot], start, size))
            if found is None:
                wanted[(keys[slot], start, size)] = [slot]
            else:
                found.append(slot)
        renewed: list[int] = []
        lasts: list[int] = []
        events_next: list[int] = []
        windows = self.windows
        for (_, start, size), members in wanted.items():
            try:
                cut = _SIGNALS.values(devices[members[0]], start, size)
            except Exception:  # each device's own frame computes its block, and faults
                continue
            if cut is None:
                continue
            t, items, events = cut
            stamps = self.t0[members][:, None] + t  # each row: t0 + t, as compute() adds
            for row, slot in enumerate(members):
                device = devices[slot]
                block = device._block = Block(start, stamps[row], items, events)
                device._ahead, device._ahead_tried = None, False
                windows.set_arrays(slot, block.timestamps, items)
            renewed += members
            lasts += [start + size] * len(members)
            event = Block.event_after(block, start)  # (the same for every member)
            events_next += [event] * len(members)
        taken = np.zeros(len(devices), dtype=bool)
        if renewed:
            taken[renewed] = True
            self.first[renewed] = self.next[renewed]
            self.last[renewed] = lasts
            self.ahead[renewed] = False
            self.ahead_first[renewed] = self.ahead_last[renewed] = 0
            self.event_next[renewed] = events_next
            self.usual[renewed] = True
            self.prepare_after = 0.0
        return taken

    def _usual_small(self, frame: int, moment: float) -> bool:
        """:meth:`update` of a small group whose every device has its usual frame or an empty
        one, slot by slot with Python numbers; False, having changed nothing, when some
        device's frame is neither (the numpy path then does the whole frame)."""
        first, last, nexts = self.first.tolist(), self.last.tolist(), self.next.tolist()
        cap, alone = self.cap.tolist(), self.alone.tolist()
        usual, running = self.usual.tolist(), self.running.tolist()
        rate, events = self.rate.tolist(), self.event_next.tolist()
        windows: list[tuple[int, int, int]] = []
        empty: list[int] = []
        for slot, t0 in enumerate(self.t0.tolist()):
            if not (usual[slot] and running[slot]) or alone[slot] == frame:
                return False
            end = int((moment - t0) * rate[slot]) + 1  # as numpy's cast: toward zero
            begin = nexts[slot]
            if end - begin > cap[slot]:
                return False
            if end <= begin:
                empty.append(slot)
            elif first[slot] <= begin and end <= last[slot] and end <= events[slot]:
                windows.append((slot, begin - first[slot], end - first[slot]))
            else:
                return False
        self.windows.publish_few(moment, windows, empty)
        nexts_array = self.next
        for slot, _, stop in windows:
            nexts_array[slot] = first[slot] + stop
        self.moment = moment
        self.frame = frame
        return True

    def prepare(self) -> None:
        """Between frames: compute the next block of devices whose block ends within
        :data:`AHEAD_SECONDS` (paced by :data:`PREPARE_PACE`), and offer it to the shared
        windows' readers."""
        moment = now()
        limit = max(1, int((moment - self.prepared_at) / PREPARE_PACE))
        self.prepared_at = moment
        if moment < self.prepare_after:
            return
        with _PUBLISHING:
            left = (self.last - self.next) / self.rate - AHEAD_SECONDS  # seconds until "soon"
            waiting = self.usual & self.running & ~self.ahead
            soon = waiting & (left < 0)
            if not soon.any():  # nothing to do before the first of them comes near its end
                # (or, when every block ahead is computed, before a device's state changes:
                # mirror() and a change of running start looking again)
                self.prepare_after = (
                    now() + float(left[waiting].min()) if waiting.any() else math.inf
                )
                return
            for slot in np.flatnonzero(soon)[:limit].tolist():
                device = self.devices[slot]
                try:
                    device._compute_ahead()
                except Exception:  # the frame that needs the block computes it, and faults
                    device._ahead, device._ahead_tried = None, True
                self.mirror(slot)
                ahead = device._ahead
                if ahead is not None:
                    self.windows.set_upcoming(slot, ahead.timestamps, ahead.items)
