"""A.R.T. DTrack protocol: decode the ASCII UDP output of a DTrack tracking system.

Knows nothing of gadgetctl. One UDP datagram holds one frame: lines ended by CR LF, each
starting with a tag (``fr``, ``ts``, ``6dcal``, ``6d``, ``6di``, ``6df``, ``6df2``, ``6dmt``,
``6dmt2``, ``glcal``, ``gl``, ``3d``) followed by header numbers and bracketed blocks
``[...]``. Locations are in millimetres; rotations are 3x3 matrices sent column by column,
so ``R[i][j] = b[i + 3*j]``. Decoded poses are 4x4 ``float64`` matrices in metres.

Differences from Gadgeteer's C++ driver, on purpose:

* ``6df2``: the C++ code compared the *button* count with 8 where it meant the valuator count,
  so Flysticks with more than 8 buttons were rejected. Here any number of buttons and
  valuators is accepted as long as the block holds them.
* A malformed line is counted and skipped instead of abandoning the rest of the datagram, and a
  datagram that is not a frame at all (binary garbage, no known line) is counted and skipped.
* Integers are read as decimal. ``strtol(..., 0)`` would take a leading 0 as octal; DTrack never
  sends one, so this only matters for damaged input, which is now rejected.
* Every count, id and number has a limit (:class:`DTrackLimits`): a line asking for more
  objects, buttons or joystick values than that, an id beyond the object cap, or an integer
  too long to be one DTrack sends is a malformed line, counted and skipped. The units therefore
  never grow past the cap, whatever a peer sends (upstream resized its arrays to any id).
* Silence longer than ``peer_timeout`` is reported with :class:`DTrackDisconnected`, so a caller can
  reconnect (and re-send the start commands) instead of waiting for ever.
* Every datagram waiting is decoded (:meth:`DTrackStandalone.sample_all`), not just the newest,
  and gaps in the frame counter are counted (``missed_frames``).

Speed: :func:`parse_frames` decodes many datagrams at once. Body (``6d``) and Flystick
(``6df2``) lines in their usual layout are checked token by token, and their numbers are
then converted all together with numpy; anything unusual goes through the general parser,
line by line, with the same result. :class:`DTrackUnits` merges many frames into unit
samples with a few array operations.
"""

from __future__ import annotations

import functools
import math
import operator
import select
import socket
import time
import warnings
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import overload

import numpy as np

from gadgetctl.transport.udp import DatagramLedger, LedgeredReceiver, bind_udp

MM_TO_M = 0.001
DEFAULT_RECEIVE_PORT = 5000
DEFAULT_COMMAND_PORT = 5001

CMD_CAMERAS_AND_TRACKING_ON = "dtrack 10 3"
CMD_CAMERAS_ON = "dtrack 10 1"
CMD_CAMERAS_OFF = "dtrack 10 0"
CMD_START_SENDING = "dtrack 31"
CMD_STOP_SENDING = "dtrack 32"


def cmd_send_frames(n: int) -> str:
    """The command asking DTrack to send ``n`` frames."""
    return f"dtrack 33 {n}"


class DTrackFormatError(ValueError):
    """A line does not follow the DTrack output format."""


@dataclass(frozen=True)
class DTrackLimits:
    """What one datagram may ask for; a line beyond a limit is malformed (counted, skipped).

    ``objects``: ids of each kind (bodies, Flysticks, tools, markers, gloves) run from 0 to
    ``objects - 1`` (markers from 1 to ``objects``), and no count is larger (``6dcal`` counts
    bodies, old Flysticks and old tools together, so it may reach three times that). DTrack
    systems track a few dozen objects; raise the cap for more. ``buttons`` and
    ``valuators`` per Flystick or tool are well above DTrack's own 16 and 8 (gadgetctl keeps
    the buttons beyond the eighth, which upstream rejected).
    """

    objects: int = 128
    buttons: int = 128
    valuators: int = 32
    fingers: int = 5


DEFAULT_LIMITS = DTrackLimits()
#: Frame counters are unsigned 32-bit numbers.
MAX_FRAME_COUNTER = 2**32 - 1
#: No integer DTrack sends has more digits than this (a 32-bit button field has 10).
_MAX_DIGITS = 12


class DTrackDisconnected(ConnectionError):
    """No datagram arrived for longer than ``peer_timeout``: the tracker is gone or stopped."""


# -- decoded data ---------------------------------------------------------------------------------


def pose_matrix(location_mm: Sequence[float], rotation: Sequence[float]) -> np.ndarray:
    """A 4x4 pose in metres from a location in mm and 9 rotation values sent column by column."""
    x, y, z = (v * MM_TO_M for v in location_mm)
    b = rotation
    return np.array(
        (b[0], b[3], b[6], x, b[1], b[4], b[7], y, b[2], b[5], b[8], z, 0.0, 0.0, 0.0, 1.0),
        dtype=np.float64,
    ).reshape(4, 4)


@dataclass(frozen=True, eq=False)
class Body:
    """A standard (``6d``) or inertial (``6di``) 6DOF body. Quality < 0 means not tracked."""

    id: int
    quality: float
    location_mm: tuple[float, float, float]
    matrix: np.ndarray
    inertial: bool = False
    drift_error: float | None = None  # 6di only

    @property
    def tracked(self) -> bool:
        return self.quality >= 0


class BodySet(Sequence[Body]):
    """The bodies of one frame as arrays, a sequence of :class:`Body` made when first read.

    ``ids`` (n,), ``quality`` (n,), ``locations_mm`` (n, 3), ``matrices`` (n, 4, 4) in metres,
    ``inertial`` (n,) and ``drift_errors`` (n,, NaN where there is none). Receivers that only
    need the arrays never pay for the objects.
    """

    __slots__ = (
        "_drift_errors", "_inertial", "_objects", "ids", "locations_mm", "matrices", "quality",
    )  # fmt: skip

    def __init__(
        self,
        ids: np.ndarray,
        quality: np.ndarray,
        locations_mm: np.ndarray,
        matrices: np.ndarray,
        inertial: np.ndarray | None = None,
        drift_errors: np.ndarray | None = None,
    ) -> None:
        self.ids = ids
        self.quality = quality
        self.locations_mm = locations_mm
        self.matrices = matrices
        self._inertial = inertial
        self._drift_errors = drift_errors
        self._objects: tuple[Body, ...] | None = None

    @property
    def inertial(self) -> np.ndarray:
        if self._inertial is None:
            self._inertial = np.zeros(len(self.ids), dtype=bool)
        return self._inertial

    @property
    def drift_errors(self) -> np.ndarray:
        if self._drift_errors is None:
            self._drift_errors = np.full(len(self.ids), np.nan)
        return self._drift_errors

    @classmethod
    def of(cls, bodies: Sequence[Body]) -> BodySet:
        """The arrays of some :class:`Body` objects."""
        if isinstance(bodies, BodySet):
            return bodies
        n = len(bodies)
        result = cls(
            np.array([b.id for b in bodies], dtype=np.int64),
            np.array([b.quality for b in bodies], dtype=np.float64),
            np.array([b.location_mm for b in bodies], dtype=np.float64).reshape(n, 3),
            np.array([b.matrix for b in bodies], dtype=np.float64).reshape(n, 4, 4),
            np.array([b.inertial for b in bodies], dtype=bool),
            np.array([np.nan if b.drift_error is None else b.drift_error for b in bodies]),
        )
        result._objects = tuple(bodies)
        return result

    @classmethod
    def join(cls, parts: Sequence[BodySet]) -> BodySet:
        """The bodies of several sets, in order."""
        if len(parts) == 1:
            return parts[0]
        if not parts:
            return EMPTY_BODIES
        names = ("ids", "quality", "locations_mm", "matrices", "inertial", "drift_errors")
        return cls(*(np.concatenate([getattr(p, name) for p in parts]) for name in names))

    def _made(self) -> tuple[Body, ...]:
        if self._objects is None:
            drift = self.drift_errors.tolist()
            self._objects = tuple(
                Body(ident, quality, tuple(loc), matrix, inertial, None if math.isnan(d) else d)
                for ident, quality, loc, matrix, inertial, d in zip(
                    self.ids.tolist(),
                    self.quality.tolist(),
                    self.locations_mm.tolist(),
                    self.matrices,
                    self.inertial.tolist(),
                    drift,
                    strict=True,
                )
            )
        return self._objects

    def __len__(self) -> int:
        return len(self.ids)

    @overload
    def __getitem__(self, index: int) -> Body: ...
    @overload
    def __getitem__(self, index: slice) -> tuple[Body, ...]: ...
    def __getitem__(self, index: int | slice) -> Body | tuple[Body, ...]:
        return self._made()[index]

    def __iter__(self) -> Iterator[Body]:
        return iter(self._made())

    def __repr__(self) -> str:
        return f"BodySet({list(self._made())!r})"


EMPTY_BODIES = BodySet(
    np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros((0, 3)), np.zeros((0, 4, 4))
)


@dataclass(frozen=True, eq=False)
class Flystick:
    """A Flystick (``6df`` or ``6df2``): pose, buttons as 0/1 and joystick values in [-1, 1]."""

    id: int
    quality: float
    location_mm: tuple[float, float, float]
    matrix: np.ndarray
    buttons: tuple[int, ...]
    joystick: tuple[float, ...]

    @property
    def tracked(self) -> bool:
        return self.quality >= 0


@dataclass(frozen=True, eq=False)
class MeasurementTool:
    """A measurement tool (``6dmt`` or ``6dmt2``)."""

    id: int
    quality: float
    location_mm: tuple[float, float, float]
    matrix: np.ndarray
    buttons: tuple[int, ...]
    tip_radius_mm: float | None = None
    covariance: tuple[float, ...] | None = None

    @property
    def tracked(self) -> bool:
        return self.quality >= 0


@dataclass(frozen=True, eq=False)
class Marker:
    """A single ``3d`` marker (ids start at 1)."""

    id: int
    quality: float
    location_mm: tuple[float, float, float]

    @property
    def position(self) -> np.ndarray:
        """The location in metres."""
        return np.asarray(self.location_mm, dtype=np.float64) * MM_TO_M


@dataclass(frozen=True, eq=False)
class Finger:
    """One finger of a glove, in the hand's coordinate system (thumb first)."""

    location_mm: tuple[float, float, float]
    matrix: np.ndarray
    tip_radius_mm: float
    phalanx_lengths_mm: tuple[float, float, float]  # outer, middle, inner
    phalanx_angles_deg: tuple[float, float]  # outer-middle, middle-inner


@dataclass(frozen=True, eq=False)
class Glove:
    """A Fingertracking hand (``gl``)."""

    id: int
    quality: float
    right: bool
    location_mm: tuple[float, float, float]
    matrix: np.ndarray
    fingers: tuple[Finger, ...]

    @property
    def tracked(self) -> bool:
        return self.quality >= 0


@dataclass(frozen=True, eq=False)
class DTrackFrame:
    """Everything one datagram said. Lists hold the objects in the order they were sent;
    ``bodies`` also offers them as arrays (see :class:`BodySet`)."""

    frame: int | None = None
    timestamp: float | None = None
    bodies: BodySet = EMPTY_BODIES
    flysticks: tuple[Flystick, ...] = ()
    meatools: tuple[MeasurementTool, ...] = ()
    markers: tuple[Marker, ...] = ()
    gloves: tuple[Glove, ...] = ()
    calibrated_bodies: int | None = None  # 6dcal: all calibrated 6DOF objects
    calibrated_flysticks: int | None = None  # from 6df2
    calibrated_gloves: int | None = None  # glcal
    old_flysticks: int = 0  # how many Flysticks came in the old 6df format
    old_meatools: int = 0  # how many tools came in the old 6dmt format
    bad_lines: int = 0


# -- parsing ------------------------------------------------------------------------------------


def _int(token: str) -> int:
    if len(token) > _MAX_DIGITS + 1:  # also keeps int() away from its digit limit
        raise DTrackFormatError(f"integer too long: {token[:20]!r}...")
    try:
        return int(token, 10)
    except ValueError:
        raise DTrackFormatError(f"not an integer: {token[:40]!r}") from None


def _float(token: str) -> float:
    try:
        value = float(token)
    except ValueError:
        raise DTrackFormatError(f"not a number: {token[:40]!r}") from None
    if not math.isfinite(value):
        raise DTrackFormatError(f"not a finite number: {token[:40]!r}")
    return value


def _floats(tokens: Sequence[str]) -> list[float]:
    """Finite numbers, all converted at once (the common case) or the first bad one named."""
    try:
        values = list(map(float, tokens))
    except ValueError:
        values = [_float(t) for t in tokens]  # raises, naming the token
    if not all(map(math.isfinite, values)):
        values = [_float(t) for t in tokens]
    return values


def _blocks(tail: str) -> list[list[str]]:
    """The values of each ``[...]`` block of ``tail``, which must hold blocks and blanks only."""
    parts = tail.split("]")
    if parts[-1] and not parts[-1].isspace():
        raise DTrackFormatError("unbalanced or stray text between blocks")
    blocks = []
    for part in parts[:-1]:
        before, bracket, body = part.partition("[")
        if not bracket or "[" in body or (before and not before.isspace()):
            raise DTrackFormatError("unbalanced or stray text between blocks")
        blocks.append(body.split())
    return blocks


def _count(token: str, what: str, limit: int | None = None) -> int:
    """A count (or id) from 0 to ``limit``."""
    n = _int(token)
    if n < 0:
        raise DTrackFormatError(f"negative {what}: {n}")
    if limit is not None and n > limit:
        raise DTrackFormatError(f"{what} {n} is over the limit of {limit}")
    return n


def _small(token: str, limit: int) -> int | None:
    """``token`` as an integer from 0 to ``limit`` if it is plain ASCII digits, else None."""
    if len(token) > _MAX_DIGITS or not token.isascii() or not token.isdigit():
        return None
    n = int(token)
    return n if n <= limit else None


_BIT_VALUES = bytes.maketrans(b"01", b"\x00\x01")


def _bits(fields: Sequence[int], n: int) -> tuple[int, ...]:
    """Buttons 0..n-1 from 32-bit fields: bit j of field k is button 32k + j."""
    text = "".join(format(f & 0xFFFFFFFF, "032b")[::-1] for f in fields)[:n]
    return tuple(text.encode("ascii").translate(_BIT_VALUES)) + (0,) * (n - len(text))


class _Line:
    """One line split into its tag, header tokens and bracketed blocks."""

    def __init__(self, words: list[str], tail: str) -> None:
        """``words``: the text before the first ``[``, split; ``tail``: the rest."""
        if not words:
            raise DTrackFormatError("empty line")
        self.tag = words[0]
        self.header = words[1:]
        self.blocks = _blocks(tail)
        self._next = 0

    def head(self, i: int) -> str:
        if i >= len(self.header):
            raise DTrackFormatError(f"{self.tag}: header value {i} missing")
        return self.header[i]

    def block(self, n: int) -> list[str]:
        """The first ``n`` values of the next block (more are allowed and ignored)."""
        if self._next >= len(self.blocks):
            raise DTrackFormatError(f"{self.tag}: block {self._next} missing")
        values = self.blocks[self._next]
        self._next += 1
        if len(values) < n:
            raise DTrackFormatError(f"{self.tag}: block has {len(values)} values, {n} needed")
        return values[:n]

    def floats(self, n: int) -> list[float]:
        return _floats(self.block(n))

    def location(self) -> tuple[float, float, float]:
        x, y, z = self.floats(3)
        return (x, y, z)


class _FrameBuilder:
    """Collects the decoded lines of one datagram."""

    def __init__(self, limits: DTrackLimits = DEFAULT_LIMITS) -> None:
        self.limits = limits
        self.values: dict[str, object] = {}
        # decoded objects, or (row, ...) records whose numbers a _Batch converts first
        self.bodies: list[BodySet | tuple[int, np.ndarray]] = []
        self.flysticks: list[Flystick | tuple[int, int, tuple[int, ...], tuple[float, ...]]] = []
        self.meatools: list[MeasurementTool] = []
        self.markers: list[Marker] = []
        self.gloves: list[Glove] = []

    def build(self, bad_lines: int, batch: _Batch | None = None) -> DTrackFrame:
        """The frame; ``batch`` must have converted the numbers of any deferred record."""
        bodies = [b if isinstance(b, BodySet) else batch.bodies(*b) for b in self.bodies]  # type: ignore[union-attr]
        sticks = [f if isinstance(f, Flystick) else batch.flystick(*f) for f in self.flysticks]  # type: ignore[union-attr]
        return DTrackFrame(
            bodies=BodySet.join(bodies),
            flysticks=tuple(sticks),
            meatools=tuple(self.meatools),
            markers=tuple(self.markers),
            gloves=tuple(self.gloves),
            bad_lines=bad_lines,
            **self.values,  # type: ignore[arg-type]
        )

    # Each method parses one tag into local lists first, so a bad line adds nothing.

    def fr(self, line: _Line) -> None:
        self.values["frame"] = _count(line.head(0), "frame counter", MAX_FRAME_COUNTER)

    def ts(self, line: _Line) -> None:
        self.values["timestamp"] = _float(line.head(0))

    def cal6d(self, line: _Line) -> None:
        limit = 3 * self.limits.objects
        self.values["calibrated_bodies"] = _count(line.head(0), "body count", limit)

    def glcal(self, line: _Line) -> None:
        limit = self.limits.objects
        self.values["calibrated_gloves"] = _count(line.head(0), "glove count", limit)

    def _n(self, line: _Line, what: str, index: int = 0) -> int:
        """The object count in header value ``index``."""
        return _count(line.head(index), what, self.limits.objects)

    def _id(self, token: str) -> int:
        return _count(token, "id", self.limits.objects - 1)

    def body6d(self, line: _Line) -> None:
        found = []
        for _ in range(self._n(line, "body count")):
            ident, quality = line.block(2)
            loc = line.location()
            found.append(
                Body(self._id(ident), _float(quality), loc, pose_matrix(loc, line.floats(9)))
            )
        self.bodies.append(BodySet.of(found))

    def body6di(self, line: _Line) -> None:
        found = []
        for _ in range(self._n(line, "body count")):
            ident, state, error = line.block(3)
            loc = line.location()
            found.append(
                Body(
                    self._id(ident),
                    float(_int(state) - 1),
                    loc,
                    pose_matrix(loc, line.floats(9)),
                    inertial=True,
                    drift_error=_float(error),
                )
            )
        self.bodies.append(BodySet.of(found))

    def flystick6df(self, line: _Line) -> None:
        found = []
        for k in range(self._n(line, "Flystick count")):
            ident, quality, bt = line.block(3)
            if _int(ident) != k:
                raise DTrackFormatError(f"6df: Flystick id {ident} at index {k}")
            mask = _count(bt, "button mask")
            loc = line.location()
            # The four hat bits also give a joystick: 0x20 left, 0x80 right, 0x10 down, 0x40 up.
            x = -1.0 if mask & 0x20 else 1.0 if mask & 0x80 else 0.0
            y = -1.0 if mask & 0x10 else 1.0 if mask & 0x40 else 0.0
            found.append(
                Flystick(
                    k,
                    _float(quality),
                    loc,
                    pose_matrix(loc, line.floats(9)),
                    _bits([mask], 8),
                    (x, y),
                )
            )
        self.flysticks.extend(found)
        self.values["old_flysticks"] = len(found)

    def flystick6df2(self, line: _Line) -> None:
        calibrated = self._n(line, "calibrated Flystick count")
        found = []
        for k in range(self._n(line, "Flystick count", 1)):
            ident, quality, nbt, nvt = line.block(4)
            if _int(ident) != k:
                raise DTrackFormatError(f"6df2: Flystick id {ident} at index {k}")
            # Fixed: upstream rejected nbt > 8 (it meant nvt); up to the limits is fine.
            n_buttons = _count(nbt, "button count", self.limits.buttons)
            n_valuators = _count(nvt, "valuator count", self.limits.valuators)
            loc = line.location()
            matrix = pose_matrix(loc, line.floats(9))
            n_fields = -(-n_buttons // 32)
            values = line.block(n_fields + n_valuators)
            fields = [_int(v) & 0xFFFFFFFF for v in values[:n_fields]]
            joystick = tuple(_float(v) for v in values[n_fields:])
            found.append(
                Flystick(k, _float(quality), loc, matrix, _bits(fields, n_buttons), joystick)
            )
        self.flysticks.extend(found)
        self.values["calibrated_flysticks"] = calibrated

    def meatool6dmt(self, line: _Line) -> None:
        found = []
        for _ in range(self._n(line, "tool count")):
            ident, quality, bt = line.block(3)
            loc = line.location()
            found.append(
                MeasurementTool(
                    self._id(ident),
                    _float(quality),
                    loc,
                    pose_matrix(loc, line.floats(9)),
                    _bits([_count(bt, "button mask")], 4),
                )
            )
        self.meatools.extend(found)
        self.values["old_meatools"] = len(found)

    def meatool6dmt2(self, line: _Line) -> None:
        found = []
        # The first number counts the calibrated tools, the second the tools that follow (ART's
        # technical appendix B.2.7). Fixed: the first was read as the count of tool blocks.
        self._n(line, "calibrated tool count")
        for _ in range(self._n(line, "tool count", 1)):
            ident, quality, nbt, radius = line.block(4)
            n_buttons = _count(nbt, "button count", self.limits.buttons)
            loc = line.location()
            matrix = pose_matrix(loc, line.floats(9))
            fields = [_int(v) & 0xFFFFFFFF for v in line.block(-(-n_buttons // 32))]
            covariance = tuple(line.floats(6))
            found.append(
                MeasurementTool(
                    self._id(ident),
                    _float(quality),
                    loc,
                    matrix,
                    _bits(fields, n_buttons),
                    tip_radius_mm=_float(radius),
                    covariance=covariance,
                )
            )
        self.meatools.extend(found)

    def marker3d(self, line: _Line) -> None:
        found = []
        for _ in range(self._n(line, "marker count")):
            ident, quality = line.block(2)
            marker = _count(ident, "marker id", self.limits.objects)
            found.append(Marker(marker, _float(quality), line.location()))
        self.markers.extend(found)

    def glove(self, line: _Line) -> None:
        found = []
        for _ in range(self._n(line, "glove count")):
            ident, quality, lr, nf = line.block(4)
            n_fingers = _count(nf, "finger count", self.limits.fingers)
            if lr not in ("0", "1"):
                raise DTrackFormatError(f"gl: hand {lr!r} is neither 0 (left) nor 1 (right)")
            loc = line.location()
            matrix = pose_matrix(loc, line.floats(9))
            fingers = []
            for _f in range(n_fingers):
                floc = line.location()
                fmatrix = pose_matrix(floc, line.floats(9))
                tip, l_out, a_om, l_mid, a_mi, l_in = line.floats(6)
                fingers.append(Finger(floc, fmatrix, tip, (l_out, l_mid, l_in), (a_om, a_mi)))
            found.append(
                Glove(self._id(ident), _float(quality), lr == "1", loc, matrix, tuple(fingers))
            )
        self.gloves.extend(found)


# Tokens (brackets included) of one 6d record in its usual layouts -> values in its middle block:
# [id qu][sx sy sz eta theta phi][b0..b8] as DTrack sends it, or [id qu][sx sy sz][b0..b8].
_BODY_LAYOUTS = {23: 6, 20: 3}
_BODY_VALUES = 13  # picked per body: quality, then the 3x4 top of its pose row by row


def _getter(indices: list[int]) -> Callable[[list[str]], tuple[str, ...]]:
    """Picks ``indices`` out of a list, always as a tuple."""
    if len(indices) == 1:
        index = indices[0]
        return lambda items: (items[index],)
    return operator.itemgetter(*indices)


class _BodyLayout:
    """Where the brackets, ids and wanted values of ``n`` records of one layout sit among the
    tokens of a ``6d`` line, as getters that pick them all in one call."""

    def __init__(self, n: int, stride: int) -> None:
        rot = 7 + _BODY_LAYOUTS[stride]  # the first rotation value
        marks = {0: "[", 3: "]", 4: "[", rot - 2: "]", rot - 1: "[", stride - 1: "]"}
        self.brackets = _getter([k * stride + p for k in range(n) for p in marks])
        self.expected = tuple(marks.values()) * n
        self.ids = _getter([k * stride + 1 for k in range(n)])
        # body by body: quality, then the pose row by row; b[i + 3j] = R[i][j], so row i
        # holds b[i], b[i+3], b[i+6] and the location's i-th value
        order = [2] + [p for i in range(3) for p in (rot + i, rot + i + 3, rot + i + 6, 5 + i)]
        self.values = _getter([k * stride + p for k in range(n) for p in order])


@functools.lru_cache(maxsize=64)
def _body_layout(n: int, stride: int) -> _BodyLayout:
    return _BodyLayout(n, stride)


_POWERS = 10.0 ** np.arange(23)  # exact doubles
_DECIMAL_CHARS = b"0123456789.- "
_FEW_TOKENS = 200  # below this, numpy's fixed costs outweigh what it saves


def _numbers(tokens: Sequence[str]) -> np.ndarray | None:
    """The tokens as finite floats, exactly as ``float()`` reads them; None if one is not a
    finite number.

    Tokens written the way DTrack writes numbers (digits with at most one point, maybe a
    leading minus, up to 15 significant digits and 22 decimals) are read by numpy as integers and
    divided by a power of ten: exact for them (both are exact doubles, so the quotient is
    correctly rounded) and, for many tokens, several times faster than ``float()``. Others go
    through ``float()``.
    """
    text = " ".join(tokens).encode("ascii", "replace")
    if len(tokens) >= _FEW_TOKENS and not text.translate(None, _DECIMAL_CHARS):
        values = _decimals(text, tokens)
        if values is not None:
            return values
    try:
        values = np.array(list(map(float, tokens)))
    except ValueError:
        return None
    return values if np.isfinite(values).all() else None


def _decimals(text: bytes, tokens: Sequence[str]) -> np.ndarray | None:
    """:func:`_numbers` for ``text``, the tokens joined by single blanks, holding digits,
    points, minus signs and blanks only; None when a token is not of the simple form."""
    count = len(tokens)
    chars = np.frombuffer(text, dtype=np.uint8)
    blanks = np.flatnonzero(chars == 32)
    points = np.flatnonzero(chars == 46)
    if len(blanks) != count - 1:
        return None
    owner = np.searchsorted(blanks, points)  # the token each point is in
    if len(owner) > 1 and not (np.diff(owner) > 0).all():
        return None  # two points in a token
    ended = text + b" "
    if (
        text.count(b"-") != text.count(b" -") + text.startswith(b"-")
        or b"- " in ended
        or b"-. " in ended
    ):
        return None  # a minus sign that does not start a token, or a token without digits
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DeprecationWarning)
            mantissas = np.fromstring(text.replace(b".", b""), dtype=np.int64, sep=" ")
    except ValueError:
        return None
    if len(mantissas) != count or not (np.abs(mantissas) < 2**53).all():
        return None  # too many digits (numpy saturates on overflow, which this catches too)
    decimals = np.zeros(count, dtype=np.intp)
    decimals[owner] = np.append(blanks, len(text))[owner] - points - 1
    if decimals.max() >= len(_POWERS):
        return None
    values = mantissas / _POWERS[decimals]
    for index in np.flatnonzero(mantissas == 0).tolist():
        if tokens[index].startswith("-"):
            values[index] = -0.0
    return values


class _Batch:
    """The numbers of the usual ``6d`` and ``6df2`` lines of several datagrams, converted
    together: 13 per object (quality, then its 4x4 pose row by row without the last row)."""

    def __init__(self) -> None:
        self.tokens: list[str] = []
        self.rows = 0
        self.quality = self.locations = self.matrices = np.zeros(0)

    def add(self, tokens: Sequence[str]) -> int:
        """Queue the tokens of some objects; returns the row of the first."""
        row = self.rows
        self.tokens += tokens
        self.rows += len(tokens) // _BODY_VALUES
        return row

    def convert(self) -> bool:
        """Convert everything queued; False if a token was not a number."""
        if not self.rows:
            return True
        values = _numbers(self.tokens)
        if values is None:
            return False
        rows = values.reshape(self.rows, _BODY_VALUES)
        self.quality = rows[:, 0]
        self.locations = rows[:, 4::4].copy()  # millimetres
        self.matrices = np.empty((self.rows, 4, 4))
        flat = self.matrices.reshape(self.rows, 16)
        flat[:, :12] = rows[:, 1:]
        flat[:, 3:12:4] *= MM_TO_M
        flat[:, 12:] = (0.0, 0.0, 0.0, 1.0)
        return True

    def bodies(self, row: int, ids: np.ndarray) -> BodySet:
        end = row + len(ids)
        return BodySet(ids, self.quality[row:end], self.locations[row:end], self.matrices[row:end])

    def flystick(
        self, row: int, ident: int, buttons: tuple[int, ...], joystick: tuple[float, ...]
    ) -> Flystick:
        location = tuple(self.locations[row].tolist())
        return Flystick(
            ident,
            float(self.quality[row]),
            location,
            self.matrices[row],
            buttons,
            joystick,  # type: ignore[arg-type]
        )


def _fast_bodies(
    count: str, tail: str, batch: _Batch, limits: DTrackLimits
) -> tuple[int, np.ndarray] | None:
    """The bodies of a ``6d`` line in a usual layout, their numbers queued in ``batch``.

    ``tail`` is the line from its first ``[``. Returns ``None`` for anything unusual (another
    layout, a bad id, a count or id over the limits); the general parser then decides, so
    results never differ.
    """
    if not (n := _small(count, limits.objects)):
        return None
    if tail.count("[") != 3 * n or tail.count("]") != 3 * n:
        return None
    tokens = tail.replace("[", " [ ").replace("]", " ] ").split()
    stride, rest = divmod(len(tokens), n)
    if rest or stride not in _BODY_LAYOUTS:
        return None
    layout = _body_layout(n, stride)
    ids = layout.ids(tokens)
    if layout.brackets(tokens) != layout.expected:
        return None
    last = limits.objects - 1
    numbers = [_small(i, last) for i in ids]
    if None in numbers:
        return None
    return batch.add(layout.values(tokens)), np.array(numbers, dtype=np.int64)


# Where a 6df2 record's tokens are, brackets included:
# [ id qu nbt nvt ] [ sx sy sz ] [ b0 .. b8 ] [ fields.. valuators.. ]
_STICK_MARKS = {0: "[", 5: "]", 6: "[", 10: "]", 11: "[", 21: "]", 22: "["}
_STICK_BRACKETS = operator.itemgetter(*_STICK_MARKS)
_STICK_EXPECTED = tuple(_STICK_MARKS.values())
_STICK_POSE = operator.itemgetter(
    2, *(p for i in range(3) for p in (12 + i, 15 + i, 18 + i, 7 + i))
)


def _fast_flysticks(
    words: list[str], tail: str, batch: _Batch, limits: DTrackLimits
) -> list[tuple] | None:
    """The Flysticks of a ``6df2`` line whose blocks hold exactly what they must, their
    pose numbers queued in ``batch``; ``None`` leaves the line to the general parser."""
    if len(words) != 3 or _small(words[1], limits.objects) is None:
        return None
    if (count := _small(words[2], limits.objects)) is None:
        return None
    tokens = tail.replace("[", " [ ").replace("]", " ] ").split()
    found: list[tuple] = []
    at = 0
    for k in range(count):
        head = tokens[at : at + 23]
        if len(head) < 23 or _STICK_BRACKETS(head) != _STICK_EXPECTED:
            return None
        n_buttons = _small(head[3], limits.buttons)
        n_valuators = _small(head[4], limits.valuators)
        if head[1] != str(k) or n_buttons is None or n_valuators is None:
            return None
        n_fields = -(-n_buttons // 32)
        end = at + 23 + n_fields + n_valuators
        if len(tokens) <= end or tokens[end] != "]":
            return None
        try:
            fields = [_int(v) & 0xFFFFFFFF for v in tokens[at + 23 : at + 23 + n_fields]]
            joystick = tuple(_floats(tokens[at + 23 + n_fields : end]))
        except (ValueError, DTrackFormatError):
            return None
        found.append((batch.add(_STICK_POSE(head)), k, _bits(fields, n_buttons), joystick))
        at = end + 1
    return found if at == len(tokens) else None


_HANDLERS: dict[str, Callable[[_FrameBuilder, _Line], None]] = {
    "fr": _FrameBuilder.fr,
    "ts": _FrameBuilder.ts,
    "6dcal": _FrameBuilder.cal6d,
    "6d": _FrameBuilder.body6d,
    "6di": _FrameBuilder.body6di,
    "6df": _FrameBuilder.flystick6df,
    "6df2": _FrameBuilder.flystick6df2,
    "6dmt": _FrameBuilder.meatool6dmt,
    "6dmt2": _FrameBuilder.meatool6dmt2,
    "glcal": _FrameBuilder.glcal,
    "gl": _FrameBuilder.glove,
    "3d": _FrameBuilder.marker3d,
}


# Lines holding one number and no block, read without splitting into blocks.
_SCALARS: dict[str, tuple[str, Callable[[str, DTrackLimits], object]]] = {
    "fr": ("frame", lambda t, _: _count(t, "frame counter", MAX_FRAME_COUNTER)),
    "ts": ("timestamp", lambda t, _: _float(t)),
    "6dcal": ("calibrated_bodies", lambda t, lim: _count(t, "body count", 3 * lim.objects)),
    "glcal": ("calibrated_gloves", lambda t, lim: _count(t, "glove count", lim.objects)),
}


def parse_frame(
    data: bytes | str,
    truncated: bool = False,
    *,
    fast: bool = True,
    limits: DTrackLimits = DEFAULT_LIMITS,
) -> DTrackFrame | None:
    """Decode one datagram; ``None`` when it holds no valid DTrack line at all.

    Lines with an unknown tag are ignored. Malformed lines are skipped and counted in the
    frame's ``bad_lines``. With ``truncated`` (the datagram did not fit the receive buffer) the
    last line is taken as cut off and counted as bad. ``fast=False`` decodes every line with
    the general parser (the result is the same; for comparisons). A line over ``limits`` is
    malformed.
    """
    return parse_frames([data], [truncated], fast=fast, limits=limits)[0]


def parse_frames(
    datagrams: Sequence[bytes | str],
    truncated: Sequence[bool] | None = None,
    *,
    fast: bool = True,
    limits: DTrackLimits = DEFAULT_LIMITS,
) -> list[DTrackFrame | None]:
    """Decode several datagrams, as :func:`parse_frame` each. The numbers of their usual body
    and Flystick lines are converted all at once, which makes a busy tracker cheap to follow."""
    flags = truncated if truncated is not None else [False] * len(datagrams)
    batch = _Batch() if fast else None
    pairs = list(zip(datagrams, flags, strict=True))
    scanned = [_scan(data, cut, batch, limits) for data, cut in pairs]
    if batch is not None and not batch.convert():
        # a bad number somewhere: decode datagram by datagram, so only its own lines suffer
        return [_decode_alone(data, cut, limits) for data, cut in pairs]
    return [None if s is None else s[0].build(s[1], batch) for s in scanned]


def _decode_alone(data: bytes | str, truncated: bool, limits: DTrackLimits) -> DTrackFrame | None:
    """One datagram with its own batch, or through the general parser if that fails."""
    batch: _Batch | None = _Batch()
    scanned = _scan(data, truncated, batch, limits)
    if batch is not None and not batch.convert():
        batch = None
        scanned = _scan(data, truncated, None, limits)
    return None if scanned is None else scanned[0].build(scanned[1], batch)


def _scan(
    data: bytes | str, truncated: bool, batch: _Batch | None, limits: DTrackLimits
) -> tuple[_FrameBuilder, int] | None:
    """Parse the lines of one datagram: (builder, bad lines), or None if nothing was valid.
    With a ``batch``, usual body and Flystick lines leave their numbers to it; without,
    every line goes through the general parser."""
    if isinstance(data, bytes):
        try:
            text = data.decode("ascii")
        except UnicodeDecodeError:
            return None
    else:
        text = data
    lines = text.rstrip("\0").splitlines()
    if truncated and lines:
        lines.pop()
    builder = _FrameBuilder(limits)
    good, bad = 0, int(truncated)
    for raw in lines:
        head, bracket, tail = raw.partition("[")
        words = head.split()
        if not bracket and not words:
            continue  # a blank line
        if batch is not None and _fast_line(builder, words, bracket + tail, batch):
            good += 1
            continue
        try:
            line = _Line(words, bracket + tail)
        except DTrackFormatError:
            bad += 1
            continue
        handler = _HANDLERS.get(line.tag)
        if handler is None:
            continue
        try:
            handler(builder, line)
        except DTrackFormatError:
            bad += 1
            continue
        good += 1
    return (builder, bad) if good else None


def _fast_line(builder: _FrameBuilder, words: list[str], tail: str, batch: _Batch) -> bool:
    """The common lines, the short way; False leaves the line to the general parser."""
    tag = words[0] if words else ""
    if len(words) == 2 and not tail and tag in _SCALARS:
        name, read = _SCALARS[tag]
        try:
            builder.values[name] = read(words[1], builder.limits)
        except DTrackFormatError:
            return False  # the general parser counts it as bad
        return True
    if tag == "6d" and len(words) == 2 and tail:
        bodies = _fast_bodies(words[1], tail, batch, builder.limits)
        if bodies is not None:
            builder.bodies.append(bodies)
            return True
    elif tag == "6df2" and tail:
        sticks = _fast_flysticks(words, tail, batch, builder.limits)
        if sticks is not None:
            builder.flysticks.extend(sticks)
            builder.values["calibrated_flysticks"] = int(words[1])
            return True
    return False


# -- the receiver -----------------------------------------------------------------------------


class DTrackStandalone(LedgeredReceiver):
    """Receives DTrack datagrams on a UDP port and optionally starts and stops the tracker.

    ``receive_port`` is a port number (bound on ``bind_address``; 0 lets the OS choose, see
    :attr:`port`) or an already-bound UDP socket, which is switched to non-blocking mode and is
    not closed by :meth:`close`. With a non-empty ``server_name`` and a non-zero
    ``command_port``, :meth:`open` sends "cameras and tracking on", waits ``start_delay`` and
    sends "start sending"; :meth:`close` sends "stop sending" and "cameras off".

    :meth:`sample` waits at most ``receive_timeout`` for data; after ``peer_timeout`` seconds
    without any datagram it raises :class:`DTrackDisconnected` (``None`` never does).
    ``receive_buffer`` asks the kernel for a larger socket buffer (bytes), so a burst at a high
    frame rate waits in it instead of being dropped. The counters (``datagrams``,
    ``bad_datagrams``, ``bad_lines``, ``truncated_datagrams``, ``missed_frames`` and
    ``kernel_dropped``: datagrams the kernel dropped because the socket's receive buffer was
    full, where the OS tells) survive :meth:`close` and :meth:`open`.
    """

    def __init__(
        self,
        receive_port: int | socket.socket = DEFAULT_RECEIVE_PORT,
        *,
        bind_address: str = "",
        server_name: str = "",
        command_port: int = DEFAULT_COMMAND_PORT,
        receive_timeout: float = 1.0,
        peer_timeout: float | None = 5.0,
        start_delay: float = 1.0,
        buffer_size: int = 20000,
        receive_buffer: int | None = None,
        limits: DTrackLimits = DEFAULT_LIMITS,
    ) -> None:
        self.receive_port = receive_port
        self.bind_address = bind_address
        self.server_name = server_name
        self.command_port = command_port
        self.receive_timeout = receive_timeout
        self.peer_timeout = peer_timeout
        self.start_delay = start_delay
        self.buffer_size = buffer_size
        self.receive_buffer = receive_buffer
        self.limits = limits
        self.bad_lines = 0  # malformed lines skipped inside otherwise valid frames
        self.truncated_datagrams = 0  # larger than buffer_size
        self.missed_frames = 0  # gaps in the frame counter (datagrams lost on the way)
        self.last_frame: DTrackFrame | None = None
        #: every datagram read, counted decoded or bad, and the kernel's drops
        self.ledger = DatagramLedger()
        self._sock: socket.socket | None = None
        self._owns_socket = False
        self._last_rx = 0.0
        self._last_counter: int | None = None

    # -- life cycle -------------------------------------------------------------------------

    @property
    def is_open(self) -> bool:
        return self._sock is not None

    @property
    def port(self) -> int:
        """The UDP port the receiver is bound to."""
        if self._sock is None:
            raise RuntimeError("the receiver is not open")
        return self._sock.getsockname()[1]

    @property
    def remote_control(self) -> bool:
        """Whether start/stop commands are sent to the DTrack server."""
        return bool(self.server_name) and self.command_port != 0

    def open(self) -> None:
        """Bind the socket and, with remote control, start the tracker."""
        if self._sock is not None:
            return
        if isinstance(self.receive_port, socket.socket):
            self._sock, self._owns_socket = self.receive_port, False
        else:
            sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            try:
                if self.receive_buffer:
                    sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, self.receive_buffer)
                bind_udp(sock, self.bind_address, self.receive_port)
            except BaseException:
                sock.close()
                raise
            self._sock, self._owns_socket = sock, True
        self._sock.setblocking(False)
        self.ledger.attach(self._sock)
        self._last_rx = time.monotonic()
        self._last_counter = None
        if self.remote_control:
            try:
                self.send_command(CMD_CAMERAS_AND_TRACKING_ON)
                time.sleep(self.start_delay)
                self.send_command(CMD_START_SENDING)
            except BaseException:
                self.close()  # an unknown host must not leave the socket bound
                raise

    def close(self) -> None:
        """Stop the tracker (with remote control) and release the socket."""
        sock = self._sock
        if sock is None:
            return
        try:
            if self.remote_control:
                self.send_command(CMD_STOP_SENDING)
                self.send_command(CMD_CAMERAS_OFF)
        except OSError:
            pass  # the server may be gone; closing must still work
        finally:
            self.ledger.detach()
            self._sock = None
            if self._owns_socket:
                sock.close()

    def __enter__(self) -> DTrackStandalone:
        self.open()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def send_command(self, command: str) -> None:
        """Send one remote command (plain ASCII, no terminating NUL) from the receive socket."""
        if self._sock is None:
            raise RuntimeError("the receiver is not open")
        self._sock.sendto(command.encode("ascii"), (self.server_name, self.command_port))

    # -- reading ----------------------------------------------------------------------------

    def sample(self) -> DTrackFrame | None:
        """The newest valid frame among the datagrams waiting, or ``None`` if none came."""
        frames = self.sample_all()
        return frames[-1] if frames else None

    def sample_all(self, limit: int | None = None) -> list[DTrackFrame]:
        """Every valid frame among the datagrams waiting, oldest first.

        Waits up to ``receive_timeout`` for the first datagram, then drains the socket, or reads
        at most ``limit`` datagrams (so a caller slower than the tracker still gets to use them).
        """
        if self._sock is None:
            raise RuntimeError("the receiver is not open")
        frames: list[DTrackFrame] = []
        if self.receive_timeout > 0:
            select.select([self._sock], [], [], self.receive_timeout)
        datagrams: list[bytes] = []
        truncated: list[bool] = []
        size = self.buffer_size
        receive = self.ledger.receive
        while limit is None or len(datagrams) < limit:
            try:
                data = receive(size + 1)  # one byte more: a longer datagram did not fit
            except (BlockingIOError, InterruptedError):
                break
            except ConnectionRefusedError:
                continue  # an ICMP error from a command sent earlier; not data
            cut = len(data) > size
            datagrams.append(data[:size] if cut else data)
            truncated.append(cut)
        got_any = bool(datagrams)
        self.ledger.drops.refresh()
        self.truncated_datagrams += sum(truncated)
        for frame in parse_frames(datagrams, truncated, limits=self.limits):
            if frame is None:
                self.ledger.bad("no valid DTrack line")
                continue
            self.ledger.decoded()
            self.bad_lines += frame.bad_lines
            self._count_missed(frame.frame)
            frames.append(frame)
        now = time.monotonic()
        if got_any:
            self._last_rx = now
        elif self.peer_timeout is not None and now - self._last_rx > self.peer_timeout:
            raise DTrackDisconnected(f"no DTrack data for {now - self._last_rx:.3f} s")
        if frames:
            self.last_frame = frames[-1]
        return frames

    @property
    def kernel_drop_source(self) -> str | None:
        """Where ``kernel_dropped`` comes from: "ancillary", "proc" or None (unknown)."""
        return self.ledger.drops.method

    def _count_missed(self, counter: int | None) -> None:
        """Frame counters skipped since the previous frame (a restarted counter is not a gap)."""
        if counter is None:
            return
        last = self._last_counter
        if last is not None and counter > last + 1:
            self.missed_frames += counter - last - 1
        self._last_counter = counter


# -- Gadgeteer's unit numbering ------------------------------------------------------------------


class _Poses:
    """Matrices of one kind of 6DOF object (identity until first tracked), grown as ids appear."""

    def __init__(self) -> None:
        self.matrices = np.zeros((0, 4, 4))
        self.quality = np.zeros(0)

    def __len__(self) -> int:
        return len(self.matrices)

    def grow(self, n: int) -> None:
        have = len(self.matrices)
        if n > have:
            self.matrices = np.concatenate((self.matrices, np.tile(np.eye(4), (n - have, 1, 1))))
            self.quality = np.concatenate((self.quality, np.full(n - have, -1.0)))


class _Sent:
    """The objects of one kind in several frames: per frame a count, then all their ids,
    qualities and matrices in order."""

    def __init__(
        self, counts: list[int], ids: np.ndarray, quality: np.ndarray, matrices: np.ndarray
    ) -> None:
        self.counts, self.ids, self.quality, self.matrices = counts, ids, quality, matrices

    @classmethod
    def of_objects(cls, per_frame: list[Sequence[Flystick | MeasurementTool]]) -> _Sent:
        objects = [o for frame in per_frame for o in frame]
        return cls(
            [len(frame) for frame in per_frame],
            np.array([o.id for o in objects], dtype=np.int64),
            np.array([o.quality for o in objects], dtype=np.float64),
            np.array([o.matrix for o in objects], dtype=np.float64).reshape(-1, 4, 4),
        )

    @classmethod
    def of_bodies(cls, per_frame: list[BodySet]) -> _Sent:
        parts = [b for b in per_frame if len(b)]
        if len(parts) == 1:
            ids, quality, matrices = parts[0].ids, parts[0].quality, parts[0].matrices
        elif parts:
            ids = np.concatenate([b.ids for b in parts])
            quality = np.concatenate([b.quality for b in parts])
            matrices = np.concatenate([b.matrices for b in parts])
        else:
            ids, quality, matrices = np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros((0, 4, 4))
        return cls([len(b) for b in per_frame], ids, quality, matrices)

    def slots(self) -> int:
        """Slots the ids need."""
        return int(self.ids.max()) + 1 if len(self.ids) else 0

    def below(self, cap: int) -> _Sent:
        """Only the objects whose id is below ``cap``."""
        keep = self.ids < cap
        if keep.all():
            return self
        frame_of = np.repeat(np.arange(len(self.counts)), self.counts)[keep]
        counts = np.bincount(frame_of, minlength=len(self.counts)).tolist()
        return _Sent(counts, self.ids[keep], self.quality[keep], self.matrices[keep])


def _merge_poses(
    kinds: Sequence[tuple[_Poses, _Sent]], frames: int
) -> tuple[np.ndarray, np.ndarray]:
    """Merge several kinds of objects over several frames with a few array operations: the
    matrices (frames, slots, 4, 4) and qualities (frames, slots) after each frame, the kinds'
    slots one after the other. Each kind's poses then hold its state after the last frame."""
    before = np.concatenate([poses.matrices for poses, _ in kinds])
    slots = len(before)
    quality = np.full((frames, slots), -1.0)
    frame_of, slot_of, offset = [], [], 0
    for poses, sent in kinds:
        frame_of.append(np.repeat(np.arange(frames), sent.counts))
        slot_of.append(sent.ids + offset)
        offset += len(poses)
    frame_of_all = np.concatenate(frame_of)
    if not len(frame_of_all):
        matrices = np.broadcast_to(before, (frames, slots, 4, 4))
    else:
        slot_of_all = np.concatenate(slot_of)
        sent_quality = np.concatenate([sent.quality for _, sent in kinds])
        sent = np.concatenate([before, *(sent.matrices for _, sent in kinds)])
        quality[frame_of_all, slot_of_all] = sent_quality
        # for each frame and slot, the newest tracked pose so far: its row in ``sent`` (rows
        # of later frames come later, so the newest is the largest)
        newest = np.tile(np.arange(slots), (frames, 1))
        tracked = np.flatnonzero(sent_quality >= 0)
        newest[frame_of_all[tracked], slot_of_all[tracked]] = tracked + slots
        np.maximum.accumulate(newest, axis=0, out=newest)
        matrices = sent[newest]
    start = 0
    for poses, _ in kinds:
        stop = start + len(poses)
        poses.matrices = matrices[-1, start:stop].copy()
        poses.quality = quality[-1, start:stop].copy()
        start = stop
    return matrices, quality


def _fixed(values: Sequence, n: int, fill: float | int) -> list:
    return [*values[:n], *[fill] * (n - len(values))]


def _padded(values: tuple, previous: tuple, fill: float | int) -> tuple:
    """``values``, padded with ``fill`` to the length of ``previous``."""
    if len(values) < len(previous):
        return values + (fill,) * (len(previous) - len(values))
    return values


class UnitSamples:
    """The units after each of several frames: ``positions`` (frames, units, 4, 4) in metres,
    ``qualities`` (frames, units), ``digital`` (frames, units) and ``analog`` (frames, units)."""

    def __init__(
        self, positions: np.ndarray, qualities: np.ndarray, digital: np.ndarray, analog: np.ndarray
    ) -> None:
        self.positions = positions
        self.qualities = qualities
        self.digital = digital
        self.analog = analog


class _Controls:
    """Per object, the newest tuple of buttons (or joystick values) seen; never shorter than
    before. ``state`` is the same object as long as nothing changes."""

    def __init__(self, fill: float | int) -> None:
        self.fill = fill
        self.state: tuple[tuple, ...] = ()

    def update(self, values: Sequence[tuple[int, tuple]], slots: int) -> tuple[tuple, ...]:
        state = self.state
        if len(state) < slots or any(i >= len(state) or v != state[i] for i, v in values):
            grown = [*state, *[()] * (slots - len(state))]
            for i, v in values:
                grown[i] = _padded(v, grown[i], self.fill)
            if tuple(grown) != state:
                self.state = tuple(grown)
        return self.state


class DTrackUnits:
    """Frames merged into Gadgeteer's unit layout for position, digital and analog data.

    Position units: Flysticks, then measurement tools, then bodies. Digital: Flystick i button j
    (j < ``buttons_per_flystick``) is unit ``8i + j``, then tool i button j is ``8F + 4i + j``.
    Analog: Flystick i joystick value j is unit ``2i + j``, raw in [-1, 1]. The arrays only grow;
    an object missing from a frame or with quality < 0 keeps its previous matrix (identity
    before it was first seen), and its quality reads -1.

    With ``extra_units``, the Flystick buttons beyond ``buttons_per_flystick`` (upstream drops
    them) follow the tool buttons, Flystick by Flystick, and the joystick values beyond
    ``valuators_per_flystick`` follow the analog units the same way.

    :meth:`merge` takes many frames at once (with a few array operations) and gives every
    unit after each frame, laid out as after the last one.
    """

    def __init__(
        self,
        buttons_per_flystick: int = 8,
        valuators_per_flystick: int = 2,
        buttons_per_meatool: int = 4,
        *,
        extra_units: bool = False,
        limits: DTrackLimits = DEFAULT_LIMITS,
    ) -> None:
        self.limits = limits
        self.buttons_per_flystick = buttons_per_flystick
        self.valuators_per_flystick = valuators_per_flystick
        self.buttons_per_meatool = buttons_per_meatool
        self.extra_units = extra_units
        self._flysticks = _Poses()
        self._meatools = _Poses()
        self._bodies = _Poses()
        self._stick_buttons = _Controls(0)
        self._tool_buttons = _Controls(0)
        self._stick_values = _Controls(0.0)

    @property
    def counts(self) -> tuple[int, int, int]:
        """(Flysticks, tools, bodies) known so far."""
        return len(self._flysticks), len(self._meatools), len(self._bodies)

    def update(self, frame: DTrackFrame) -> None:
        """Merge one frame."""
        self.merge([frame])

    def merge(self, frames: Sequence[DTrackFrame]) -> UnitSamples:
        """Merge frames in order; the units after each of them."""
        n = len(frames)
        cap = self.limits.objects  # however the frames were parsed, never more units
        sticks = _Sent.of_objects([f.flysticks for f in frames]).below(cap)
        tools = _Sent.of_objects([f.meatools for f in frames]).below(cap)
        bodies = _Sent.of_bodies([BodySet.of(f.bodies) for f in frames]).below(cap)
        calibrated_sticks = [f.calibrated_flysticks or 0 for f in frames]
        calibrated_bodies = [
            f.calibrated_bodies - f.old_flysticks - f.old_meatools
            for f in frames
            if f.calibrated_bodies is not None
        ]
        self._flysticks.grow(min(cap, max([sticks.slots(), *calibrated_sticks])))
        self._meatools.grow(tools.slots())
        self._bodies.grow(min(cap, max([bodies.slots(), *calibrated_bodies])))
        positions, qualities = _merge_poses(
            ((self._flysticks, sticks), (self._meatools, tools), (self._bodies, bodies)), n
        )
        states = [self._controls(frame) for frame in frames]
        digital = self._rows([s[:2] for s in states], lambda key: self._digital(*key), np.int8)
        analog = self._rows([s[2:] for s in states], lambda key: self._analog(*key), np.float64)
        return UnitSamples(positions, qualities, digital, analog)

    @staticmethod
    def _rows(keys: list[tuple], lay_out: Callable[..., list], dtype: type) -> np.ndarray:
        """One row per frame, laid out in the current layout from the frame's control states
        (``keys``); a state is laid out once for as long as it stays the same object."""
        rows: list[list] = []
        last: tuple = ()
        row: list = []
        for key in keys:
            if len(key) != len(last) or any(a is not b for a, b in zip(key, last, strict=True)):
                last, row = key, lay_out(key)
            rows.append(row)
        return np.array(rows, dtype=dtype).reshape(len(rows), -1)

    def _controls(self, frame: DTrackFrame) -> tuple[tuple, tuple, tuple]:
        """Buttons of the Flysticks, of the tools and joystick values after ``frame``."""
        n_sticks, n_tools = len(self._flysticks), len(self._meatools)
        most_buttons, most_values = self.limits.buttons, self.limits.valuators
        known = [s for s in frame.flysticks if s.id < n_sticks]
        sticks = [(s.id, s.buttons[:most_buttons]) for s in known]
        values = [(s.id, s.joystick[:most_values]) for s in known]
        tools = [(t.id, t.buttons[:most_buttons]) for t in frame.meatools if t.id < n_tools]
        return (
            self._stick_buttons.update(sticks, n_sticks),
            self._tool_buttons.update(tools, n_tools),
            self._stick_values.update(values, n_sticks),
        )

    def _digital(self, sticks: tuple[tuple, ...], tools: tuple[tuple, ...]) -> list[int]:
        per_stick, per_tool = self.buttons_per_flystick, self.buttons_per_meatool
        values = [b for bt in sticks for b in _fixed(bt, per_stick, 0)]
        values += [b for bt in tools for b in _fixed(bt, per_tool, 0)]
        if self.extra_units:  # as many as each Flystick has now
            for bt, now in zip(sticks, self._stick_buttons.state, strict=True):
                values += _fixed(bt[per_stick:], max(0, len(now) - per_stick), 0)
        return values

    def _analog(self, sticks: tuple[tuple, ...]) -> list[float]:
        per_stick = self.valuators_per_flystick
        values = [v for vt in sticks for v in _fixed(vt, per_stick, 0.0)]
        if self.extra_units:
            for vt, now in zip(sticks, self._stick_values.state, strict=True):
                values += _fixed(vt[per_stick:], max(0, len(now) - per_stick), 0.0)
        return values

    def position_array(self) -> np.ndarray:
        """A new (units, 4, 4) array of the matrices (metres) in unit order."""
        return np.concatenate(
            (self._flysticks.matrices, self._meatools.matrices, self._bodies.matrices)
        )

    def positions(self) -> list[np.ndarray]:
        """4x4 matrices (metres) in unit order."""
        return list(self.position_array())

    def qualities(self) -> list[float]:
        """Tracking quality per position unit (-1 = not tracked in the last frame)."""
        return np.concatenate(
            (self._flysticks.quality, self._meatools.quality, self._bodies.quality)
        ).tolist()

    def digital(self) -> list[int]:
        return self._digital(self._stick_buttons.state, self._tool_buttons.state)

    def analog(self) -> list[float]:
        return self._analog(self._stick_values.state)
