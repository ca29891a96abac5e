"""The replay driver: plays a recording back through the input manager.

`gadgetctl replay` puts a :class:`ReplayDevice` (element type ``replay_device``, registered
and defined only while replaying) in place of every recorded device, so proxies, aliases,
proxy filters and the monitor see the recorded samples as they saw the live device:

* without a configuration, :func:`replay_configuration` synthesises one from the
  recording's header: a replay device per recorded device (its kinds, analog min and max),
  and the recorded proxies (device and unit) and aliases;
* with a configuration, the elements whose names match recorded devices (after the
  ``--map old=new`` renaming) are replaced by replay devices with the element's own min
  and max; everything else stays as it is. Device-level position filters are not applied
  again: recorded positions already went through them.

A :class:`ReplayFeeder` thread releases the records on the recording's own schedule
(:class:`~gadgetctl.monitor.replay.ReplaySchedule`: speed, loop, renaming) and adds each
sampling instant to its device, stamped on the input manager's clock.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from gadgetctl.errors import GadgetctlError
from gadgetctl.input.clock import now
from gadgetctl.input.device import Input, SamplingMode
from gadgetctl.input.devicetypes import (
    GLOVE_SHAPE,
    Analog,
    Command,
    Digital,
    Gesture,
    Glove,
    Hat,
    Position,
    String,
)
from gadgetctl.input.filters import FilterChain
from gadgetctl.input.kinds import PROXY_TYPES, DeviceKind
from gadgetctl.input.samples import SampleStore
from gadgetctl.jccl.access import ElementAccess
from gadgetctl.jccl.configuration import ConfigElement, Configuration, PropertyValue
from gadgetctl.jccl.definitions import Location
from gadgetctl.monitor.poses import matrix_from_pose
from gadgetctl.monitor.records import REPLAY_UNITS, HeaderRecord, MarkerRecord, SampleRecord
from gadgetctl.monitor.replay import ReplaySchedule

REPLAY_ELEMENT_TYPE = "replay_device"
DEFINITION_FILE = Path(__file__).with_name("replay_device.jdef")
#: Kinds a replay device can play back (keyboard and mouse events are not replayed).
REPLAYABLE = (
    DeviceKind.ANALOG,
    DeviceKind.DIGITAL,
    DeviceKind.POSITION,
    DeviceKind.GLOVE,
    DeviceKind.GESTURE,
    DeviceKind.COMMAND,
    DeviceKind.STRING,
    DeviceKind.HAT,
)
_REPLAYABLE_NAMES = {k.value for k in REPLAYABLE}


class ReplayError(GadgetctlError):
    """A recording or mapping replay cannot use."""


class _InstanceKinds:
    """``kinds()`` answers for the instance once it is configured (the recorded device's
    kinds), and for the class before (every replayable kind)."""

    def __get__(self, obj: Any, owner: type) -> Callable[[], tuple[DeviceKind, ...]]:
        kinds = None if obj is None else obj.__dict__.get("_kinds")
        if kinds is not None:
            return lambda: kinds
        return lambda: Input.__dict__["kinds"].__func__(owner)


class ReplayDevice(Analog, Digital, Position, Glove, Gesture, Command, String, Hat):
    """A recorded device played back: samples come from a :class:`ReplayFeeder`."""

    ELEMENT_TYPE = REPLAY_ELEMENT_TYPE
    SAMPLING = SamplingMode.FRAME
    kinds = _InstanceKinds()  # type: ignore[assignment]

    def config(self, access: ElementAccess) -> None:
        super().config(access)
        recorded = access.string("recorded_type")
        if recorded:
            self.element_type = recorded
        names = [k for k in access.strings("kind") if k]
        kinds = tuple(DeviceKind(k) for k in names if k in _REPLAYABLE_NAMES) or REPLAYABLE
        self._kinds = kinds
        self.store = SampleStore(kinds, self.store.cap)
        self.position_filters = FilterChain()  # recorded positions went through them already

    def feed(self, kind: DeviceKind, timestamp: float, values: Any) -> None:
        """Add one recorded sampling instant (thread-safe)."""
        self.store.add(kind, timestamp, values)


# --------------------------------------------------------------------------- setting up


def install(manager: Any) -> None:
    """Make ``replay_device`` known to ``manager``'s definitions and device registry."""
    from gadgetctl.jccl.defparser import read_definition
    from gadgetctl.jccl.xmlload import load_file

    if REPLAY_ELEMENT_TYPE not in manager.repo:
        definition = read_definition(load_file(DEFINITION_FILE), columns=False)
        if definition is None:
            raise ReplayError(f"{DEFINITION_FILE}: cannot read the replay_device definition")
        manager.repo.add(definition)
    if REPLAY_ELEMENT_TYPE not in manager.registry:
        manager.registry.register_device(ReplayDevice)


@dataclass
class RecordedDevice:
    """A device of the recording, under its replay name."""

    name: str
    recorded_name: str
    type: str = ""
    kinds: list[str] = field(default_factory=list)
    units: dict[str, int] = field(default_factory=dict)
    minimum: float | None = None
    maximum: float | None = None
    #: kind -> unit count the header claims beyond the units its samples hold (not replayed)
    claimed_beyond: dict[str, int] = field(default_factory=dict)


@dataclass
class ReplayPlan:
    """What a replay needs to know before it starts."""

    devices: dict[str, RecordedDevice]
    elements: list[ConfigElement]
    notes: list[str]
    configuration: Configuration


def _mapped(mapping: Mapping[str, str], name: str) -> str:
    return mapping.get(name, name)


def recorded_devices(
    header: HeaderRecord, schedule: ReplaySchedule, mapping: Mapping[str, str]
) -> dict[str, RecordedDevice]:
    """The recorded devices (renamed), from the header's element list and the samples."""
    info = header.info if isinstance(header.info, Mapping) else {}
    elements = info.get("elements")
    elements = elements if isinstance(elements, Mapping) else {}
    seen_kinds: dict[str, set[str]] = {}
    seen_units: dict[str, dict[str, int]] = {}
    for record in schedule.records:
        if not isinstance(record, SampleRecord):
            continue
        kinds = seen_kinds.setdefault(record.device, set())
        kinds.add(record.kind)
        units = seen_units.setdefault(record.device, {})
        if record.unit + 1 > units.get(record.kind, 0):
            units[record.kind] = record.unit + 1
    devices: dict[str, RecordedDevice] = {}
    for original, kinds in seen_kinds.items():
        described = elements.get(original)
        if isinstance(described, Mapping) and described.get("element") not in (None, "device"):
            continue  # samples of a proxy or alias: they come out of the replayed devices
        if elements and not isinstance(described, Mapping):
            continue  # the header lists every recorded element; this one is not a device
        if not kinds & _REPLAYABLE_NAMES:
            continue
        described = described if isinstance(described, Mapping) else {}
        name = _mapped(mapping, original)
        declared = [k for k in described.get("kinds", []) if k in _REPLAYABLE_NAMES]
        units = dict(seen_units.get(original, {}))
        claimed = described.get("units")
        beyond: dict[str, int] = {}
        for kind, count in (claimed if isinstance(claimed, Mapping) else {}).items():
            if not isinstance(count, int) or isinstance(count, bool):
                continue
            # A monitor's recording holds a sample of every unit its header counts: a larger
            # count would only pad every replayed instant (1,024 glove units claimed by a
            # 17 KB file wrote 33 MB), so it is said, not replayed.
            if 0 < units.get(kind, 0) < count:
                beyond[str(kind)] = count
        device = RecordedDevice(
            name,
            original,
            str(described.get("type", "")),
            sorted(
                set(declared) | (kinds & _REPLAYABLE_NAMES), key=[k.value for k in REPLAYABLE].index
            ),
            units,
            claimed_beyond=beyond,
        )
        if isinstance(described.get("min"), (int, float)) and isinstance(
            described.get("max"), (int, float)
        ):
            device.minimum, device.maximum = float(described["min"]), float(described["max"])
        devices[name] = device
    return devices


def check_mapping(
    mapping: Mapping[str, str],
    recorded: Iterable[str],
    configuration: Configuration | None,
    path: Path,
) -> None:
    """Raise :class:`ReplayError` when ``--map OLD=NEW`` names a device the recording does
    not hold, or (with a configuration) an element the configuration does not have, before
    anything is configured or opened: a mistyped NEW would leave the configuration's own
    (perhaps real) device in place."""
    from gadgetctl.suggest import with_suggestion

    recorded = list(recorded)
    problems = [
        with_suggestion(f"{old!r} is not a device of the recording {path}", old, recorded)
        for old in mapping
        if old not in recorded
    ]
    if configuration is not None:
        names = [e.name for e in configuration.elements]
        problems += [
            with_suggestion(f"{new!r} is not an element of the configuration", new, names)
            for new in mapping.values()
            if new not in names
        ]
    if problems:
        raise ReplayError(f"--map: {'; '.join(problems)}")


def _value(text: object, where: Location) -> PropertyValue:
    return PropertyValue(str(text), where)


def _element(
    type_name: str,
    name: str,
    where: Location,
    properties: Mapping[str, Sequence[object]],
    version: str = "1",
) -> ConfigElement:
    return ConfigElement(
        type_name,
        name,
        version,
        where,
        {prop: [_value(v, where) for v in values] for prop, values in properties.items()},
    )


def replay_element(
    device: RecordedDevice, where: Location, original: ConfigElement | None = None
) -> ConfigElement:
    """The ``replay_device`` element standing in for ``device`` (min and max from the
    element it replaces, else from the recording)."""
    props: dict[str, list[object]] = {"kind": list(device.kinds)}
    recorded_type = original.type if original is not None else device.type
    if recorded_type:
        props["recorded_type"] = [recorded_type]
    low = high = None
    if original is not None and original.texts("min") and original.texts("max"):
        low, high = original.texts("min")[0], original.texts("max")[0]
    elif device.minimum is not None and device.maximum is not None:
        low, high = repr(device.minimum), repr(device.maximum)
    if low is not None and high is not None:
        props["min"], props["max"] = [low], [high]
    return _element(REPLAY_ELEMENT_TYPE, device.name, where, props)


def plan_replay(
    header: HeaderRecord,
    schedule: ReplaySchedule,
    path: Path,
    configuration: Configuration | None,
    mapping: Mapping[str, str],
) -> ReplayPlan:
    """The elements to configure: the given configuration with its recorded devices
    replaced, or one synthesised from the header."""
    devices = recorded_devices(header, schedule, mapping)
    if not devices:
        raise ReplayError(f"{path}: the recording holds no samples of any device to replay")
    where = Location(f"<replay of {path}>")
    notes = [
        f"the header claims {count} {kind} units of {device.recorded_name!r}; "
        f"the {device.units.get(kind, 0)} its samples hold are replayed"
        for device in devices.values()
        for kind, count in device.claimed_beyond.items()
    ]
    elements: list[ConfigElement] = []
    if configuration is not None:
        present = set()
        for element in configuration.elements:
            device = devices.get(element.name)
            if device is not None and element.parent is None:
                elements.append(replay_element(device, element.location, element))
                present.add(element.name)
            else:
                elements.append(element)
        for name, device in devices.items():
            if name not in present:
                hint = (
                    f" (map it with --map {device.recorded_name}=NAME)"
                    if name == device.recorded_name
                    else ""
                )
                notes.append(
                    f"recorded device {name!r} is not in the configuration; it is replayed on its own{hint}"
                )
                elements.append(replay_element(device, where))
        result = Configuration(
            files=list(configuration.files),
            loaded=elements,
            diagnostics=list(configuration.diagnostics),
        )
        return ReplayPlan(devices, elements, notes, result)
    info = header.info if isinstance(header.info, Mapping) else {}
    described = info.get("elements")
    described = described if isinstance(described, Mapping) else {}
    elements = [replay_element(device, where) for device in devices.values()]
    names = set(devices)
    proxies = {}
    for original, entry in described.items():
        if not isinstance(entry, Mapping) or entry.get("element") != "proxy":
            continue
        proxy_type = str(entry.get("type", ""))
        if proxy_type not in PROXY_TYPES:
            continue
        target = _mapped(mapping, str(entry.get("device", "")))
        name = _mapped(mapping, original)
        props: dict[str, list[object]] = {"device": [target]}
        if proxy_type not in ("gesture_proxy", "keyboard_mouse_proxy"):
            props["unit"] = [int(entry.get("unit", 0) or 0)]
        proxies[name] = _element(proxy_type, name, where, props)
        if target not in names:
            notes.append(
                f"proxy {name!r} points at {target!r}, which the recording has no samples of"
            )
    elements.extend(proxies.values())
    for original, entry in described.items():
        if isinstance(entry, Mapping) and entry.get("element") == "alias":
            target = _mapped(mapping, str(entry.get("proxy", "")))
            elements.append(
                _element("alias", _mapped(mapping, original), where, {"proxy": [target]})
            )
    return ReplayPlan(devices, elements, notes, Configuration(loaded=elements))


# --------------------------------------------------------------------------- feeding


def _neutral(kind: str) -> Any:
    if kind == "position":
        return np.eye(4)
    if kind == "glove":
        return np.zeros(GLOVE_SHAPE)
    if kind == "string":
        return ""
    if kind == "analog":
        return 0.0
    return 0


def _datum(kind: str, record: SampleRecord) -> Any:
    """The device datum of a sample record, as the device type stores it."""
    raw = record.raw
    try:
        if kind == "analog":
            return float(raw)
        if kind == "position":
            return matrix_from_pose(record.value)  # a matrix, or written with --pose
        if kind == "glove":
            return np.asarray(record.value, dtype=np.float64).reshape(GLOVE_SHAPE)
        if kind == "string":
            return str(raw)
        return int(raw)
    except (TypeError, ValueError):
        return _neutral(kind)


class ReplayFeeder:
    """Releases a recording's samples into the replay devices, in a daemon thread."""

    def __init__(
        self,
        schedule: ReplaySchedule,
        lookup: Callable[[str], Input | None],
        units: Mapping[str, Mapping[str, int]] | None = None,
    ) -> None:
        self.schedule = schedule
        self._lookup = lookup
        self._units = {name: dict(u) for name, u in (units or {}).items()}
        self._last: dict[tuple[str, str], list[Any]] = {}
        self._markers: list[MarkerRecord] = []
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._done = threading.Event()
        self._thread: threading.Thread | None = None
        self.fed = 0  # sampling instants added
        self.error: str | None = None

    @property
    def done(self) -> bool:
        return self._done.is_set()

    def start(self) -> None:
        self.schedule.sleep = self._sleep  # stop() interrupts the waits
        self._thread = threading.Thread(target=self._run, name="gadgetctl-replay", daemon=True)
        self._thread.start()

    def _sleep(self, seconds: float) -> None:
        self._stop.wait(seconds)

    def stop(self, timeout: float = 1.0) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout)

    def drain_markers(self) -> list[MarkerRecord]:
        with self._lock:
            markers, self._markers = self._markers, []
        return markers

    def _run(self) -> None:
        try:
            for batch in self.schedule.batches():
                if self._stop.is_set():
                    break
                self.feed(batch.records)
        except Exception as err:  # a bad record must not kill the monitor silently
            self.error = f"{type(err).__name__}: {err}"
        finally:
            self._done.set()

    def feed(self, records: Iterable[SampleRecord | MarkerRecord]) -> None:
        """Group records into sampling instants (device, kind, timestamp) and add them."""
        groups: dict[tuple[str, str, float], dict[int, SampleRecord]] = {}
        for record in records:
            if isinstance(record, MarkerRecord):
                with self._lock:
                    self._markers.append(record)
                continue
            if record.kind not in _REPLAYABLE_NAMES:
                continue
            groups.setdefault((record.device, record.kind, record.timestamp), {})[record.unit] = (
                record
            )
        devices: dict[str, Input | None] = {}
        for (name, kind, timestamp), units in groups.items():
            device = (
                devices.get(name)
                if name in devices
                else devices.setdefault(name, self._lookup(name))
            )
            if not isinstance(device, ReplayDevice) or DeviceKind(kind) not in device.kinds():
                continue
            last = self._last.get((name, kind))
            count = max(
                max(units) + 1, self._units.get(name, {}).get(kind, 0), len(last) if last else 0
            )
            if last is None or len(last) < count:
                last = (last or []) + [_neutral(kind) for _ in range(count - len(last or []))]
            values = list(last)
            for unit, record in units.items():
                values[unit] = _datum(kind, record)
            self._last[(name, kind)] = values
            if kind in ("position", "glove"):
                data: Any = np.stack(values)
            else:
                data = tuple(values)
            device.feed(DeviceKind(kind), timestamp, data)
            self.fed += 1


def make_schedule(
    records: Iterable[object], *, speed: float, loop: bool, mapping: Mapping[str, str] | None
) -> ReplaySchedule:
    """A schedule stamping released samples on the input manager's clock."""
    return ReplaySchedule(records, speed, loop, mapping=mapping, clock=now, max_units=REPLAY_UNITS)
