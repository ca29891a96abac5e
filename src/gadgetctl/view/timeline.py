"""A recording replayed under the page's control: play, pause, speed and scrubbing.

`gadgetctl replay` releases a recording in real time through a
:class:`~gadgetctl.monitor.replay.ReplaySchedule`; the view needs to jump as well. A
:class:`ReplayTimeline` holds the schedule's records with their replay offsets (pauses
longer than ``MAX_PAUSE`` already shortened) and, once per frame (:meth:`advance`), hands
the records that became due to the same :class:`~gadgetctl.monitor.replaydevice.ReplayFeeder`
the replay command uses, so the replay devices, proxies, filters and aliases are the
input manager's own. A seek hands over, for every recorded device, kind and unit, the last
sample at or before the new time, so the poses are those recorded at that moment.

It is the session's replay source (``done``, ``drain_markers``): markers are noted by the
session as the replay passes them.
"""

from __future__ import annotations

import bisect
import dataclasses
import math
import threading
from collections.abc import Callable

from gadgetctl.monitor.records import MarkerRecord, SampleRecord

#: Speeds the page may choose.
MIN_SPEED, MAX_SPEED = 0.05, 20.0
#: Markers shown on the timeline, at most (a recording may hold more; all are noted).
MAX_TIMELINE_MARKERS = 64


class ReplayTimeline:
    """See the module documentation. Thread-safe: the page's controls call :meth:`play`,
    :meth:`pause`, :meth:`set_speed` and :meth:`seek` from viser's threads; the frame loop
    calls :meth:`advance`."""

    def __init__(self, schedule, feeder, clock: Callable[[], float]) -> None:
        self._feeder = feeder
        self._clock = clock
        mapping = schedule.mapping
        self._samples: list[tuple[float, SampleRecord]] = []
        self.markers: list[tuple[str, float]] = []
        self._keys: dict[tuple[str, str, int], tuple[list[float], list[SampleRecord]]] = {}
        for record, offset in zip(schedule.records, schedule.offsets, strict=True):
            if isinstance(record, MarkerRecord):
                self.markers.append((record.name, offset))
                continue
            if not isinstance(record, SampleRecord):
                continue
            name = mapping.get(record.device, record.device)
            if name != record.device:
                record = dataclasses.replace(record, device=name)
            self._samples.append((offset, record))
            times, records = self._keys.setdefault((name, record.kind, record.unit), ([], []))
            times.append(offset)
            records.append(record)
        self._offsets = [offset for offset, _ in self._samples]
        self.duration = max(self._offsets[-1] if self._offsets else 0.0, 0.0)
        if self.markers:
            self.duration = max(self.duration, self.markers[-1][1])
        self.position = 0.0
        self.playing = True
        self.speed = 1.0
        self.seeks = 0
        self._cursor = 0  # the next sample to hand over
        self._marker_cursor = 0
        self._passed: list[MarkerRecord] = []
        self._pending_seek: float | None = 0.0  # start with the poses at 0
        self._last_advance: float | None = None
        self._lock = threading.Lock()

    # -- the page's controls ------------------------------------------------------------

    def play(self) -> None:
        with self._lock:
            if self.position >= self.duration:
                self._pending_seek = 0.0
            self.playing = True

    def pause(self) -> None:
        with self._lock:
            self.playing = False

    def set_speed(self, speed: float) -> None:
        if not math.isfinite(speed):
            return
        with self._lock:
            self.speed = min(MAX_SPEED, max(MIN_SPEED, speed))

    def seek(self, position: float) -> None:
        """Jump to ``position`` seconds of replay (clamped to the recording)."""
        if not math.isfinite(position):
            return
        with self._lock:
            self._pending_seek = min(self.duration, max(0.0, position))

    def seek_marker(self, index: int) -> None:
        if 0 <= index < len(self.markers):
            self.seek(self.markers[index][1])

    # -- the session's replay source ----------------------------------------------------

    @property
    def done(self) -> bool:
        return False  # the page stays open at the end of the recording

    def drain_markers(self) -> list[MarkerRecord]:
        with self._lock:
            passed, self._passed = self._passed, []
        return passed

    # -- once per frame -----------------------------------------------------------------

    def advance(self) -> None:
        """Hand over what became due since the last call (or the state at a seek)."""
        moment = self._clock()
        with self._lock:
            elapsed = 0.0 if self._last_advance is None else moment - self._last_advance
            self._last_advance = moment
            if self._pending_seek is not None:
                target, self._pending_seek = self._pending_seek, None
                self._jump(target, moment)
                return
            if not self.playing:
                return
            target = min(self.duration, self.position + elapsed * self.speed)
            end = bisect.bisect_right(self._offsets, target)
            due = self._samples[self._cursor : end]
            self._cursor = end
            self._pass_markers(target, moment)
            self.position = target
            if target >= self.duration:
                self.playing = False
        if due:
            speed = self.speed
            self._feeder.feed(
                dataclasses.replace(r, timestamp=moment - (target - offset) / speed)
                for offset, r in due
            )

    def _jump(self, target: float, moment: float) -> None:
        """(Under the lock.) The newest sample of every key at ``target``, stamped now."""
        latest = []
        for times, records in self._keys.values():
            index = bisect.bisect_right(times, target) - 1
            if index >= 0:
                latest.append(dataclasses.replace(records[index], timestamp=moment))
        self.position = target
        self._cursor = bisect.bisect_right(self._offsets, target)
        self._marker_cursor = bisect.bisect_right([t for _, t in self.markers], target)
        self.seeks += 1
        if latest:
            self._feeder.feed(latest)

    def _pass_markers(self, target: float, moment: float) -> None:
        while (
            self._marker_cursor < len(self.markers)
            and self.markers[self._marker_cursor][1] <= target
        ):
            name, offset = self.markers[self._marker_cursor]
            self._passed.append(MarkerRecord(name, moment - (target - offset) / self.speed))
            self._marker_cursor += 1

    def state(self) -> dict[str, object]:
        with self._lock:
            return {
                "position": round(self.position, 6),
                "duration": round(self.duration, 6),
                "playing": self.playing,
                "speed": self.speed,
                "seeks": self.seeks,
                "markers": [
                    {"name": n, "time": round(t, 6)} for n, t in self.markers[:MAX_TIMELINE_MARKERS]
                ],
                "markers_total": len(self.markers),
            }
