"""Payloads of the VRPN device messages: Tracker, Button, Analog, Dial, Text, ping and pong.

``encode_*`` functions build payloads; :func:`decode` turns a payload of a known type name
into a report object. Two kinds of bad payload are told apart, as the C++ remote treats them:

* :class:`StrictLengthError` for the types whose C++ handler checks the exact length (tracker
  reports 64/72/72 bytes, button change 8 bytes): the C++ client drops the connection;
* :class:`CodecError` for anything else malformed (a count beyond its limit, a payload too
  short for its count): the message is counted and ignored.
"""

from __future__ import annotations

import math
import struct
from typing import NamedTuple

# Type names.
TRACKER_POS_QUAT = "vrpn_Tracker Pos_Quat"
TRACKER_VELOCITY = "vrpn_Tracker Velocity"
TRACKER_ACCELERATION = "vrpn_Tracker Acceleration"
TRACKER_TYPES = (
    TRACKER_POS_QUAT,
    TRACKER_VELOCITY,
    TRACKER_ACCELERATION,
    "vrpn_Tracker To_Room",
    "vrpn_Tracker Unit_To_Sensor",
    "vrpn_Tracker Request_Tracker_To_Room",
    "vrpn_Tracker Request_Unit_To_Sensor",
    "vrpn_Tracker Workspace",
    "vrpn_Tracker Request_Tracker_Workspace",
    "vrpn_Tracker set_update_rate",
    "vrpn_Tracker Reset_Origin",
)
BUTTON_CHANGE = "vrpn_Button Change"
BUTTON_STATES = "vrpn_Button States"
BUTTON_TYPES = (BUTTON_CHANGE, BUTTON_STATES, "vrpn_Button Admin", "vrpn_Button Alert")
ANALOG_CHANNEL = "vrpn_Analog Channel"
DIAL_UPDATE = "vrpn_Dial update"
TEXT_MESSAGE = "vrpn_Base text_message"
PING = "vrpn_Base ping_message"
PONG = "vrpn_Base pong_message"
BASE_TYPES = (TEXT_MESSAGE, PING, PONG)

MAX_BUTTONS = 256
MAX_CHANNELS = 128
MAX_TEXT = 1024
#: Tracker sensors a gadgetctl client keeps: ids 0 to ``MAX_SENSORS - 1``. The C++ remote
#: grows its per-sensor arrays to whatever id a server sends; a report beyond this limit is
#: counted as stray and ignored, never allocated for.
MAX_SENSORS = 1024
#: Dials a gadgetctl client keeps (ids 0 to ``MAX_DIALS - 1``; C++ ``vrpn_DIAL_MAX``).
MAX_DIALS = 128

_POSE = struct.Struct(">ii3d4d")
_MOTION = struct.Struct(">ii3d4dd")
_II = struct.Struct(">ii")
_D = struct.Struct(">d")
_DIAL = struct.Struct(">di")

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]  # x, y, z, w


class CodecError(ValueError):
    """A malformed device payload: counted and ignored."""


class StrictLengthError(CodecError):
    """A payload of the wrong length for a type the C++ remote checks: the connection drops."""


class TrackerPose(NamedTuple):
    sensor: int
    position: Vec3
    quat: Quat


class TrackerVelocity(NamedTuple):
    sensor: int
    velocity: Vec3
    quat: Quat
    dt: float


class TrackerAcceleration(NamedTuple):
    sensor: int
    acceleration: Vec3
    quat: Quat
    dt: float


class ButtonChange(NamedTuple):
    button: int
    state: int


class ButtonStates(NamedTuple):
    states: tuple[int, ...]


class AnalogChannels(NamedTuple):
    channels: tuple[float, ...]


class DialUpdate(NamedTuple):
    dial: int
    delta: float


class TextReport(NamedTuple):
    severity: int
    level: int
    text: str


class Ping(NamedTuple):
    pass


class Pong(NamedTuple):
    pass


Report = (
    TrackerPose
    | TrackerVelocity
    | TrackerAcceleration
    | ButtonChange
    | ButtonStates
    | AnalogChannels
    | DialUpdate
    | TextReport
    | Ping
    | Pong
)


# -- encoders ---------------------------------------------------------------------------------


def encode_pose(sensor: int, position: Vec3, quat: Quat = (0.0, 0.0, 0.0, 1.0)) -> bytes:
    return _POSE.pack(sensor, sensor, *position, *quat)


def encode_velocity(
    sensor: int, velocity: Vec3, quat: Quat = (0.0, 0.0, 0.0, 1.0), dt: float = 1.0
) -> bytes:
    return _MOTION.pack(sensor, sensor, *velocity, *quat, dt)


def encode_acceleration(
    sensor: int, acceleration: Vec3, quat: Quat = (0.0, 0.0, 0.0, 1.0), dt: float = 1.0
) -> bytes:
    return _MOTION.pack(sensor, sensor, *acceleration, *quat, dt)


def encode_button_change(button: int, state: int) -> bytes:
    return _II.pack(button, 1 if state else 0)


def encode_button_states(states: tuple[int, ...] | list[int]) -> bytes:
    if len(states) > MAX_BUTTONS:
        raise ValueError(f"at most {MAX_BUTTONS} buttons")
    return struct.pack(f">i{len(states)}i", len(states), *(1 if s else 0 for s in states))


def encode_analog(channels: tuple[float, ...] | list[float]) -> bytes:
    if len(channels) > MAX_CHANNELS:
        raise ValueError(f"at most {MAX_CHANNELS} analog channels")
    return struct.pack(f">d{len(channels)}d", float(len(channels)), *channels)


def encode_dial(dial: int, delta: float) -> bytes:
    return _DIAL.pack(delta, dial)


def encode_text(text: str, severity: int = 0, level: int = 0) -> bytes:
    raw = text.encode("latin-1", "replace")[: MAX_TEXT - 1]
    return struct.pack(">II", severity, level) + raw + b"\0"


# -- decoders ---------------------------------------------------------------------------------


def _pose(payload: bytes) -> TrackerPose:
    if len(payload) != _POSE.size:
        raise StrictLengthError(f"tracker pose of {len(payload)} bytes (must be 64)")
    v = _POSE.unpack(payload)
    if v[0] < 0:
        raise StrictLengthError(f"negative tracker sensor {v[0]}")
    return TrackerPose(v[0], v[2:5], v[5:9])


def _motion(payload: bytes, cls: type) -> TrackerVelocity | TrackerAcceleration:
    if len(payload) != _MOTION.size:
        raise StrictLengthError(f"{cls.__name__} of {len(payload)} bytes (must be 72)")
    v = _MOTION.unpack(payload)
    if v[0] < 0:
        raise CodecError(f"negative tracker sensor {v[0]}")
    return cls(v[0], v[2:5], v[5:9], v[9])


def _button_change(payload: bytes) -> ButtonChange:
    if len(payload) != 8:
        raise StrictLengthError(f"button change of {len(payload)} bytes (must be 8)")
    button, state = _II.unpack(payload)
    if not 0 <= button < MAX_BUTTONS:
        raise CodecError(f"button {button} out of range")
    return ButtonChange(button, 1 if state else 0)


def _button_states(payload: bytes) -> ButtonStates:
    if len(payload) < 4:
        raise CodecError("button states without a count")
    (n,) = struct.unpack_from(">i", payload)
    if not 0 <= n <= MAX_BUTTONS:
        raise CodecError(f"button count {n} out of range (0 to {MAX_BUTTONS})")
    if len(payload) < 4 + 4 * n:
        raise CodecError(f"button states of {len(payload)} bytes for {n} buttons")
    return ButtonStates(tuple(1 if s else 0 for s in struct.unpack_from(f">{n}i", payload, 4)))


def _analog(payload: bytes) -> AnalogChannels:
    if len(payload) < 8:
        raise CodecError("analog report without a channel count")
    (count,) = _D.unpack_from(payload)
    if not (math.isfinite(count) and count == int(count) and 0 <= count <= MAX_CHANNELS):
        raise CodecError(f"analog channel count {count!r} out of range (0 to {MAX_CHANNELS})")
    n = int(count)
    if len(payload) < 8 + 8 * n:
        raise CodecError(f"analog report of {len(payload)} bytes for {n} channels")
    return AnalogChannels(struct.unpack_from(f">{n}d", payload, 8))


def _dial(payload: bytes) -> DialUpdate:
    if len(payload) < _DIAL.size:
        raise CodecError(f"dial update of {len(payload)} bytes (needs 12)")
    delta, dial = _DIAL.unpack_from(payload)
    return DialUpdate(dial, delta)


def _text(payload: bytes) -> TextReport:
    if len(payload) < 9:
        raise CodecError("text message too short")
    severity, level = struct.unpack_from(">II", payload)
    raw = payload[8 : 8 + MAX_TEXT].split(b"\0", 1)[0]
    return TextReport(severity, level, raw.decode("latin-1"))


_DECODERS = {
    TRACKER_POS_QUAT: _pose,
    TRACKER_VELOCITY: lambda p: _motion(p, TrackerVelocity),
    TRACKER_ACCELERATION: lambda p: _motion(p, TrackerAcceleration),
    BUTTON_CHANGE: _button_change,
    BUTTON_STATES: _button_states,
    ANALOG_CHANNEL: _analog,
    DIAL_UPDATE: _dial,
    TEXT_MESSAGE: _text,
    PING: lambda p: Ping(),
    PONG: lambda p: Pong(),
}

#: Payload lengths the C++ remote insists on (any other drops the connection).
STRICT_LENGTHS = {
    TRACKER_POS_QUAT: _POSE.size,
    TRACKER_VELOCITY: _MOTION.size,
    TRACKER_ACCELERATION: _MOTION.size,
    BUTTON_CHANGE: 8,
}

#: Type names :func:`decode` understands.
DECODED_TYPES = frozenset(_DECODERS)
#: Every type name a client describes to a server (the device families it reads).
CLIENT_TYPES = BASE_TYPES + TRACKER_TYPES + BUTTON_TYPES + (ANALOG_CHANNEL, DIAL_UPDATE)


def decode(type_name: str | None, payload: bytes) -> Report | None:
    """The report in ``payload``, None for a type without a decoder; raises :class:`CodecError`."""
    decoder = _DECODERS.get(type_name)  # type: ignore[arg-type]
    return None if decoder is None else decoder(payload)
