"""Summaries of finished recordings: counts, rates, gaps, value ranges and sparklines."""

from __future__ import annotations

import math
from array import array
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gadgetctl.monitor.poses import euler_xyz_degrees_batch, matrix_from_pose, quaternions_wxyz
from gadgetctl.monitor.recording import Recording, RecordingProblem, read_recording
from gadgetctl.monitor.records import EndRecord, FrameRecord, MarkerRecord, SampleRecord
from gadgetctl.monitor.sparkline import sparkline

GAP_FACTOR = 3.0
AXES = ("x", "y", "z")
#: A translation axis moving less than this (meters) is drawn flat: float noise and a
#: resting tracker's jitter are not shown as motion.
MIN_SPARK_SPAN = 1e-3
_POSE_BATCH = 4096  # positions whose angles are computed together
NUMERIC_KINDS = ("analog", "digital", "gesture", "command", "hat")


@dataclass(frozen=True, slots=True)
class GapSummary:
    """Intervals longer than ``threshold`` (3x the median interval), in seconds."""

    threshold: float | None
    count: int
    largest: float | None

    def to_dict(self) -> dict[str, object]:
        return {"threshold": self.threshold, "count": self.count, "largest": self.largest}


@dataclass(frozen=True, slots=True)
class UnitSummary:
    """One unit of one kind of a device.

    ``minimum``/``maximum`` cover numeric kinds (gloves: every angle); positions have the
    translation ranges (meters), the rotation ranges (Euler XYZ angles in degrees, as
    :mod:`gadgetctl.monitor.poses` defines them) and one sparkline per axis (``sparklines``:
    x, y, z) instead. The sparkline shows the value over time (gloves: the mean angle);
    strings have none.
    """

    kind: str
    unit: int
    samples: int
    minimum: float | None = None
    maximum: float | None = None
    translation_min: tuple[float, float, float] | None = None
    translation_max: tuple[float, float, float] | None = None
    sparkline: str | None = None
    rotation_min: tuple[float, float, float] | None = None
    rotation_max: tuple[float, float, float] | None = None
    sparklines: dict[str, str] | None = None
    turn: float | None = (
        None  # positions: the largest angle (degrees) away from the first orientation
    )

    def to_dict(self) -> dict[str, object]:
        result: dict[str, object] = {
            "kind": self.kind,
            "unit": self.unit,
            "samples": self.samples,
            "minimum": self.minimum,
            "maximum": self.maximum,
            "translation_min": list(self.translation_min) if self.translation_min else None,
            "translation_max": list(self.translation_max) if self.translation_max else None,
            "sparkline": self.sparkline,
        }
        if self.kind == "position":
            result["rotation_min_degrees"] = list(self.rotation_min) if self.rotation_min else None
            result["rotation_max_degrees"] = list(self.rotation_max) if self.rotation_max else None
            result["sparklines"] = dict(self.sparklines) if self.sparklines else None
            result["turn_degrees"] = self.turn
        return result


@dataclass(frozen=True, slots=True)
class DeviceSummary:
    """One device: ``samples`` records, ``updates`` distinct sample timestamps.

    Rates, intervals and gaps are computed on the updates.
    """

    name: str
    kinds: tuple[str, ...]
    samples: int
    updates: int
    first_timestamp: float | None
    last_timestamp: float | None
    duration: float
    mean_rate: float
    median_interval: float | None
    max_interval: float | None
    gaps: GapSummary
    units: tuple[UnitSummary, ...]

    def to_dict(self) -> dict[str, object]:
        return {
            "name": self.name,
            "kinds": list(self.kinds),
            "samples": self.samples,
            "updates": self.updates,
            "first_timestamp": self.first_timestamp,
            "last_timestamp": self.last_timestamp,
            "duration": self.duration,
            "mean_rate": self.mean_rate,
            "median_interval": self.median_interval,
            "max_interval": self.max_interval,
            "gaps": self.gaps.to_dict(),
            "units": [u.to_dict() for u in self.units],
        }


@dataclass(frozen=True, slots=True)
class RecordingSummary:
    """A whole recording; ``end_reason`` is None when the writer never wrote its end record."""

    path: str
    created: str
    info: dict[str, object]
    samples: int
    frames: int
    first_timestamp: float | None
    duration: float
    end_reason: str | None
    markers: tuple[MarkerRecord, ...]
    devices: tuple[DeviceSummary, ...]
    problems: tuple[RecordingProblem, ...] = field(default=())

    def to_dict(self) -> dict[str, object]:
        start = self.first_timestamp
        return {
            "path": self.path,
            "created": self.created,
            "info": self.info,
            "samples": self.samples,
            "frames": self.frames,
            "duration": self.duration,
            "end_reason": self.end_reason,
            "markers": [
                {
                    "name": m.name,
                    "timestamp": m.timestamp,
                    "offset": None if start is None else m.timestamp - start,
                }
                for m in self.markers
            ],
            "devices": [d.to_dict() for d in self.devices],
            "problems": [
                {"line": p.line, "severity": p.severity, "message": p.message}
                for p in self.problems
            ],
        }


# --------------------------------------------------------------------------- accumulation


def _number(value: object) -> float:
    try:
        return float(value)  # type: ignore[arg-type]
    except OverflowError:  # an integer beyond any float
        return math.inf if value > 0 else -math.inf  # type: ignore[operator]
    except (TypeError, ValueError):
        return math.nan


def _matrix(value: object) -> np.ndarray | None:
    """The 4x4 transform of a position value (a matrix, or a position with a quaternion or
    Euler angles), None when it is none of them."""
    try:
        return matrix_from_pose(value)
    except (TypeError, ValueError, KeyError, IndexError, OverflowError):
        return None


def _angles(value: object) -> list[float]:
    out: list[float] = []
    if isinstance(value, (list, tuple)):
        for item in value:
            if isinstance(item, (list, tuple)):
                out.extend(_number(a) for a in item)
            else:
                out.append(_number(item))
    return out


class _UnitAccumulator:
    __slots__ = (
        "angles",
        "first",
        "high",
        "kind",
        "low",
        "pending",
        "samples",
        "series",
        "translations",
        "turn",
        "unit",
    )

    def __init__(self, kind: str, unit: int) -> None:
        self.kind, self.unit, self.samples = kind, unit, 0
        self.series = array("d")
        self.translations = array("d")  # x, y, z per position sample (NaN when unreadable)
        self.angles = array("d")  # Euler XYZ degrees per readable position sample
        self.pending: list[np.ndarray] = []  # rotations waiting for a batch
        self.first: np.ndarray | None = None  # the first orientation's quaternion
        self.turn = 0.0
        self.low: float | None = None
        self.high: float | None = None

    def add(self, value: object) -> None:
        self.samples += 1
        kind = self.kind
        if kind == "position":
            m = _matrix(value)
            if m is None or not np.isfinite(m).all():
                self.translations.extend((math.nan, math.nan, math.nan))
                return
            self.translations.extend(m[:3, 3].tolist())
            self.pending.append(m)
            if len(self.pending) >= _POSE_BATCH:
                self._flush_angles()
        elif kind == "glove":
            angles = [a for a in _angles(value) if math.isfinite(a)]
            if angles:
                low, high = min(angles), max(angles)
                self.low = low if self.low is None else min(self.low, low)
                self.high = high if self.high is None else max(self.high, high)
                self.series.append(sum(angles) / len(angles))
            else:
                self.series.append(math.nan)
        elif kind != "string":
            self.series.append(_number(value) if not isinstance(value, str) else math.nan)

    def _flush_angles(self) -> None:
        if self.pending:
            batch = np.stack(self.pending)
            self.angles.extend(euler_xyz_degrees_batch(batch).ravel().tolist())
            quaternions = quaternions_wxyz(batch)
            if self.first is None:
                self.first = quaternions[0]
            cosines = np.clip(np.abs(quaternions @ self.first), 0.0, 1.0)
            self.turn = max(self.turn, float(np.degrees(2.0 * np.arccos(cosines.min()))))
            self.pending = []

    def _position_summary(self, width: int) -> UnitSummary:
        self._flush_angles()
        xyz = (
            np.frombuffer(self.translations, dtype=np.float64).reshape(-1, 3)
            if self.translations
            else None
        )
        if xyz is None or not np.isfinite(xyz).all(axis=1).any():
            return UnitSummary(self.kind, self.unit, self.samples)
        readable = xyz[np.isfinite(xyz).all(axis=1)]
        lo, hi = readable.min(axis=0), readable.max(axis=0)
        lines = {}
        for axis, name in enumerate(AXES):  # each axis on its own scale, time kept (NaN: a gap)
            column = xyz[:, axis]
            if hi[axis] - lo[axis] < MIN_SPARK_SPAN:  # at rest: a row of middle bars
                column = np.where(np.isfinite(column), 0.0, np.nan)
            lines[name] = sparkline(column, width)
        angles = np.frombuffer(self.angles, dtype=np.float64).reshape(-1, 3)
        a_lo, a_hi = angles.min(axis=0), angles.max(axis=0)
        return UnitSummary(
            self.kind,
            self.unit,
            self.samples,
            translation_min=(float(lo[0]), float(lo[1]), float(lo[2])),
            translation_max=(float(hi[0]), float(hi[1]), float(hi[2])),
            rotation_min=(float(a_lo[0]), float(a_lo[1]), float(a_lo[2])),
            rotation_max=(float(a_hi[0]), float(a_hi[1]), float(a_hi[2])),
            sparklines=lines,
            turn=self.turn,
        )

    def summary(self, width: int) -> UnitSummary:
        if self.kind == "string":
            return UnitSummary(self.kind, self.unit, self.samples)
        if self.kind == "position":
            return self._position_summary(width)
        series = np.frombuffer(self.series, dtype=np.float64) if self.series else np.empty(0)
        line = sparkline(series, width)
        if self.kind == "glove":
            return UnitSummary(
                self.kind, self.unit, self.samples, self.low, self.high, sparkline=line
            )
        finite = series[np.isfinite(series)]
        if finite.size == 0:
            return UnitSummary(self.kind, self.unit, self.samples, sparkline=line)
        return UnitSummary(
            self.kind,
            self.unit,
            self.samples,
            float(finite.min()),
            float(finite.max()),
            sparkline=line,
        )


class _DeviceAccumulator:
    __slots__ = ("name", "samples", "timestamps", "units")

    def __init__(self, name: str) -> None:
        self.name = name
        self.samples = 0
        self.timestamps = array("d")
        self.units: dict[tuple[str, int], _UnitAccumulator] = {}

    def add(self, record: SampleRecord) -> None:
        self.samples += 1
        self.timestamps.append(record.timestamp)
        key = (record.kind, record.unit)
        unit = self.units.get(key)
        if unit is None:
            unit = self.units[key] = _UnitAccumulator(*key)
        unit.add(record.value)

    def summary(self, width: int) -> DeviceSummary:
        stamps = np.unique(np.frombuffer(self.timestamps, dtype=np.float64))
        first = float(stamps[0]) if stamps.size else None
        last = float(stamps[-1]) if stamps.size else None
        duration = (last - first) if first is not None and last is not None else 0.0
        intervals = np.diff(stamps)
        if intervals.size:
            median = float(np.median(intervals))
            threshold = GAP_FACTOR * median
            above = intervals[intervals > threshold]
            gaps = GapSummary(
                threshold, int(above.size), float(above.max()) if above.size else None
            )
            largest = float(intervals.max())
        else:
            median = largest = None
            gaps = GapSummary(None, 0, None)
        rate = (stamps.size - 1) / duration if duration > 0 else 0.0
        units = tuple(self.units[key].summary(width) for key in sorted(self.units))
        return DeviceSummary(
            self.name,
            tuple(sorted({k for k, _ in self.units})),
            self.samples,
            int(stamps.size),
            first,
            last,
            duration,
            rate,
            median,
            largest,
            gaps,
            units,
        )


def summarize_records(
    records: Iterable[object], *, width: int = 40
) -> tuple[list[DeviceSummary], list[MarkerRecord], int, EndRecord | None]:
    """(devices sorted by name, markers, frame count, end record) of decoded records."""
    devices: dict[str, _DeviceAccumulator] = {}
    markers: list[MarkerRecord] = []
    frames = 0
    end: EndRecord | None = None
    for record in records:
        if isinstance(record, SampleRecord):
            acc = devices.get(record.device)
            if acc is None:
                acc = devices[record.device] = _DeviceAccumulator(record.device)
            acc.add(record)
        elif isinstance(record, MarkerRecord):
            markers.append(record)
        elif isinstance(record, FrameRecord):
            frames += 1
        elif isinstance(record, EndRecord):
            end = record
    return [devices[name].summary(width) for name in sorted(devices)], markers, frames, end


def summarize_recording(path: str | Path, *, width: int = 40) -> RecordingSummary:
    """Read a recording and summarize it; raises :class:`RecordingError` for a non-recording."""
    return summarize(read_recording(path), width=width)


def summarize(recording: Recording, *, width: int = 40) -> RecordingSummary:
    """Summarize an opened recording (gadgetctl's own, or a VRPN log read as one)."""
    devices, markers, frames, end = summarize_records(recording.records, width=width)
    firsts = [d.first_timestamp for d in devices if d.first_timestamp is not None]
    lasts = [d.last_timestamp for d in devices if d.last_timestamp is not None]
    first = min(firsts) if firsts else None
    duration = (max(lasts) - first) if first is not None else 0.0
    return RecordingSummary(
        path=str(recording.path),
        created=recording.header.created,
        info=dict(recording.header.info),
        samples=sum(d.samples for d in devices),
        frames=frames,
        first_timestamp=first,
        duration=duration,
        end_reason=end.reason if end else None,
        markers=tuple(markers),
        devices=tuple(devices),
        problems=tuple(recording.problems),
    )
