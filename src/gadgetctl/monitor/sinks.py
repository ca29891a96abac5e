"""Where a monitor session's records go (:class:`Sinks`): the recorders added to it, each
opened once the header is known, what waits meanwhile, and which statuses changed.

The session decides what each frame's records are; this module only hands them out, in the
order they came, to every recorder that wants them (sample records, or frame records for a
per-frame sink). It knows nothing of devices or frames.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass

from gadgetctl.monitor.poses import MATRIX
from gadgetctl.monitor.recording import Recorder
from gadgetctl.monitor.records import MarkerRecord, StatusRecord

#: What makes a recorder, given the header (known after the devices' first samples).
Opener = Callable[[Mapping[str, object]], Recorder]

SAMPLES, FRAME, STATUSES, MARKER = "samples", "frame", "statuses", "marker"


@dataclass(slots=True)
class Sink:
    open: Opener
    per_frame: bool
    recorder: Recorder | None = None
    pose: str = MATRIX  # how positions are written (gadgetctl.monitor.poses)


class Sinks:
    """The sinks of one session. Records emitted before :meth:`open` wait, in order, and go
    out when it is called; ``samples_written`` counts the sample records handed out."""

    def __init__(self) -> None:
        self.sinks: list[Sink] = []
        self.is_open = False
        self.samples_written = 0
        self._waiting: list[tuple[str, object, int]] = []
        self._statuses: dict[str, tuple[str, str | None]] = {}
        #: One tuple per distinct status, not per name (20,000 names alike share a few).
        self._status_pairs: dict[tuple[str, str | None], tuple[str, str | None]] = {}

    def __bool__(self) -> bool:
        return bool(self.sinks)

    def __len__(self) -> int:
        return len(self.sinks)

    def add(self, opener: Opener, *, per_frame: bool = False, pose: str = MATRIX) -> None:
        self.sinks.append(Sink(opener, bool(per_frame), pose=pose))

    @property
    def recorders(self) -> list[Recorder]:
        return [s.recorder for s in self.sinks if s.recorder is not None]

    def poses(self, *, per_frame: bool) -> list[str]:
        """The poses the sample sinks (or, with ``per_frame``, the frame sinks) write in."""
        return sorted({s.pose for s in self.sinks if s.per_frame is per_frame})

    def open(self, header: Mapping[str, object]) -> None:
        """Open every sink not open yet with ``header``, then hand out what waited."""
        for sink in self.sinks:
            if sink.recorder is None:
                sink.recorder = sink.open(header)
        self.is_open = True
        waiting, self._waiting = self._waiting, []
        for what, payload, count in waiting:
            self.deliver(what, payload, count)

    def emit(self, what: str, payload: object, count: int) -> None:
        """Hand out a record now, or when the sinks open (see :meth:`deliver`)."""
        if not self.is_open:
            self._waiting.append((what, payload, count))
            return
        self.deliver(what, payload, count)

    def deliver(self, what: str, payload: object, count: int) -> None:
        """Hand out one record to every open sink that wants it: :data:`SAMPLES` (encoded
        text by pose, ``count`` samples), :data:`FRAME` (a frame record by pose),
        :data:`STATUSES` (a list of status records) or :data:`MARKER`."""
        for sink in self.sinks:
            recorder = sink.recorder
            if recorder is None or recorder.closed:
                continue
            if what == SAMPLES:
                if not sink.per_frame:
                    recorder.write_encoded(payload[sink.pose], count)  # type: ignore[index]
            elif what == FRAME:
                if sink.per_frame:
                    recorder.write_frame(payload[sink.pose])  # type: ignore[index]
            elif what == STATUSES:
                recorder.write_statuses(payload)  # type: ignore[arg-type]
            elif what == MARKER:
                marker: MarkerRecord = payload  # type: ignore[assignment]
                recorder.write_marker(marker.name, marker.timestamp)
        if what == SAMPLES:
            self.samples_written += count

    def note_statuses(
        self,
        moment: float,
        statuses: Iterable[tuple[str, str | None, str, str, str | None]],
    ) -> None:
        """Emit a status record for each ``(name, element, type, state, reason)`` whose
        state or reason differs from the last one noted (all of them the first time)."""
        changed: list[StatusRecord] = []
        known, pairs = self._statuses, self._status_pairs
        for name, element, element_type, state, reason in statuses:
            current = (state, reason)
            if known.get(name) != current:
                known[name] = pairs.setdefault(current, current)
                changed.append(StatusRecord(moment, name, element, element_type, state, reason))
        if changed:
            self.emit(STATUSES, changed, 0)

    def close(
        self, reason: str, final: Mapping[str, Mapping[str, object]] | None, moment: float
    ) -> None:
        """Write ``final`` (the final statistics, unless None) and the end record of every
        open sink."""
        for sink in self.sinks:
            recorder = sink.recorder
            if recorder is None or recorder.closed:
                continue
            if final is not None:
                recorder.write_stats(final, moment)
            recorder.close(reason)
