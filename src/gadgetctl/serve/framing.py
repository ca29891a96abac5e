"""Many VRPN device messages framed at once, with numpy, for `serve`'s high rates (a 1 kHz,
32-sensor tracker fanned out): the same bytes as :func:`gadgetctl.vrpn.wire.pack_message`
with the payloads of :mod:`gadgetctl.vrpn.codecs` (tests compare them byte for byte), but
one array operation per batch instead of one ``struct.pack`` per message. It lives here,
not in :mod:`gadgetctl.vrpn`, because that package stays free of numpy.

Times are Unix seconds (float64 arrays); sequence numbers are 0 (receivers ignore them).
"""

from __future__ import annotations

import numpy as np

from gadgetctl.vrpn.wire import HEADER_SIZE

_HEADER_FIELDS = [
    ("length", ">u4"),
    ("sec", ">i4"),
    ("usec", ">i4"),
    ("sender", ">i4"),
    ("type", ">i4"),
    ("sequence", ">u4"),
]
_POSE = np.dtype(
    [
        *_HEADER_FIELDS,
        ("sensor", ">i4"),
        ("filler", ">i4"),
        ("position", ">f8", (3,)),
        ("quat", ">f8", (4,)),
    ]
)
_CHANGE = np.dtype([*_HEADER_FIELDS, ("button", ">i4"), ("state", ">i4")])
#: One whole tracker pose message, header and payload (VRPN_drv reads received ones with it).
POSE_MESSAGE = _POSE
#: Bytes of one framed message of each batch (every message of a batch has the same size).
POSE_SIZE = _POSE.itemsize
CHANGE_SIZE = _CHANGE.itemsize


def analog_size(channels: int) -> int:
    return HEADER_SIZE + 8 * (channels + 1)


def split_times(times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unix seconds as (seconds, microseconds) int arrays, as :func:`.wire.split_time` does."""
    times = np.asarray(times, dtype=np.float64)
    sec = np.floor(times)
    usec = np.rint((times - sec) * 1e6)
    carry = usec >= 1_000_000
    sec = sec + carry
    usec = np.where(carry, usec - 1_000_000, usec)
    sec = ((sec.astype(np.int64) + 2**31) % 2**32) - 2**31
    return sec, usec.astype(np.int64)


def _header(
    records: np.ndarray,
    payload: int,
    sec: np.ndarray,
    usec: np.ndarray,
    sender: np.ndarray | int,
    type_id: int,
) -> None:
    records["length"] = HEADER_SIZE + payload
    records["sec"] = sec
    records["usec"] = usec
    records["sender"] = sender
    records["type"] = type_id
    records["sequence"] = 0


def pack_poses(
    senders: np.ndarray | int,
    type_id: int,
    times: np.ndarray,
    sensors: np.ndarray | int,
    positions: np.ndarray,
    quats: np.ndarray,
) -> bytes:
    """``vrpn_Tracker Pos_Quat`` messages, one per row: ``senders`` (m,) or one id, ``times``
    (m,), ``sensors`` (m,) or one number, ``positions`` (m, 3), ``quats`` (m, 4) as x, y, z,
    w."""
    records = np.empty(len(positions), dtype=_POSE)
    fill_poses(records, senders, type_id, times, sensors, positions, quats)
    return records.tobytes()


def fill_poses(
    records: np.ndarray,
    senders: np.ndarray | int,
    type_id: int,
    times: np.ndarray,
    sensors: np.ndarray | int,
    positions: np.ndarray,
    quats: np.ndarray,
) -> None:
    """:func:`pack_poses` into ``records`` (:data:`POSE_MESSAGE` records, one per row; a
    view of a larger buffer, say), not into a new bytes object."""
    sec, usec = split_times(times)
    _header(records, 64, sec, usec, senders, type_id)
    records["sensor"] = sensors
    records["filler"] = sensors
    records["position"] = np.asarray(positions, dtype=np.float64)
    records["quat"] = quats


def pack_analogs(sender: int, type_id: int, times: np.ndarray, values: np.ndarray) -> bytes:
    """``vrpn_Analog Channel`` messages, one per row of ``values`` (n, channels <= 128)."""
    values = np.asarray(values, dtype=np.float64)
    n, channels = values.shape
    if channels > 128:
        raise ValueError("at most 128 analog channels")
    dtype = np.dtype([*_HEADER_FIELDS, ("count", ">f8"), ("channels", ">f8", (channels,))])
    records = np.empty(n, dtype=dtype)
    sec, usec = split_times(times)
    _header(records, 8 * (channels + 1), sec, usec, sender, type_id)
    records["count"] = float(channels)
    records["channels"] = values
    return records.tobytes()


def pack_button_changes(
    sender: int, type_id: int, times: np.ndarray, buttons: np.ndarray, states: np.ndarray
) -> bytes:
    """``vrpn_Button Change`` messages, one per (time, button, state)."""
    times = np.asarray(times, dtype=np.float64)
    records = np.empty(len(times), dtype=_CHANGE)
    sec, usec = split_times(times)
    _header(records, 8, sec, usec, sender, type_id)
    records["button"] = buttons
    records["state"] = np.asarray(states) != 0
    return records.tobytes()
