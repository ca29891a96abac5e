"""Samples and proxy values as JSON-ready data and NDJSON sample records."""

from __future__ import annotations

from typing import Any

import numpy as np

from gadgetctl.input.device import Input
from gadgetctl.input.devicetypes import Analog
from gadgetctl.input.events import KeyEvent, MouseMoveEvent, ScrollEvent
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.proxies import (
    AnalogProxy,
    DigitalProxy,
    GestureProxy,
    GloveProxy,
    KeyboardMouseProxy,
    PositionProxy,
    Proxy,
)
from gadgetctl.input.samples import FrameSamples, Sample
from gadgetctl.monitor.numbertext import array_texts
from gadgetctl.monitor.poses import MATRIX, pose_values
from gadgetctl.monitor.records import encode_rows, sample_head


def plain_value(kind: DeviceKind, value: Any) -> Any:
    if kind is DeviceKind.POSITION or kind is DeviceKind.GLOVE:
        return np.asarray(value, dtype=np.float64)
    if kind is DeviceKind.STRING:
        return str(value)
    try:
        return int(value)
    except (TypeError, ValueError):
        return value


def event_value(event: Any) -> dict[str, object]:
    """A keyboard/mouse event as a JSON object for sample records."""
    if isinstance(event, KeyEvent):
        return {"event": "key", "key": event.key.name, "pressed": event.pressed}
    if isinstance(event, MouseMoveEvent):
        return {"event": "move", "dx": float(event.dx), "dy": float(event.dy)}
    if isinstance(event, ScrollEvent):
        return {"event": "scroll", "direction": str(event.direction)}
    return {"event": str(event)}


def plain_json(value: Any) -> Any:
    tolist = getattr(value, "tolist", None)
    return tolist() if tolist is not None else value


def json_value(kind: DeviceKind, value: Any) -> Any:
    if kind is DeviceKind.KEYBOARD_MOUSE:
        return event_value(value)
    tolist = getattr(value, "tolist", None)
    return tolist() if tolist is not None else value


def encode_frame(
    name: str, kind: DeviceKind, frame: FrameSamples, device: Input, pose: str = MATRIX
) -> tuple[str, int]:
    """Sample records (NDJSON text, count) of every sample of one kind in one frame;
    positions in the ``pose`` format (:mod:`gadgetctl.monitor.poses`)."""
    parts: list[str] = []
    count = 0
    label = kind.value
    if kind is DeviceKind.POSITION and pose != MATRIX:
        return _encode_poses(name, frame, pose)
    analog = kind is DeviceKind.ANALOG and isinstance(device, Analog)
    low, high = (device.analog_min, device.analog_max) if analog else (0.0, 1.0)
    for chunk in frame.chunks:
        if type(chunk) is Sample:
            stamps = [chunk.timestamp]
            row = [json_value(kind, v) for v in chunk.values]
            rows = [row]
            count += len(row)
            if analog:
                parts.append(
                    encode_rows(
                        name, label, stamps, [[device.normalize(float(v)) for v in row]], rows
                    )
                )
            else:
                parts.append(encode_rows(name, label, stamps, rows))
            continue
        values = np.asarray(chunk.values)
        if not len(values):
            continue
        count += values.shape[0] * (values.shape[1] if values.ndim > 1 else 1)
        if values.ndim == 1:
            values = values[:, None]
        if not analog:
            text = encode_array_rows(name, label, chunk.timestamps, values)
            if text is None:
                stamps = np.asarray(chunk.timestamps, dtype=np.float64).tolist()
                text = encode_rows(name, label, stamps, values.tolist())
            parts.append(text)
            continue
        if high <= low:
            normalised = np.zeros(values.shape)
        else:
            normalised = (np.clip(values.astype(np.float64), low, high) - low) / (high - low)
        text = encode_array_rows(name, label, chunk.timestamps, normalised, values)
        if text is None:
            stamps = np.asarray(chunk.timestamps, dtype=np.float64).tolist()
            text = encode_rows(name, label, stamps, normalised.tolist(), values.tolist())
        parts.append(text)
    return "".join(parts), count


def encode_array_rows(
    device: str,
    kind: str,
    timestamps: np.ndarray,
    values: np.ndarray,
    raw: np.ndarray | None = None,
) -> str | None:
    """:func:`~gadgetctl.monitor.records.encode_rows` of numpy arrays (``values`` and
    ``raw`` of shape (samples, units, ...)) with their numbers written by
    :func:`array_texts`: the same text, a few times faster for positions' matrices. A raw
    value is written where it is not the value (doubles that differ, or integers). None
    where :func:`array_texts` gives none (then call ``encode_rows``)."""
    if values.ndim < 2 or (raw is not None and raw.shape != values.shape):
        return None
    if len(values) == 1:  # (the usual chunk of a slow device: repr costs less than a call)
        stamp = float(timestamps[0])
        stamps = [repr(stamp)] if stamp - stamp == 0.0 and len(timestamps) == 1 else None
    else:
        stamps = array_texts(np.asarray(timestamps, dtype=np.float64))
    if stamps is None or len(stamps) != len(values):
        return None
    units = values.shape[1]
    if not units:
        return None
    cells = (len(values) * units, *values.shape[2:])
    texts = array_texts(values.reshape(cells))
    if texts is None:
        return None
    tails = ["}\n"] * len(texts)
    if raw is not None:
        raw_texts = array_texts(raw.reshape(cells))
        if raw_texts is None:
            return None
        # encode_rows leaves out a raw value equal to its value, both floats
        if raw.dtype == values.dtype == np.float64:
            differ = np.flatnonzero(raw.reshape(len(texts), -1) != values.reshape(len(texts), -1))
        else:
            differ = range(len(texts))
        for at in differ:
            tails[at] = ',"raw":' + raw_texts[at] + "}\n"
    prefix = sample_head(device, kind)
    if units == 1:
        head = prefix + '0,"timestamp":'
        return "".join(
            [
                head + stamp + ',"value":' + text + tail
                for stamp, text, tail in zip(stamps, texts, tails, strict=True)
            ]
        )
    heads = [prefix + repr(unit) + ',"timestamp":' for unit in range(units)]
    lines: list[str] = []
    append = lines.append
    at = 0
    for stamp in stamps:
        for head in heads:
            append(head + stamp + ',"value":' + texts[at] + tails[at])
            at += 1
    return "".join(lines)


def _encode_poses(name: str, frame: FrameSamples, pose: str) -> tuple[str, int]:
    parts: list[str] = []
    count = 0
    for chunk in frame.chunks:
        if type(chunk) is Sample:
            stamps, matrices = [chunk.timestamp], np.asarray(chunk.values, dtype=np.float64)[None]
        else:
            stamps = np.asarray(chunk.timestamps, dtype=np.float64).tolist()
            matrices = np.asarray(chunk.values, dtype=np.float64)
        if not len(stamps):
            continue
        matrices = matrices.reshape(len(stamps), -1, 4, 4)
        units = matrices.shape[1]
        flat = pose_values(matrices, pose)
        rows = [flat[i * units : (i + 1) * units] for i in range(len(stamps))]
        parts.append(encode_rows(name, "position", stamps, rows))
        count += len(stamps) * units
    return "".join(parts), count


def proxy_value(proxy: Proxy) -> tuple[Any, Any]:
    """(value, raw) of a proxy for records and views; raw is None where it equals the value."""
    device = proxy.device
    if isinstance(proxy, AnalogProxy):
        return float(proxy.data), (proxy.raw if proxy.raw is not None else None)
    if isinstance(proxy, DigitalProxy):
        raw = None
        if device is not None:
            latest = device.store.latest(DeviceKind.DIGITAL)
            if latest is not None and proxy.unit < len(latest.values):
                raw = int(latest.values[proxy.unit])
        return int(proxy.data), raw
    if isinstance(proxy, PositionProxy):
        return proxy.matrix, None
    if isinstance(proxy, GloveProxy):
        return proxy.data, None
    if isinstance(proxy, GestureProxy):
        return int(proxy.data), None
    if isinstance(proxy, KeyboardMouseProxy):
        return sorted(k.name for k in proxy.data), None
    data = proxy.data
    return (str(data) if isinstance(data, str) else int(data)), None
