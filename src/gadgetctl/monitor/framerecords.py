"""The records a monitor session writes of its frames, made from what its
:class:`~gadgetctl.monitor.gathering.FrameGatherer` gathered: the elements of the header
(what replay needs to know of each), each frame's sample records as NDJSON text, and the
frame record (what each element delivered, with its newest values). A :class:`FrameRecords`
keeps only what it needs to write a proxy's value once: the timestamp it wrote last."""

from __future__ import annotations

from collections.abc import Iterator, Sequence

from gadgetctl.input.devicetypes import Analog
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.manager import InputManager
from gadgetctl.input.proxies import PositionProxy
from gadgetctl.input.status import ElementKind
from gadgetctl.monitor.encoding import encode_frame, json_value, plain_json, proxy_value
from gadgetctl.monitor.gathering import FrameGatherer
from gadgetctl.monitor.poses import MATRIX, pose_values
from gadgetctl.monitor.records import (
    FrameDevice,
    FrameRecord,
    SampleRecord,
    encode_samples,
)

DEVICE, PROXY, ALIAS = ElementKind.DEVICE.value, ElementKind.PROXY.value, ElementKind.ALIAS.value
#: Characters of sample records written at once when a frame's records go out in parts.
ENCODED_PART = 1 << 20


class FrameRecords:
    """The records of the frames ``gatherer`` gathers from ``manager``; ``stream_proxies``:
    proxies and aliases get sample records of their own (when the selection names them)."""

    def __init__(
        self, manager: InputManager, gatherer: FrameGatherer, *, stream_proxies: bool
    ) -> None:
        self.manager = manager
        self.gatherer = gatherer
        self.stream_proxies = stream_proxies
        self._proxy_stamps: dict[str, float | None] = {}

    def header_elements(
        self, selected: Sequence[str]
    ) -> tuple[list[str], dict[str, dict[str, object]]]:
        """What replay needs of the header: the watched devices, and every selected element
        and what it leads to with its type, kinds, units and links.
        Devices whose entries are alike share one entry (read-only, as the whole header is):
        10,000 devices of one configuration made 10,000 equal dicts, with their lists of
        kinds and dicts of units, about 6 MB held while the header was encoded."""
        manager = self.manager
        elements: dict[str, dict[str, object]] = {}
        devices = []
        alike: dict[tuple, dict[str, object]] = {}  # each entry, by what it holds
        for name in self.gatherer.watched(selected):
            device = manager.device(name)
            if device is not None:
                devices.append(name)
                track = self.gatherer.tracks.get(name)
                units = dict(track.units) if track is not None else {}
                store = device.store
                store.sync()
                made = store.channels_made  # a kind without a channel never had a sample
                for kind in store.kinds:
                    if kind in made and kind.value not in units:
                        latest = store.latest(kind)
                        if latest is not None:
                            units[kind.value] = len(latest.values)
                kinds = device.kinds()
                limits = (
                    (device.analog_min, device.analog_max) if isinstance(device, Analog) else None
                )
                # (the limits by their text: -0.0 equals 0.0 but is written otherwise)
                key = (device.element_type, kinds, tuple(units.items()), repr(limits))
                entry = alike.get(key)
                if entry is None:
                    entry = {
                        "element": DEVICE,
                        "type": device.element_type,
                        "kinds": [k.value for k in kinds],
                        "units": units,
                    }
                    if limits is not None:
                        entry["min"], entry["max"] = limits
                    alike[key] = entry
                elements[name] = entry
                continue
            proxy = manager.proxies.get(name)
            if proxy is not None:
                elements[name] = {
                    "element": PROXY,
                    "type": proxy.element_type,
                    "device": proxy.device_name,
                    "unit": proxy.unit,
                }
                continue
            target = manager.aliases.get(name)
            if target is not None:
                elements[name] = {"element": ALIAS, "type": "alias", "proxy": target}
        return devices, elements

    def samples(self, selected: Sequence[str], pose: str = MATRIX) -> tuple[str, int]:
        """This frame's sample records of the ``selected`` devices (and proxies and aliases,
        when :attr:`stream_proxies`), as NDJSON text and count; positions in ``pose``."""
        parts: list[str] = []
        count = 0
        for text, n in self.sample_parts(selected, pose, 0):
            parts.append(text)
            count += n
        return "".join(parts), count

    def sample_parts(
        self, selected: Sequence[str], pose: str, size: int | None = None
    ) -> Iterator[tuple[str, int]]:
        """:meth:`samples` in parts of at least ``size`` characters (None:
        :data:`ENCODED_PART`; 0: of each device and kind) and their counts, in order; none
        that is empty."""
        size = ENCODED_PART if size is None else size
        parts: list[str] = []
        length = count = 0
        for text, n in self._sample_pieces(selected, pose):
            if not text:
                continue
            parts.append(text)
            length += len(text)
            count += n
            if length >= size:
                yield "".join(parts) if len(parts) > 1 else text, count
                parts.clear()
                length = count = 0
        if parts:
            yield "".join(parts), count

    def _sample_pieces(self, selected: Sequence[str], pose: str) -> Iterator[tuple[str, int]]:
        """The sample records of :meth:`samples`, per device and kind or proxy."""
        manager = self.manager
        stream_proxies = self.stream_proxies
        for name in selected:
            track = self.gatherer.current_track(name)
            if track is not None and manager.device(name) is track.device:
                for kind, samples in track.frames.items():
                    yield encode_frame(name, kind, samples, track.device, pose)
                continue
            if stream_proxies:
                proxy = manager.proxy(name)
                if proxy is None or proxy.stupefied or proxy.timestamp is None:
                    continue
                if self._proxy_stamps.get(name) == proxy.timestamp:
                    continue
                self._proxy_stamps[name] = proxy.timestamp
                value, raw = proxy_value(proxy)
                value = (
                    pose_values(value, pose)[0]
                    if isinstance(proxy, PositionProxy)
                    else plain_json(value)
                )
                raw = value if raw is None else raw
                unit = proxy.unit if proxy.HAS_UNIT else 0
                record = SampleRecord(name, proxy.KIND.value, unit, proxy.timestamp, value, raw)
                yield encode_samples([record]), 1

    def frame(
        self, selected: Sequence[str], frame: int, timestamp: float, pose: str = MATRIX
    ) -> FrameRecord:
        """What every ``selected`` element delivered in manager frame ``frame`` (gathered at
        ``timestamp``), with its newest values (positions in ``pose``)."""
        manager = self.manager
        devices: dict[str, FrameDevice] = {}
        for name in selected:
            track = self.gatherer.current_track(name)
            if track is not None and manager.device(name) is track.device:
                values: dict[str, dict[int, object]] = {}
                store = track.device.store
                for kind in store.kinds:
                    latest = store.latest(kind)
                    if latest is None:
                        continue
                    if kind is DeviceKind.ANALOG and isinstance(track.device, Analog):
                        values[kind.value] = {
                            u: track.device.normalize(float(v)) for u, v in enumerate(latest.values)
                        }
                    elif kind is DeviceKind.POSITION:
                        values[kind.value] = dict(enumerate(pose_values(latest.values, pose)))
                    else:
                        values[kind.value] = {
                            u: json_value(kind, v) for u, v in enumerate(latest.values)
                        }
                devices[name] = FrameDevice(track.count, values)
                continue
            proxy = manager.proxy(name)
            if proxy is None:
                continue
            value, _ = proxy_value(proxy)
            fresh = (
                proxy.timestamp is not None
                and self._proxy_stamps.get("frame:" + name) != proxy.timestamp
            )
            self._proxy_stamps["frame:" + name] = proxy.timestamp
            unit = proxy.unit if proxy.HAS_UNIT else 0
            value = (
                pose_values(value, pose)[0]
                if isinstance(proxy, PositionProxy)
                else plain_json(value)
            )
            devices[name] = FrameDevice(1 if fresh else 0, {proxy.KIND.value: {unit: value}})
        return FrameRecord(frame, timestamp, devices)
