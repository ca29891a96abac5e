"""What a monitor view draws: one snapshot of a session (:class:`Snapshot`), its elements
(:class:`ElementView`) and their units (:class:`UnitView`), and what
:meth:`~gadgetctl.monitor.session.MonitorSession.frames` yields per frame (:class:`Frame`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

from gadgetctl.monitor.records import MarkerRecord
from gadgetctl.monitor.stats import DeviceSnapshot


@dataclass(slots=True)
class UnitView:
    """One unit of one kind, as a view shows it.

    ``value``: analog normalised to [0, 1]; digital 0/1 for devices and the toggle state
    0-3 (off, on, toggle on, toggle off) for proxies; position a 4x4 array in meters; glove
    a (6, 4) array of radians; gesture, command and hat integers; string text; keyboard and
    mouse the names of the keys held. ``raw`` is the device datum where it differs.
    """

    kind: str
    unit: int
    value: Any
    raw: Any = None
    changed: bool = False  # digital: the state changed during this frame
    presses: int = 0  # digital: presses (off -> on) counted since the start or the last reset
    history: Sequence[float] | None = None  # analog: the normalised value, one per frame


@dataclass(slots=True)
class ElementView:
    """One device, proxy or alias: its status, the statistics of the device that feeds it
    and its current values."""

    name: str
    element: str  # device, proxy, alias
    type: str
    state: str
    reason: str | None = None
    target: str | None = None  # a proxy's device, an alias's proxy
    #: Why VR Juggler would leave this element pending although gadgetctl runs it.
    note: str | None = None
    unit: int | None = None  # a proxy's unit
    device: str | None = None  # the device whose statistics are shown
    stats: DeviceSnapshot | None = None
    age: float | None = None  # seconds since the newest sample
    count: int = 0  # samples this frame (sampling instants)
    values: list[UnitView] = field(default_factory=list)
    health: dict[str, object] = field(default_factory=dict)  # a device's Input.health()
    #: A stupefied proxy's or alias's device when that device is pending, faulted or
    #: otherwise not running: the one cause, whose own line gives the reason.
    blocked_by: str | None = None


@dataclass(slots=True)
class Snapshot:
    frame: int
    timestamp: float
    elapsed: float
    frame_rate: float
    elements: list[ElementView]
    markers: list[MarkerRecord]
    keyboards: list[str]
    samples_written: int
    finished: bool = False


class Frame(NamedTuple):
    """What :meth:`MonitorSession.frames` yields once per frame (a named tuple: made every
    frame, it costs a fifth of a frozen dataclass)."""

    number: int
    timestamp: float
    elapsed: float
    samples: int  # samples of the watched devices this frame (sampling instants)
