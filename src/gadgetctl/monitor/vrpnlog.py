"""VRPN log files (``.vrpn``) read as gadgetctl recordings, for ``replay`` and ``replay
--summary``.

Every VRPN device (sender) of the log becomes a recorded device of the same name: tracker
sensors are position units (4x4 matrices in metres from position and quaternion), buttons
digital units, analog channels analog units (value normalised over VRPN's usual -1..1, raw
kept). Sample times are the log's own timestamps (the VRPN sender's clock, Unix seconds).
Each button change is one sample of its unit; a button "States" message one sample of every
button; a tracker report one sample of its sensor; an analog report one sample per channel;
a dial update one sample of the analog unit of its dial, the dial's accumulated rotation in
revolutions (as VRPN_drv reads dials). A text message (``vrpn_Base text_message``) is a
marker named "DEVICE: SEVERITY LEVEL: TEXT". A message whose time is 0 (the C++
``vrpn_Button_Server`` writes that) takes the time of the message before it (of the first
timed message for those that open the log).

A file is a VRPN log when it starts with a VRPN cookie (:func:`is_vrpn_log`). Reading is
lazy and bounded (:class:`gadgetctl.vrpn.LogReader`); a damaged record stops the reading
with an error problem, a file cut short ends it with a warning, as for gadgetctl's own
recordings.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from datetime import UTC, datetime
from pathlib import Path

from gadgetctl.monitor.recording import Recording, RecordingError, RecordingProblem
from gadgetctl.monitor.records import (
    REPLAY_UNITS,
    EndRecord,
    HeaderRecord,
    MarkerRecord,
    Record,
    SampleRecord,
)

MAGIC = b"vrpn: ver. "
#: Characters of a text message kept in its marker's name.
MAX_MARKER_NAME = 300
#: Messages of time 0 at the start of a log held for the first timed message's time at most.
MAX_UNTIMED = 1000
ANALOG_RANGE = (-1.0, 1.0)


def is_vrpn_log(path: Path) -> bool:
    """Whether ``path`` is a regular file starting with a VRPN cookie."""
    try:
        if not path.is_file():
            return False
        with path.open("rb") as f:
            return f.read(len(MAGIC)) == MAGIC
    except OSError:
        return False


def _matrix(position: tuple[float, ...], quat: tuple[float, ...]) -> list[list[float]]:
    x, y, z, w = quat
    n = x * x + y * y + z * z + w * w
    s = 2.0 / n if n > 0.0 else 0.0
    return [
        [1.0 - s * (y * y + z * z), s * (x * y - z * w), s * (x * z + y * w), float(position[0])],
        [s * (x * y + z * w), 1.0 - s * (x * x + z * z), s * (y * z - x * w), float(position[1])],
        [s * (x * z - y * w), s * (y * z + x * w), 1.0 - s * (x * x + y * y), float(position[2])],
        [0.0, 0.0, 0.0, 1.0],
    ]


def _normalise(raw: float) -> float:
    low, high = ANALOG_RANGE
    return (min(max(raw, low), high) - low) / (high - low)


#: (sender, kind) or sender -> recorded device name.
Routes = Mapping[tuple[str, str] | str, str]
_KINDS = (
    ("tracker", "position", "Tracker0@localhost", 2),
    ("button", "digital", "Button0@localhost", 1),
    ("analog", "analog", "Analog@localhost", 1),
)  # property prefix, kind, vrpn.jdef defaults


def routes_from_configuration(configuration) -> dict[tuple[str, str], str]:
    """Where the configuration's ``vrpn`` elements would take each VRPN device's data, as
    VRPN_drv does: ``(sender, kind) -> element``, e.g. ``("Tracker0", "position") -> "Vrpn"``."""
    from gadgetctl.vrpn import VrpnNameError, parse_device_name

    routes: dict[tuple[str, str], str] = {}
    for element in configuration.by_type("vrpn"):
        for prefix, kind, default_server, default_count in _KINDS:
            servers, counts = element.texts(f"{prefix}_server"), element.texts(f"{prefix}_count")
            server = servers[0].strip() if servers else default_server
            try:
                count = int(counts[0]) if counts else default_count
                sender = parse_device_name(server).device
            except (ValueError, VrpnNameError):
                continue
            if count > 0:
                routes.setdefault((sender, kind), element.full_name)
    return routes


def _route(routes: Routes, sender: str, kind: str) -> str:
    return routes.get((sender, kind)) or routes.get(sender) or sender


def read_vrpn_log(path: str | Path, routes: Routes | None = None) -> Recording:
    """Open a VRPN log as a :class:`Recording`; :class:`RecordingError` if it is not one.
    ``routes`` renames devices per VRPN sender (and kind): several senders may feed one
    device, as the tracker, button and analog devices of one ``vrpn`` element do."""
    from gadgetctl.vrpn import LogFormatError, LogReader

    path = Path(path)
    try:
        reader = LogReader(path)
    except LogFormatError as exc:
        raise RecordingError(f"{path}: not a readable VRPN log ({exc})") from None
    except OSError as exc:
        raise RecordingError(f"{path}: cannot read: {exc.strerror or exc}") from None
    routes = routes or {}
    first, elements = _scan(path, routes)
    created = datetime.fromtimestamp(first, UTC).strftime("%Y-%m-%dT%H:%M:%S.%fZ") if first else ""
    header = HeaderRecord(
        created,
        first or 0.0,
        first or 0.0,
        f"VRPN {reader.version} log",
        {"vrpn_log": str(path), "vrpn_version": reader.version, "elements": elements},
    )
    problems: list[RecordingProblem] = []
    return Recording(header, _records(reader, problems, routes), problems, path)


def _scan(path: Path, routes: Routes) -> tuple[float | None, dict[str, dict[str, object]]]:
    """The first timestamp and, per device, its kinds and unit counts (a first pass, so the
    header describes every device as a monitor recording's header does)."""
    from gadgetctl.vrpn import LogFormatError, LogReader, codecs

    first: float | None = None
    units: dict[str, dict[str, int]] = {}
    try:
        with LogReader(path) as reader:
            for m in reader:
                if m.sender is None:
                    continue
                report = m.report
                if isinstance(report, codecs.TrackerPose) and report.sensor < REPLAY_UNITS:
                    kind, count = "position", report.sensor + 1
                elif isinstance(report, codecs.ButtonChange):
                    kind, count = "digital", report.button + 1
                elif isinstance(report, codecs.ButtonStates):
                    kind, count = "digital", len(report.states)
                elif isinstance(report, codecs.AnalogChannels):
                    kind, count = "analog", len(report.channels)
                elif isinstance(report, codecs.DialUpdate) and 0 <= report.dial < codecs.MAX_DIALS:
                    kind, count = "analog", report.dial + 1
                else:
                    continue
                if first is None and m.timestamp > 0:
                    first = m.timestamp
                device = units.setdefault(_route(routes, m.sender, kind), {})
                device[kind] = max(device.get(kind, 0), count)
    except (LogFormatError, OSError):
        pass  # the second pass reports it
    elements: dict[str, dict[str, object]] = {}
    for name, counts in units.items():
        element: dict[str, object] = {
            "element": "device",
            "type": "vrpn",
            "kinds": sorted(counts),
            "units": counts,
        }
        if "analog" in counts:
            element["min"], element["max"] = ANALOG_RANGE
        elements[name] = element
    return first, elements


def _samples(
    m, skipped: list[int], routes: Routes, t: float, dials: dict[tuple[str, int], float]
) -> list[SampleRecord]:
    """The sample records of one log message at time ``t`` (none for other types);
    ``dials`` holds each dial's rotation so far."""
    from gadgetctl.vrpn.codecs import (
        MAX_DIALS,
        AnalogChannels,
        ButtonChange,
        ButtonStates,
        DialUpdate,
        TrackerPose,
    )

    sender, report = m.sender, m.report
    kind = (
        "position"
        if isinstance(report, TrackerPose)
        else "analog"
        if isinstance(report, AnalogChannels)
        else "digital"
    )
    device = _route(routes, sender, kind)
    if isinstance(report, TrackerPose):
        if report.sensor >= REPLAY_UNITS:
            skipped[0] += 1
            return []
        return [
            SampleRecord(
                device, "position", report.sensor, t, _matrix(report.position, report.quat), None
            )
        ]
    if isinstance(report, ButtonChange):
        return [SampleRecord(device, "digital", report.button, t, report.state, report.state)]
    if isinstance(report, ButtonStates):
        return [
            SampleRecord(device, "digital", unit, t, state, state)
            for unit, state in enumerate(report.states)
        ]
    if isinstance(report, AnalogChannels):
        return [
            SampleRecord(device, "analog", unit, t, _normalise(raw), raw)
            for unit, raw in enumerate(report.channels)
        ]
    if isinstance(report, DialUpdate):
        if not 0 <= report.dial < MAX_DIALS:
            skipped[1] += 1
            return []
        key = (device, report.dial)
        raw = dials[key] = dials.get(key, 0.0) + report.delta
        return [SampleRecord(device, "analog", report.dial, t, _normalise(raw), raw)]
    return []


def _marker(m, t: float) -> MarkerRecord | None:
    """A text message as a marker (None for other messages)."""
    from gadgetctl.safetext import printable
    from gadgetctl.vrpn.codecs import TextReport

    report = m.report
    if not isinstance(report, TextReport):
        return None
    kind = {0: "normal", 1: "warning", 2: "error"}.get(report.severity, "severity")
    name = f"{m.sender}: {kind} {report.level}: {report.text}"
    return MarkerRecord(printable(name)[:MAX_MARKER_NAME], t)


def _records(reader, problems: list[RecordingProblem], routes: Routes) -> Iterator[Record]:
    from gadgetctl.vrpn import LogFormatError
    from gadgetctl.vrpn.codecs import MAX_DIALS

    skipped = [0, 0]  # sensors beyond REPLAY_UNITS, dials beyond MAX_DIALS
    samples = markers = 0
    last: float | None = None
    held: list = []  # messages of time 0 before the first timed one
    dials: dict[tuple[str, int], float] = {}
    damaged = False
    try:
        for m in reader:
            if m.sender is None:
                continue
            if m.timestamp > 0:
                t = m.timestamp
            elif last is not None:
                t = last
            elif len(held) < MAX_UNTIMED:
                held.append(m)  # no time yet: they take the first one's
                continue
            else:
                t = 0.0  # a log that never gives a time: as written
            for early in [*held, m]:
                marker = _marker(early, t)
                if marker is not None:
                    markers += 1
                    last = t
                    yield marker
                for record in _samples(early, skipped, routes, t, dials):
                    samples += 1
                    last = record.timestamp
                    yield record
            held.clear()
    except LogFormatError as exc:
        damaged = True
        problems.append(
            RecordingProblem(
                reader.records + 1, "error", f"VRPN log damaged at {exc}; the rest is not read"
            )
        )
    finally:
        reader.close()
    if reader.truncated:
        problems.append(
            RecordingProblem(
                reader.records + 1,
                "warning",
                "the VRPN log ends inside a record (the writer was stopped)",
            )
        )
    if skipped[0]:
        problems.append(
            RecordingProblem(
                reader.records,
                "warning",
                f"{skipped[0]} tracker reports of sensors beyond {REPLAY_UNITS - 1} skipped",
            )
        )
    if skipped[1]:
        problems.append(
            RecordingProblem(
                reader.records,
                "warning",
                f"{skipped[1]} dial updates of dials beyond {MAX_DIALS - 1} skipped",
            )
        )
    if reader.bad_reports:
        problems.append(
            RecordingProblem(
                reader.records, "warning", f"{reader.bad_reports} malformed device reports skipped"
            )
        )
    if last is not None and not damaged and not reader.truncated:
        yield EndRecord(last, "end of the VRPN log", samples, markers, 0)
