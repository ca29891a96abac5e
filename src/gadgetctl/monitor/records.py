"""Monitor records and their NDJSON encoding: one JSON object per line, each with ``"v": 1``.

Sample records are the hot path and are formatted by hand (``repr`` of floats round-trips
exactly; :mod:`gadgetctl.monitor.numbertext` writes numpy arrays' numbers so); the rare
records go through :func:`json.dumps`. Non-finite floats are written as
``NaN``, ``Infinity`` and ``-Infinity``, as Python's :mod:`json` does. The format is
described in ``docs/recording-format.md``.
"""

from __future__ import annotations

import itertools
import json
import re
import time
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field, replace
from datetime import UTC, datetime
from typing import Any

FORMAT_NAME = "gadgetctl-recording"
FORMAT_VERSION = 1
#: Units of one device and kind a recording may name (0 to MAX_UNITS - 1): a sample of a unit
#: beyond that is malformed, so no recording can make a replay allocate without limit.
MAX_UNITS = 1 << 16
#: Units of one device and kind a replay plays (0 to REPLAY_UNITS - 1), as many as the VRPN and
#: Trackd drivers take. A replayed sampling instant holds every unit up to the highest one seen,
#: so one sample of a far unit would make every later instant that wide: samples of units
#: beyond are skipped and counted (one line on stderr).
REPLAY_UNITS = 1024
KINDS = ("analog", "digital", "position", "glove", "gesture", "command", "string", "hat")


class RecordFormatError(ValueError):
    """A line or JSON object that is not a valid record."""


class UnknownRecordType(RecordFormatError):
    """A well-formed record of a type this version does not know (newer writers may add types)."""


@dataclass(frozen=True, slots=True)
class SampleRecord:
    """One sample of one unit of one device (or proxy); ``timestamp`` in monotonic seconds."""

    device: str
    kind: str
    unit: int
    timestamp: float
    value: object
    raw: object


@dataclass(frozen=True, slots=True)
class MarkerRecord:
    """A named point in time, e.g. set by the user while recording."""

    name: str
    timestamp: float


@dataclass(frozen=True, slots=True)
class FrameDevice:
    """One device in a frame: samples received this frame and the newest value per kind/unit."""

    count: int
    values: Mapping[str, Mapping[int, object]] = field(default_factory=dict)


@dataclass(frozen=True, slots=True)
class FrameRecord:
    """The per-frame output: frame number, frame timestamp and each device's newest values."""

    frame: int
    timestamp: float
    devices: Mapping[str, FrameDevice] = field(default_factory=dict)


@dataclass(frozen=True, slots=True)
class StatsRecord:
    """A snapshot of running statistics: device name -> statistic name -> value."""

    timestamp: float
    devices: Mapping[str, Mapping[str, object]] = field(default_factory=dict)


@dataclass(frozen=True, slots=True)
class EndRecord:
    """The last record of a recording closed cleanly or on SIGINT/SIGTERM."""

    timestamp: float
    reason: str
    samples: int
    markers: int
    frames: int


@dataclass(frozen=True, slots=True)
class StatusRecord:
    """An element's state: written for each element when a session starts and whenever its
    state or reason changes (``element`` is device, proxy, alias, input_manager or None)."""

    timestamp: float
    name: str
    element: str | None
    element_type: str
    state: str
    reason: str | None = None


@dataclass(frozen=True, slots=True)
class HeaderRecord:
    """The first line of a recording; ``info`` is free-form data from the writer."""

    created: str
    wall_time: float
    monotonic: float
    generator: str
    info: Mapping[str, object] = field(default_factory=dict)
    version: int = FORMAT_VERSION

    @classmethod
    def now(
        cls, info: Mapping[str, object] | None = None, *, clock: Any = time.monotonic
    ) -> HeaderRecord:
        """A header stamped with the current wall-clock and ``clock`` times."""
        from gadgetctl import __version__

        wall = time.time()
        created = datetime.fromtimestamp(wall, UTC).strftime("%Y-%m-%dT%H:%M:%S.%fZ")
        return cls(created, wall, clock(), f"gadgetctl {__version__}", dict(info or {}))


Record = (
    SampleRecord
    | MarkerRecord
    | FrameRecord
    | StatsRecord
    | StatusRecord
    | EndRecord
    | HeaderRecord
)


# --------------------------------------------------------------------------- encoding

_NUMERIC_LIST = re.compile(r"[\[\]0-9eE.,+\- ]*")
#: Device names as JSON text (the record heads are made from them: a head kept per device
#: and kind, with its key, was 4 MB for 10,000 devices of three kinds).
_NAME_TEXTS: dict[str, str] = {}
_KIND_TEXTS: dict[str, str] = {}
#: Names kept: enough for 10,000 devices (at 4096 such a monitor made every head anew, with
#: json.dumps).
_PREFIX_CACHE_LIMIT = 1 << 16
#: Devices of a statistics record encoded by one encoder call (one call each cost 10,000
#: devices' record more than computing their statistics).
STATS_BATCH = 128
_SCALARS = (float, int, str, bool)
_DECODER = json.JSONDecoder()


def _json_default(value: object) -> object:
    tolist = getattr(value, "tolist", None)
    if tolist is not None:  # numpy arrays and scalars
        return tolist()
    if isinstance(value, (set, frozenset, tuple)):
        return list(value)
    return str(value)


#: What ``json.dumps(obj, separators=(",", ":"), default=_json_default)`` makes, without a
#: new encoder for each of the 20,000 status and statistics entries of a large run.
_dumps = json.JSONEncoder(separators=(",", ":"), default=_json_default).encode


def _nonfinite(value: float) -> str:
    return "NaN" if value != value else ("Infinity" if value > 0 else "-Infinity")


def encode_value(value: object) -> str:
    """``value`` as JSON text; floats round-trip, tuples and numpy arrays become arrays."""
    t = type(value)
    if t is float:
        return repr(value) if value - value == 0.0 else _nonfinite(value)
    if t is int:
        return repr(value)
    if t is list:
        text = repr(value)
        if _NUMERIC_LIST.fullmatch(text):  # nested lists of finite floats and ints
            return text.replace(" ", "")
        return "[" + ",".join([encode_value(v) for v in value]) + "]"
    if t is str:
        return json.dumps(value)
    if t is bool:
        return "true" if value else "false"
    if value is None:
        return "null"
    if t is tuple:
        return encode_value(list(value))
    tolist = getattr(value, "tolist", None)
    if tolist is not None:
        return encode_value(tolist())
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return int.__repr__(value)
    if isinstance(value, float):
        return encode_value(float(value))
    if isinstance(value, str):
        return json.dumps(str(value))
    if isinstance(value, (list, tuple)):
        return encode_value(list(value))
    if isinstance(value, Mapping):
        return _dumps(value)
    raise TypeError(f"cannot encode a sample value of type {t.__name__}")


def _name_text(name: str) -> str:
    """``json.dumps(name)``, kept for the names seen most."""
    text = _NAME_TEXTS.get(name)
    if text is None:
        text = json.dumps(name)
        if len(_NAME_TEXTS) < _PREFIX_CACHE_LIMIT:
            _NAME_TEXTS[name] = text
    return text


def sample_head(device: str, kind: str) -> str:
    """The head of a sample record of ``device`` and ``kind``, up to its unit."""
    if type(device) is not str or type(kind) is not str:
        if not isinstance(device, str) or not isinstance(kind, str):
            raise TypeError("device and kind of a sample record must be strings")
        return _HEAD + json.dumps(device) + ',"kind":' + json.dumps(kind) + ',"unit":'
    name = _name_text(device)
    kind_text = _KIND_TEXTS.get(kind)
    if kind_text is None:
        kind_text = json.dumps(kind)
        if len(_KIND_TEXTS) < 256:
            _KIND_TEXTS[kind] = kind_text
    return _HEAD + name + ',"kind":' + kind_text + ',"unit":'


_HEAD = '{"v":1,"type":"sample","device":'


def _timestamp(value: object) -> str:
    if type(value) is float and value - value == 0.0:
        return repr(value)
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        number = float(value)
        if number - number == 0.0:
            return repr(number)
    raise ValueError(f"timestamp must be a finite number, not {value!r}")


def _unit(value: object) -> str:
    if type(value) is int:
        return repr(value)
    if hasattr(value, "__index__") and not isinstance(value, bool):
        return repr(value.__index__())  # type: ignore[attr-defined]
    raise ValueError(f"unit must be an integer, not {value!r}")


def encode_samples(records: Iterable[SampleRecord]) -> str:
    """Sample records as NDJSON lines (each ending in a newline), formatted by hand."""
    parts: list[str] = []
    append = parts.append
    for r in records:
        prefix = sample_head(r.device, r.kind)
        unit = r.unit
        ts = r.timestamp
        value = r.value
        raw = r.raw
        t = type(value)
        if (t is float and value - value == 0.0) or t is int:
            vtext = repr(value)
        else:
            vtext = encode_value(value)
        if raw is value or (type(raw) is t and t in _SCALARS and raw == value):
            tail = "}\n"
        else:
            tail = ',"raw":' + encode_value(raw) + "}\n"
        append(
            prefix
            + (repr(unit) if type(unit) is int else _unit(unit))
            + ',"timestamp":'
            + (repr(ts) if type(ts) is float and ts - ts == 0.0 else _timestamp(ts))
            + ',"value":'
            + vtext
            + tail
        )
    return "".join(parts)


def _scalar_text(value: object) -> str:
    t = type(value)
    if (t is float and value - value == 0.0) or t is int:
        return repr(value)
    return encode_value(value)


def encode_rows(
    device: str,
    kind: str,
    timestamps: Iterable[float],
    rows: Iterable[Iterable[object]],
    raw_rows: Iterable[Iterable[object]] | None = None,
) -> str:
    """Sample records of consecutive samples of one device and kind, as NDJSON lines.

    ``rows[i][unit]`` is the value of ``unit`` at ``timestamps[i]``; ``raw_rows`` (same
    shape) the raw data, omitted where it equals the value (None: raw is the value). The
    text is the one :func:`encode_samples` writes for the same records, without building
    them: this is the monitor's hot path (values as Python lists, e.g. numpy ``tolist()``).
    """
    prefix = sample_head(device, kind)
    parts: list[str] = []
    append = parts.append
    heads: list[str] = []
    if raw_rows is None:
        raw_rows = itertools.repeat(None)
    for ts, row, raws in zip(timestamps, rows, raw_rows):  # noqa: B905 - raw_rows may repeat None
        stamp = (
            ',"timestamp":'
            + (repr(ts) if type(ts) is float and ts - ts == 0.0 else _timestamp(ts))
            + ',"value":'
        )
        if len(heads) < len(row):
            heads.extend(prefix + repr(u) for u in range(len(heads), len(row)))
        if raws is None:
            for unit, value in enumerate(row):
                t = type(value)
                append(
                    heads[unit]
                    + stamp
                    + (
                        repr(value)
                        if (t is float and value - value == 0.0) or t is int
                        else encode_value(value)
                    )
                    + "}\n"
                )
        else:
            for unit, (value, raw) in enumerate(zip(row, raws, strict=True)):
                t = type(value)
                vtext = (
                    repr(value)
                    if (t is float and value - value == 0.0) or t is int
                    else encode_value(value)
                )
                if raw is value or (type(raw) is t and t in _SCALARS and raw == value):
                    append(heads[unit] + stamp + vtext + "}\n")
                else:
                    append(heads[unit] + stamp + vtext + ',"raw":' + _scalar_text(raw) + "}\n")
    return "".join(parts)


def encode_record(record: Record) -> str:
    """Any record as one NDJSON line ending in a newline."""
    if isinstance(record, SampleRecord):
        return encode_samples((record,))
    if isinstance(record, MarkerRecord):
        obj: dict[str, object] = {
            "v": FORMAT_VERSION,
            "type": "marker",
            "name": record.name,
            "timestamp": record.timestamp,
        }
    elif isinstance(record, FrameRecord):
        obj = {
            "v": FORMAT_VERSION,
            "type": "frame",
            "frame": record.frame,
            "timestamp": record.timestamp,
            "devices": {
                name: {
                    "count": dev.count,
                    "values": {
                        kind: {str(u): v for u, v in units.items()}
                        for kind, units in dev.values.items()
                    },
                }
                for name, dev in record.devices.items()
            },
        }
    elif isinstance(record, StatsRecord):
        obj = {
            "v": FORMAT_VERSION,
            "type": "stats",
            "timestamp": record.timestamp,
            "devices": {name: dict(values) for name, values in record.devices.items()},
        }
    elif isinstance(record, StatusRecord):
        obj = {
            "v": FORMAT_VERSION,
            "type": "status",
            "timestamp": record.timestamp,
            "name": record.name,
            "element": record.element,
            "element_type": record.element_type,
            "state": record.state,
            "reason": record.reason,
        }
    elif isinstance(record, EndRecord):
        obj = {
            "v": FORMAT_VERSION,
            "type": "end",
            "timestamp": record.timestamp,
            "reason": record.reason,
            "samples": record.samples,
            "markers": record.markers,
            "frames": record.frames,
        }
    elif isinstance(record, HeaderRecord):
        obj = {
            "v": record.version,
            "type": "header",
            "format": FORMAT_NAME,
            "created": record.created,
            "wall_time": record.wall_time,
            "monotonic": record.monotonic,
            "clock": "monotonic",
            "generator": record.generator,
            "info": dict(record.info),
        }
    else:
        raise TypeError(f"not a record: {type(record).__name__}")
    if isinstance(obj.get("timestamp"), (int, float)):
        _timestamp(obj["timestamp"])
    return _dumps(obj) + "\n"


def encode_status_parts(records: Iterable[StatusRecord], size: int = 1 << 20) -> Iterator[str]:
    """Status records as NDJSON lines, each what :func:`encode_record` makes of it, with each
    distinct timestamp and (element, type, state, reason) encoded once (a session's start
    writes one record per element, 20,000 alike for 10,000 devices and their proxies), joined
    in parts of about ``size`` characters (0: a line each), in order: as one string they were
    megabytes of text made from as many again in pieces."""
    parts: list[str] = []
    length = 0
    stamps: dict[float, str] = {}
    tails: dict[tuple[object, ...], str] = {}
    for r in records:
        moment = r.timestamp
        if type(moment) is not float or type(r.name) is not str:
            line = encode_record(r)  # the general path checks and encodes the rest
        else:
            stamp = stamps.get(moment)
            if stamp is None:
                stamp = stamps[moment] = _timestamp(moment)  # raises for a non-finite one
            key = (r.element, r.element_type, r.state, r.reason)
            tail = tails.get(key)
            if tail is None:
                tail = tails[key] = (
                    f',"element":{_dumps(r.element)},"element_type":{_dumps(r.element_type)}'
                    f',"state":{_dumps(r.state)},"reason":{_dumps(r.reason)}}}\n'
                )
            line = f'{{"v":{FORMAT_VERSION},"type":"status","timestamp":{stamp}'
            line += f',"name":{_name_text(r.name)}{tail}'
        parts.append(line)
        length += len(line)
        if length >= size:
            yield "".join(parts) if len(parts) > 1 else line
            parts.clear()
            length = 0
    if parts:
        yield "".join(parts)


def encode_stats_parts(record: StatsRecord, size: int = 1 << 20) -> Iterator[str]:
    """The text of :func:`encode_record` for ``record`` in parts of about ``size`` characters
    (a device at a time): the statistics of 10,000 devices are a 6 MB line, which as one
    string, and its bytes, raised a monitor's peak memory by 20 MB at its very end."""
    _timestamp(record.timestamp)
    head = _dumps(
        {"v": FORMAT_VERSION, "type": "stats", "timestamp": record.timestamp, "devices": {}}
    )
    parts = [head[:-2]]  # without the closing "}}" of the empty devices
    length = len(parts[0])
    first = True
    # :data:`STATS_BATCH` devices to one encoder call: the object of them, without its braces,
    # is their ``"name":{...}`` pairs, as one call a device wrote them
    devices = iter(record.devices.items())
    while batch := {
        name: values if type(values) is dict else dict(values)
        for name, values in itertools.islice(devices, STATS_BATCH)
    }:
        text = _dumps(batch)
        text = text[1:-1] if first else "," + text[1:-1]
        first = False
        parts.append(text)
        length += len(text)
        if length >= size:
            yield "".join(parts)
            parts, length = [], 0
    parts.append("}}\n")
    yield "".join(parts)


def encode_header_parts(record: HeaderRecord, size: int = 1 << 20) -> Iterator[str]:
    """The text of :func:`encode_record` for ``record`` in parts of about ``size``
    characters: its info an entry at a time, and a dict in it with string keys (a session's
    ``elements``, one entry per element) an entry of that at a time. The header of 10,000
    devices and their proxies is a line of megabytes, which as one string was made of as
    many again in pieces."""
    info = record.info
    if type(info) is not dict or not all(type(k) is str for k in info):
        yield encode_record(record)  # keys json would convert, or not a dict: as ever
        return
    head = encode_record(replace(record, info={}))
    parts = [head[: -len("{}}\n")] + "{"]  # up to the info's opening brace
    length = len(parts[0])
    comma = ""
    for key, value in info.items():
        for text in _item_parts(comma + _dumps(key) + ":", value):
            parts.append(text)
            length += len(text)
            if length >= size:
                yield "".join(parts)
                parts, length = [], 0
        comma = ","
    parts.append("}}\n")
    yield "".join(parts)


def _item_parts(lead: str, value: object) -> Iterator[str]:
    """``lead`` and ``value`` as :func:`_dumps` writes them, a dict with string keys an entry
    at a time."""
    if type(value) is not dict or not all(type(k) is str for k in value):
        yield lead + _dumps(value)
        return
    yield lead + "{"
    comma = ""
    made: dict[int, str] = {}  # (an entry many names share, as alike devices do: made once)
    for name, entry in value.items():
        text = made.get(id(entry))
        if text is None:
            text = made[id(entry)] = _dumps(entry)
        yield comma + _name_text(name) + ":" + text
        comma = ","
    yield "}"


# --------------------------------------------------------------------------- decoding


def _field(obj: Mapping[str, Any], name: str, kind: type | tuple[type, ...]) -> Any:
    try:
        value = obj[name]
    except KeyError:
        raise RecordFormatError(f"missing field {name!r}") from None
    if not isinstance(value, kind) or (isinstance(value, bool) and kind is not bool):
        raise RecordFormatError(f"field {name!r} has the wrong type ({type(value).__name__})")
    return value


def _time(obj: Mapping[str, Any], name: str = "timestamp") -> float:
    try:
        value = float(_field(obj, name, (int, float)))
    except OverflowError:
        value = float("inf")
    if value - value != 0.0:
        raise RecordFormatError(f"field {name!r} is not a finite number")
    return value


def _optional(obj: Mapping[str, Any], name: str, kind: type, default: Any) -> Any:
    """An optional field of type ``kind`` (an int for a float), ``default`` when absent."""
    if name not in obj:
        return default
    if kind is float:
        return _time(obj, name)
    return _field(obj, name, kind)


def _mapping(obj: Mapping[str, Any], name: str) -> Mapping[str, Any]:
    return _field(obj, name, dict) if name in obj else {}


def _frame_devices(obj: Mapping[str, Any]) -> dict[str, FrameDevice]:
    devices = {}
    for name, entry in _mapping(obj, "devices").items():
        if not isinstance(entry, dict):
            raise RecordFormatError(f"frame entry for {name!r} is not an object")
        values: dict[str, dict[int, object]] = {}
        for kind, units in _mapping(entry, "values").items():
            if not isinstance(units, dict):
                raise RecordFormatError(f"frame values of {name!r}/{kind} are not an object")
            try:
                values[kind] = {int(u): v for u, v in units.items()}
            except ValueError:
                raise RecordFormatError(
                    f"frame values of {name!r}/{kind} have a non-integer unit"
                ) from None
        devices[name] = FrameDevice(_field(entry, "count", int), values)
    return devices


def decode_record(obj: object) -> Record:
    """The record a decoded JSON object describes; raises :class:`RecordFormatError`."""
    if not isinstance(obj, dict):
        raise RecordFormatError("not a JSON object")
    version = _field(obj, "v", int)
    if version < 1:
        raise RecordFormatError(f"invalid version {version}")
    if version > FORMAT_VERSION:
        raise RecordFormatError(
            f"record version {version} is newer than this reader ({FORMAT_VERSION})"
        )
    kind = _field(obj, "type", str)
    if kind == "sample":
        if "value" not in obj:
            raise RecordFormatError("missing field 'value'")
        value = obj["value"]
        unit = _field(obj, "unit", int)
        if not 0 <= unit < MAX_UNITS:
            raise RecordFormatError(f"unit {unit} out of range (0 to {MAX_UNITS - 1})")
        return SampleRecord(
            _field(obj, "device", str),
            _field(obj, "kind", str),
            unit,
            _time(obj),
            value,
            obj.get("raw", value),
        )
    if kind == "frame":
        return FrameRecord(_field(obj, "frame", int), _time(obj), _frame_devices(obj))
    if kind == "marker":
        return MarkerRecord(_field(obj, "name", str), _time(obj))
    if kind == "stats":
        devices = _mapping(obj, "devices")
        if not all(isinstance(v, dict) for v in devices.values()):
            raise RecordFormatError("stats entries must be objects")
        return StatsRecord(_time(obj), devices)
    if kind == "status":
        element = obj.get("element")
        reason = obj.get("reason")
        return StatusRecord(
            _time(obj),
            _field(obj, "name", str),
            element if isinstance(element, str) else None,
            str(obj.get("element_type", "")),
            _field(obj, "state", str),
            reason if isinstance(reason, str) else None,
        )
    if kind == "end":
        return EndRecord(
            _time(obj),
            _field(obj, "reason", str),
            _field(obj, "samples", int),
            _optional(obj, "markers", int, 0),
            _optional(obj, "frames", int, 0),
        )
    if kind == "header":
        if obj.get("format") != FORMAT_NAME:
            raise RecordFormatError(f"header format is not {FORMAT_NAME!r}")
        info = obj.get("info", {})
        if not isinstance(info, dict):
            raise RecordFormatError("header field 'info' is not an object")
        return HeaderRecord(
            str(obj.get("created", "")),
            _optional(obj, "wall_time", float, 0.0),
            _time(obj, "monotonic") if "monotonic" in obj else 0.0,
            str(obj.get("generator", "")),
            info,
            version,
        )
    raise UnknownRecordType(f"unknown record type {kind!r}")


def decode_line(line: str | bytes) -> Record:
    """The record on one NDJSON line; raises :class:`RecordFormatError`."""
    try:
        obj = _DECODER.decode(line if isinstance(line, str) else line.decode("utf-8"))
    except (ValueError, UnicodeDecodeError) as exc:
        raise RecordFormatError(f"not valid JSON: {exc}") from None
    except RecursionError:
        raise RecordFormatError("not valid JSON: nested too deeply") from None
    try:
        return decode_record(obj)
    except RecursionError:
        raise RecordFormatError("nested too deeply") from None
