"""Changes only, one line each: the data side of ``--format events`` (evtest-style).

:class:`ChangeDetector` looks at every sample a session gathered in a frame, in order, and
keeps what it last reported per device, kind and unit; it reports

* a button pressed or released (every change between two samples, also within one frame);
* an analog unit moving more than the dead band (a share of the device's range) away from
  the value last reported, with the raw reading (an integer where the device gives one);
* a position moving more than a distance (meters) or turning more than an angle (degrees)
  from the pose last reported;
* a glove joint turning more than the angle; a hat, gesture, command or string value that
  differs from the previous one (commands and strings from the first one on);
* keyboard and mouse events; a device's status when it is not running or changes; markers.

:func:`event_line` writes one :class:`ChangeEvent` as a line (:func:`event_lines` many),
``TIME  NAME[UNIT]  KIND  VALUE...`` (fields separated by two spaces; see docs/monitor.md).
Nothing here prints or imports typer or rich.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from gadgetctl.input.device import DeviceState
from gadgetctl.input.devicetypes import Analog
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.samples import Sample
from gadgetctl.monitor.encoding import proxy_value
from gadgetctl.monitor.poses import (
    EULER,
    MATRIX,
    QUATERNION,
    euler_xyz_degrees_batch,
    quaternions_wxyz,
)
from gadgetctl.monitor.units import from_meters
from gadgetctl.safetext import fixed, printable

if TYPE_CHECKING:
    from gadgetctl.monitor.session import MonitorSession

DEFAULT_DEAD_BAND = 0.02  # of an analog device's range (min..max)
DEFAULT_DISTANCE = 0.01  # meters
DEFAULT_ANGLE = 1.0  # degrees
UNIT_SYMBOLS = {"meters": "m", "feet": "ft", "inches": "in", "centimeters": "cm"}
HAT_NAMES = {0: "centered", 1: "up", 2: "right", 4: "down", 8: "left"}
FINGERS = ("thumb", "index", "middle", "ring", "pinky", "wrist")
DISCRETE = (DeviceKind.COMMAND, DeviceKind.STRING)  # events, not states: the first one counts too


@dataclass(frozen=True, slots=True)
class Thresholds:
    """How far a value must move before it is reported again."""

    dead_band: float = DEFAULT_DEAD_BAND
    distance: float = DEFAULT_DISTANCE
    angle: float = DEFAULT_ANGLE

    def __post_init__(self) -> None:
        for name in ("dead_band", "distance", "angle"):
            value = getattr(self, name)
            if not (value >= 0 and math.isfinite(value)):
                raise ValueError(
                    f"{name.replace('_', ' ')} must be a finite number >= 0, not {value!r}"
                )


@dataclass(frozen=True, slots=True)
class ChangeEvent:
    """One change: ``kind`` is a data kind (digital, analog, position, glove, hat, gesture,
    command, string), ``key`` (keyboard/mouse), ``status`` or ``marker``."""

    timestamp: float
    name: str
    kind: str
    unit: int | None = None
    value: Any = None
    raw: Any = None


@dataclass(slots=True)
class _DeviceMemory:
    last: dict[tuple[DeviceKind, int], Any] = field(default_factory=dict)
    state: str | None = None
    error: str | None = None
    faults: int = 0


class ChangeDetector:
    """Turns a session's frames into :class:`ChangeEvent` lists (see the module doc)."""

    def __init__(self, thresholds: Thresholds | None = None) -> None:
        self.thresholds = thresholds or Thresholds()
        self._devices: dict[str, _DeviceMemory] = {}
        self._markers_seen = 0
        self._scans = {
            DeviceKind.DIGITAL: self._digital,
            DeviceKind.ANALOG: self._analog,
            DeviceKind.POSITION: self._positions,
        }

    def frame(self, session: MonitorSession, moment: float) -> list[ChangeEvent]:
        """The changes of the session's current frame (its watched devices and its new
        markers), in time order."""
        events: list[ChangeEvent] = []
        manager = session.manager
        for name in session.watched:
            device = manager.device(name)
            if device is None:
                continue
            memory = self._devices.setdefault(name, _DeviceMemory())
            self._status(events, name, device, memory, moment)
            for kind, samples in session.frame_samples(name).items():
                scan = self._scans.get(kind)
                if scan is not None:
                    arrays = _arrays(samples)
                    if arrays is not None:  # the hot path: whole columns at a time
                        scan(events, name, device, memory, *arrays)
                        continue
                for sample in samples:
                    self._sample(
                        events, name, device, memory, kind, sample.timestamp, sample.values
                    )
        if session.selectors:  # proxies and aliases asked for by name: what they give
            selected_devices = set()
            for name in session.selected:
                if manager.device(name) is not None:
                    selected_devices.add(name)
                    continue
                proxy = manager.proxy(name)
                if proxy is not None:
                    memory = self._devices.setdefault(name, _DeviceMemory())
                    self._proxy(events, name, proxy, memory, moment)
            # a device only read through a selected proxy or alias: its status, not its data
            read_only = {n for n in session.watched if manager.device(n) is not None}
            read_only -= selected_devices
            if read_only:
                events[:] = [e for e in events if e.name not in read_only or e.kind == "status"]
        markers = session.markers
        for marker in markers[self._markers_seen :]:
            events.append(ChangeEvent(marker.timestamp, "-", "marker", value=marker.name))
        self._markers_seen = len(markers)
        events.sort(key=lambda event: event.timestamp)
        return events

    def _proxy(
        self,
        events: list[ChangeEvent],
        name: str,
        proxy: Any,
        memory: _DeviceMemory,
        moment: float,
    ) -> None:
        """A selected proxy's or alias's changes, under its own name and without a unit: the
        value it gives this frame (normalised, filtered, a button's state), as the
        application reading it sees it; its state when it is stupefied or comes back."""
        state = "stupefied" if proxy.stupefied else "active"
        reason = proxy.reason if proxy.stupefied else None
        if (state, reason) != (memory.state, memory.error):
            if memory.state is not None or proxy.stupefied:
                events.append(ChangeEvent(moment, name, "status", value=state, raw=reason))
            memory.state, memory.error = state, reason
        if proxy.stupefied:
            return
        kind = DeviceKind(proxy.KIND.value)
        if kind is DeviceKind.KEYBOARD_MOUSE:
            return  # its keys are the keyboard device's key events
        value, raw = proxy_value(proxy)
        if kind is DeviceKind.DIGITAL:
            value = 1 if int(value) in (1, 2) else 0  # on or toggled on: pressed
        found: list[ChangeEvent] = []
        self._sample(found, name, None, memory, kind, moment, [value])
        for event in found:
            given = raw if raw is not None and kind is DeviceKind.ANALOG else event.raw
            events.append(replace(event, unit=None, raw=given))

    def _status(
        self,
        events: list[ChangeEvent],
        name: str,
        device: Any,
        memory: _DeviceMemory,
        moment: float,
    ) -> None:
        shown = getattr(device, "shown_state", None)
        if shown is not None:  # faulted with its error, undecodable with the first error
            shown_state, error = shown()
            state = shown_state.value
        else:
            state = (
                device.state.value if isinstance(device.state, DeviceState) else str(device.state)
            )
            error = device.error if state in ("faulted", "reconnecting") else None
        faults = getattr(device, "faults", 0)
        first = memory.state is None
        missed = (
            not first
            and faults > memory.faults
            and state != "faulted"
            and memory.state != "faulted"
        )
        memory.faults = faults
        if missed:  # it faulted and restarted between two frames: say so all the same
            events.append(ChangeEvent(moment, name, "status", value="faulted", raw=device.error))
            memory.state, memory.error = "faulted", device.error
        if (state, error) == (memory.state, memory.error):
            return
        memory.state, memory.error = state, error
        if first and state == DeviceState.RUNNING.value:
            return  # running from the start is the normal case: nothing to say
        events.append(ChangeEvent(moment, name, "status", value=state, raw=error))

    def _sample(
        self,
        events: list[ChangeEvent],
        name: str,
        device: Any,
        memory: _DeviceMemory,
        kind: DeviceKind,
        stamp: float,
        values: Any,
    ) -> None:
        last = memory.last
        if kind is DeviceKind.KEYBOARD_MOUSE:
            for value in values:
                events.append(ChangeEvent(stamp, name, "key", value=value))
            return
        for unit, value in enumerate(values):
            key = (kind, unit)
            previous = last.get(key)
            if kind is DeviceKind.DIGITAL:
                state = 1 if value else 0
                if previous is not None and state != previous:
                    events.append(ChangeEvent(stamp, name, kind.value, unit, state, value))
                last[key] = state
            elif kind is DeviceKind.ANALOG:
                raw = float(value)
                normal = device.normalize(raw) if isinstance(device, Analog) else raw
                if previous is None:
                    last[key] = normal
                elif abs(normal - previous) > self.thresholds.dead_band:
                    events.append(ChangeEvent(stamp, name, kind.value, unit, normal, value))
                    last[key] = normal
            elif kind is DeviceKind.POSITION:
                matrix = np.asarray(value, dtype=np.float64).reshape(4, 4)
                if previous is None:
                    last[key] = matrix
                elif self._pose_moved(previous, matrix):
                    events.append(ChangeEvent(stamp, name, kind.value, unit, matrix))
                    last[key] = matrix
            elif kind is DeviceKind.GLOVE:
                angles = np.asarray(value, dtype=np.float64)
                if previous is None:
                    last[key] = angles
                elif (
                    previous.shape != angles.shape
                    or np.degrees(np.abs(angles - previous)).max() > self.thresholds.angle
                ):
                    events.append(ChangeEvent(stamp, name, kind.value, unit, angles))
                    last[key] = angles
            else:  # hat, gesture, command, string: every change
                plain = str(value) if kind is DeviceKind.STRING else _integer(value)
                if plain != previous and (previous is not None or kind in DISCRETE):
                    events.append(ChangeEvent(stamp, name, kind.value, unit, plain, value))
                last[key] = plain

    def _digital(
        self,
        events: list[ChangeEvent],
        name: str,
        device: Any,
        memory: _DeviceMemory,
        stamps: np.ndarray,
        values: np.ndarray,
    ) -> None:
        """Every change of every button of a frame (the same as :meth:`_sample`, by column)."""
        states = values != 0
        for unit in range(states.shape[1]):
            key = (DeviceKind.DIGITAL, unit)
            column = states[:, unit]
            previous = memory.last.get(key)
            before = np.concatenate(
                ([column[0] if previous is None else bool(previous)], column[:-1])
            )
            for index in np.flatnonzero(column != before).tolist():
                state = int(column[index])
                events.append(
                    ChangeEvent(
                        float(stamps[index]), name, "digital", unit, state, values[index, unit]
                    )
                )
            memory.last[key] = int(column[-1])

    def _analog(
        self,
        events: list[ChangeEvent],
        name: str,
        device: Any,
        memory: _DeviceMemory,
        stamps: np.ndarray,
        values: np.ndarray,
    ) -> None:
        """Each unit's moves beyond the dead band from the value last reported (the same as
        :meth:`_sample`), looked for a block of samples at a time."""
        if isinstance(device, Analog):
            low, high = device.analog_min, device.analog_max
            normal = (
                np.zeros(values.shape)
                if high <= low
                else (np.minimum(np.maximum(values, low), high) - low) / (high - low)
            )
        else:
            normal = values
        band = self.thresholds.dead_band
        count = len(stamps)
        if count <= _SHORT_FRAME:  # a frame's few samples: a loop costs less than numpy calls
            times = stamps.tolist()
            for unit, (column, raws) in enumerate(
                zip(normal.T.tolist(), values.T.tolist(), strict=True)
            ):
                key = (DeviceKind.ANALOG, unit)
                last = memory.last.get(key)
                start = 0
                if last is None:
                    last, start = column[0], 1
                for index in range(start, count):
                    moved = column[index]
                    if abs(moved - last) > band:
                        events.append(
                            ChangeEvent(times[index], name, "analog", unit, moved, raws[index])
                        )
                        last = moved
                memory.last[key] = last
            return
        for unit in range(values.shape[1]):
            key = (DeviceKind.ANALOG, unit)
            column = normal[:, unit]
            last = memory.last.get(key)
            start = 0
            if last is None:
                last, start = float(column[0]), 1
            # each sample's move from the one before: a run of samples that each moved
            # beyond the band right after a reported one is reported at once (a noisy
            # channel: every sample)
            stepped = np.abs(column[1:] - column[:-1]) > band
            block = _BLOCK
            while start < count:
                if start and last == column[start - 1] and stepped[start - 1]:
                    ahead = stepped[start - 1 :]
                    run = int(np.argmin(ahead))
                    stop = count if ahead[run] else start + run  # (all of them: argmin 0)
                    for stamp, moved, raw in zip(
                        stamps[start:stop].tolist(),
                        column[start:stop].tolist(),
                        values[start:stop, unit],
                        strict=True,
                    ):
                        events.append(ChangeEvent(stamp, name, "analog", unit, moved, raw))
                    last, start, block = float(column[stop - 1]), stop, _BLOCK
                    continue
                window = column[start : start + block]
                beyond = np.abs(window - last) > band
                if not beyond.any():
                    start += block
                    block = min(block * 2, _MAX_BLOCK)  # quiet: look further ahead
                    continue
                index = start + int(np.argmax(beyond))
                last = float(column[index])
                events.append(
                    ChangeEvent(
                        float(stamps[index]), name, "analog", unit, last, values[index, unit]
                    )
                )
                start, block = index + 1, _BLOCK
            memory.last[key] = last

    def _positions(
        self,
        events: list[ChangeEvent],
        name: str,
        device: Any,
        memory: _DeviceMemory,
        stamps: np.ndarray,
        values: np.ndarray,
    ) -> None:
        """Each unit's moves beyond the distance or angle from the pose last reported (the
        same as :meth:`_sample`), looked for a block of samples at a time."""
        count, width = values.shape
        if width % 16:
            for index in range(count):  # not whole matrices: sample by sample, as it says
                self._sample(
                    events, name, device, memory, DeviceKind.POSITION, stamps[index], values[index]
                )
            return
        for unit in range(width // 16):
            key = (DeviceKind.POSITION, unit)
            poses = values[:, 16 * unit : 16 * unit + 16].reshape(count, 4, 4)
            last = memory.last.get(key)
            start = 0
            if last is None:
                last, start = poses[0].copy(), 1
            block = _BLOCK
            while start < count:
                window = poses[start : start + block]
                beyond = self._moved(last, window)
                if not beyond.any():
                    start += block
                    block = min(block * 2, _MAX_BLOCK)
                    continue
                index = start + int(np.argmax(beyond))
                last = poses[index].copy()
                events.append(ChangeEvent(float(stamps[index]), name, "position", unit, last))
                start, block = index + 1, _BLOCK
            memory.last[key] = last

    def _pose_moved(self, before: np.ndarray, after: np.ndarray) -> bool:
        return bool(self._moved(before, after[None])[0])

    def _moved(self, before: np.ndarray, after: np.ndarray) -> np.ndarray:
        """Whether each pose of ``after`` (n, 4, 4) moved more than the distance, or turned
        more than the angle, from ``before`` (4, 4): the angle of the rotation between them,
        whose cosine is (trace(Rb^T Ra) - 1) / 2, the trace being the sum of the products
        of their rotations' elements."""
        offset = after[:, :3, 3] - before[:3, 3]
        distance = np.sqrt(np.einsum("ij,ij->i", offset, offset))
        trace = np.einsum("ij,nij->n", before[:3, :3], after[:, :3, :3])
        cosine = np.minimum(np.maximum((trace - 1.0) / 2.0, -1.0), 1.0)  # (np.clip's numbers)
        with np.errstate(invalid="ignore"):  # (a pose of nan moves nowhere, as before)
            return (distance > self.thresholds.distance) | (
                np.degrees(np.arccos(cosine)) > self.thresholds.angle
            )


_BLOCK = 16  # samples an analog scan looks at first after an event
_SHORT_FRAME = 64  # samples of a unit up to which an analog scan is a plain loop
_MAX_BLOCK = 4096


def _arrays(frame: Any) -> tuple[np.ndarray, np.ndarray] | None:
    """(timestamps (n,), values (n, units)) of a frame's samples of one kind, or None when
    the number of units changed within the frame."""
    stamps: list[np.ndarray] = []
    rows: list[np.ndarray] = []
    for chunk in frame.chunks:
        if type(chunk) is Sample:
            stamps.append(np.asarray([chunk.timestamp], dtype=np.float64))
            rows.append(np.asarray([chunk.values], dtype=np.float64))
        else:
            values = np.asarray(chunk.values, dtype=np.float64)
            stamps.append(np.asarray(chunk.timestamps, dtype=np.float64))
            rows.append(values.reshape(len(values), -1))
    if not rows:
        return None
    try:
        values = np.concatenate(rows) if len(rows) > 1 else rows[0]
    except ValueError:
        return None
    if not len(values) or values.ndim != 2:
        return None
    return (np.concatenate(stamps) if len(stamps) > 1 else stamps[0]), values


def _integer(value: Any) -> Any:
    try:
        return int(value)
    except (TypeError, ValueError):
        return value


# --------------------------------------------------------------------------- the line


def number_text(value: Any) -> str:
    """A reading as text: integers (and floats holding one, as a joystick's -15450.0) as
    integers, never ``-1.545e+04``; other numbers with 6 significant digits."""
    if isinstance(value, (bool, np.bool_, int, np.integer)):
        return str(int(value))
    try:
        number = float(value)
    except (TypeError, ValueError):
        return printable(str(value))
    if math.isfinite(number) and number.is_integer() and abs(number) < 1e15:
        return str(int(number))
    return f"{number:.6g}"


def pose_text(matrix: Any, pose: str = EULER, length_unit: str = "meters") -> str:
    """A transform as ``x X y Y z Z UNIT`` followed by ``rot X Y Z deg`` (Euler XYZ),
    ``q W X Y Z`` (quaternion) or the matrix's 16 values row by row (``m ...``)."""
    return pose_texts(np.asarray(matrix, dtype=np.float64).reshape(1, 4, 4), pose, length_unit)[0]


def pose_texts(matrices: np.ndarray, pose: str = EULER, length_unit: str = "meters") -> list[str]:
    """:func:`pose_text` of each of ``matrices`` (n, 4, 4), their rotations converted at once."""
    if pose == MATRIX:
        return [
            "m " + " ".join(fixed(v, 4, True) for v in values)
            for values in matrices.reshape(len(matrices), 16).tolist()
        ]
    symbol = UNIT_SYMBOLS.get(length_unit, length_unit)
    places = from_meters(matrices[:, :3, 3], length_unit).tolist()
    if pose == QUATERNION:
        turns = [
            f"  q {w:+.4f} {qx:+.4f} {qy:+.4f} {qz:+.4f}"
            for w, qx, qy, qz in quaternions_wxyz(matrices).tolist()
        ]
    else:
        turns = [
            f"  rot {ax:+.1f} {ay:+.1f} {az:+.1f} deg"
            for ax, ay, az in euler_xyz_degrees_batch(matrices).tolist()
        ]
    return [
        f"x {fixed(x, 4, True)} y {fixed(y, 4, True)} z {fixed(z, 4, True)} {symbol}{turn}"
        for (x, y, z), turn in zip(places, turns, strict=True)
    ]


def _value_text(event: ChangeEvent, pose: str, length_unit: str) -> str:
    kind, value = event.kind, event.value
    if kind == "digital":
        return "pressed" if value else "released"
    if kind == "analog":
        return f"{fixed(value, 4)} raw {number_text(event.raw)}"
    if kind == "position":
        return pose_text(value, pose, length_unit)
    if kind == "glove":
        with np.errstate(all="ignore"):  # a hostile angle is inf, not a warning on stderr
            angles = np.degrees(np.asarray(value, dtype=np.float64)).reshape(-1, 4)
        return " ".join(
            f"{finger} {'/'.join(fixed(a, 0) for a in row)}"
            for finger, row in zip(FINGERS, angles.tolist(), strict=False)
        )
    if kind == "hat":
        return (
            HAT_NAMES.get(value, number_text(value))
            if isinstance(value, int)
            else number_text(value)
        )
    if kind in ("string", "marker"):
        return json.dumps(str(value), ensure_ascii=False)
    if kind == "status":
        return f"{value}: {printable(str(event.raw))}" if event.raw else str(value)
    if kind == "key":
        return _key_text(value)
    return number_text(value)


def _key_text(event: Any) -> str:
    key = getattr(event, "key", None)
    if key is not None and hasattr(event, "pressed"):
        return f"{key.name} {'pressed' if event.pressed else 'released'}"
    if hasattr(event, "dx"):
        return f"move {number_text(event.dx)} {number_text(event.dy)}"
    if hasattr(event, "direction"):
        return f"scroll {event.direction}"
    return printable(str(event))


def event_line(
    event: ChangeEvent, origin: float, *, pose: str = EULER, length_unit: str = "meters"
) -> str:
    """``TIME  NAME[UNIT]  KIND  VALUE...``: TIME in seconds since ``origin`` (6 decimals),
    the unit in brackets for data of a unit, fields separated by two spaces."""
    return event_lines([event], origin, pose=pose, length_unit=length_unit)[0]


def event_lines(
    events: Sequence[ChangeEvent],
    origin: float,
    *,
    pose: str = EULER,
    length_unit: str = "meters",
) -> list[str]:
    """:func:`event_line` of each of ``events``, the poses among them written at once."""
    posed = [i for i, event in enumerate(events) if event.kind == "position"]
    texts: dict[int, str] = {}
    if posed:
        matrices = np.array(
            [np.asarray(events[i].value, dtype=np.float64).reshape(4, 4) for i in posed]
        )
        texts = dict(zip(posed, pose_texts(matrices, pose, length_unit), strict=True))
    lines = []
    names: dict[tuple[str, int | None], str] = {}
    for i, event in enumerate(events):
        where = names.get((event.name, event.unit))
        if where is None:
            where = names[event.name, event.unit] = printable(event.name) + (
                f"[{event.unit}]" if event.unit is not None else ""
            )
        kind = event.kind
        if kind == "analog":  # (most lines of a busy run: _value_text's, inline)
            text = f"{fixed(event.value, 4)} raw {number_text(event.raw)}"
        else:
            text = texts.get(i)
            if text is None:
                text = _value_text(event, pose, length_unit)
                if kind not in _NUMBERS_ONLY:
                    text = printable(text)
        lines.append(f"{event.timestamp - origin:.6f}  {where}  {kind}  {text}")
    return lines


#: Kinds whose value text is made of numbers and words of ours only (nothing to escape).
_NUMBERS_ONLY = frozenset(("digital", "analog", "position"))
