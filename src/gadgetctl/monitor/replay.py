"""Replay timing: hands recorded samples out at their original pace, faster, or at once.

Independent of the input manager: :class:`ReplaySchedule` only decides *when* each record
is due and gives it a fresh timestamp; the caller feeds the records wherever they go.
"""

from __future__ import annotations

import itertools
import math
import statistics
import time
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass

from gadgetctl.monitor.records import MarkerRecord, SampleRecord

ReplayRecord = SampleRecord | MarkerRecord
FAST_CHUNK = 1024
DEFAULT_LOOP_STEP = 1.0
#: The longest wait between two records of a replay, in replay seconds: a longer pause in
#: the recording (a gap of days, a first timestamp of 0 among Unix times, 1e308) is
#: shortened to this, and counted in ``ReplaySchedule.pauses_shortened``.
MAX_PAUSE = 10.0


@dataclass(frozen=True, slots=True)
class ReplayBatch:
    """Records released together; ``due`` is the clock time the first one was due."""

    due: float
    records: list[ReplayRecord]


def _loop_step(stamps: list[float]) -> float:
    """The pause between the last sample of a pass and the first of the next one."""
    distinct = sorted(set(stamps))
    steps = [b - a for a, b in itertools.pairwise(distinct)]
    return statistics.median(steps) if steps else DEFAULT_LOOP_STEP


class ReplaySchedule:
    """Yields recorded samples and markers when they are due, relative to the first sample.

    ``speed`` 2 replays twice as fast; 0 or ``math.inf`` as fast as possible. ``loop``
    repeats the recording forever (or ``max_loops`` times); each pass starts one typical
    sample interval after the previous one ended, so timestamps keep increasing. Released
    records get new timestamps: with ``rebase`` on the ``clock`` (``start + offset / speed``;
    unscaled when as fast as possible), otherwise the recorded ones plus the loop offset.
    ``mapping`` renames devices; names that occur nowhere are listed in ``unused_mapping``.
    Frames, stats and end records are not replayed. Records due within ``tolerance`` seconds
    are released together, to save sleeps. With ``max_units``, samples of units from
    ``max_units`` on are left out and counted in ``units_beyond``. A pause between two
    records that would take longer than ``max_pause`` seconds to replay (at any speed; as
    fast as possible: ``max_pause`` recorded seconds) is shortened to that, so every wait
    and every replayed timestamp stays finite and bounded; ``pauses_shortened`` counts them
    and ``longest_pause`` is the longest one recorded.
    """

    def __init__(
        self,
        records: Iterable[object],
        speed: float = 1.0,
        loop: bool = False,
        *,
        mapping: Mapping[str, str] | None = None,
        max_loops: int | None = None,
        rebase: bool = True,
        tolerance: float = 0.001,
        clock: Callable[[], float] = time.monotonic,
        sleep: Callable[[float], object] = time.sleep,
        max_units: int | None = None,
        max_pause: float = MAX_PAUSE,
    ) -> None:
        if math.isnan(speed) or speed < 0:
            raise ValueError(
                f"replay speed must be 0 (as fast as possible) or positive, not {speed}"
            )
        if max_loops is not None and max_loops < 1:
            raise ValueError("max_loops must be at least 1")
        self.speed = speed
        self.paced = 0 < speed < math.inf
        self.loop = loop
        self.max_loops = max_loops if loop else 1
        self.rebase = rebase
        self.tolerance = max(0.0, tolerance)
        self._clock, self.sleep = clock, sleep
        kept: list[ReplayRecord] = []
        self.units_beyond = 0  # samples of units from max_units on, left out
        for r in records:
            if isinstance(r, SampleRecord):
                if max_units is not None and r.unit >= max_units:
                    self.units_beyond += 1
                    continue
                kept.append(r)
            elif isinstance(r, MarkerRecord):
                kept.append(r)
        kept.sort(key=lambda r: r.timestamp)
        self._records = kept
        timeline = self._timeline(kept, max_pause * (speed if self.paced else 1.0))
        sampled = [t for r, t in zip(kept, timeline, strict=True) if isinstance(r, SampleRecord)]
        stamps = sampled or timeline
        origin = stamps[0] if stamps else 0.0
        self.t0 = next((r.timestamp for r in kept if isinstance(r, SampleRecord)), 0.0)
        if not sampled and kept:
            self.t0 = kept[0].timestamp
        self.duration = (stamps[-1] - origin) if stamps else 0.0
        self.period = self.duration + _loop_step(stamps)
        self._offsets = [t - origin for t in timeline]
        self.mapping = dict(mapping or {})
        names = sorted({r.device for r in kept if isinstance(r, SampleRecord)})
        self.unused_mapping = tuple(old for old in self.mapping if old not in names)
        self.devices = tuple(sorted({self.mapping.get(n, n) for n in names}))
        self.mapping_warnings = self._check_mapping(names)

    @property
    def offsets(self) -> list[float]:
        """Each record's replay time from the first sample, in recorded seconds (pauses
        longer than ``max_pause`` shortened), in the order of :attr:`records`."""
        return list(self._offsets)

    def _timeline(self, kept: list[ReplayRecord], longest: float) -> list[float]:
        """The records' times from the first one, each pause longer than ``longest`` (recorded
        seconds) shortened to it (counted)."""
        self.pauses_shortened = 0
        self.longest_pause = 0.0
        times: list[float] = []
        elapsed, previous = 0.0, None
        for record in kept:
            if previous is not None:
                step = record.timestamp - previous
                if not step <= longest:  # NaN too
                    self.pauses_shortened += 1
                    self.longest_pause = max(self.longest_pause, step)
                    step = longest
                elapsed += step
            times.append(elapsed)
            previous = record.timestamp
        return times

    def _check_mapping(self, names: list[str]) -> tuple[str, ...]:
        warnings = [f"{old!r} does not occur in the recording" for old in self.unused_mapping]
        targets: dict[str, list[str]] = {}
        for name in names:
            targets.setdefault(self.mapping.get(name, name), []).append(name)
        warnings += [
            f"{' and '.join(map(repr, sources))} all become {target!r}"
            for target, sources in targets.items()
            if len(sources) > 1
        ]
        return tuple(warnings)

    @property
    def records(self) -> tuple[ReplayRecord, ...]:
        """The samples and markers of one pass, in time order, as recorded (not renamed)."""
        return tuple(self._records)

    def __len__(self) -> int:
        """Records per pass."""
        return len(self._records)

    def _release(self, start: float, base: float, i: int, j: int) -> list[ReplayRecord]:
        scale = self.speed if self.paced else 1.0
        mapping = self.mapping
        out: list[ReplayRecord] = []
        for record, offset in zip(self._records[i:j], self._offsets[i:j], strict=True):
            stamp = (start + (offset + base) / scale) if self.rebase else record.timestamp + base
            if isinstance(record, SampleRecord):
                out.append(
                    SampleRecord(
                        mapping.get(record.device, record.device),
                        record.kind,
                        record.unit,
                        stamp,
                        record.value,
                        record.raw,
                    )
                )
            else:
                out.append(MarkerRecord(record.name, stamp))
        return out

    def batches(self) -> Iterator[ReplayBatch]:
        """Groups of records, each released when its first record is due."""
        offsets, n = self._offsets, len(self._offsets)
        if n == 0:
            return
        start = self._clock()
        passes = 0
        while True:
            base = passes * self.period
            i = 0
            while i < n:
                if self.paced:
                    due = start + (offsets[i] + base) / self.speed
                    now = self._clock()
                    if due - now > self.tolerance:
                        self.sleep(due - now)
                        now = self._clock()
                    limit = (now + self.tolerance - start) * self.speed - base
                    j = i + 1
                    while j < n and offsets[j] <= limit:
                        j += 1
                else:
                    due = start + offsets[i] + base
                    j = min(n, i + FAST_CHUNK)
                yield ReplayBatch(due, self._release(start, base, i, j))
                i = j
            passes += 1
            if self.max_loops is not None and passes >= self.max_loops:
                return

    def __iter__(self) -> Iterator[ReplayRecord]:
        for batch in self.batches():
            yield from batch.records
