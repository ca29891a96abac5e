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
* Silence longer than ``peer_timeout`` is reported with :class:`DTrackDisconnected`, so a caller can
  reconnect (and re-send the start commands) instead of waiting for ever.
"""

from __future__ import annotations

import math
import re
import select
import socket
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

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


class DTrackDisconnected(ConnectionError):
    """No datagram arrived for longer than ``peer_timeout``: the tracker is gone or stopped."""


# -- decoded data ---------------------------------------------------------------------------------


def pose_matrix(location_mm: Sequence[float], rotation: Sequence[float]) -> np.ndarray:
    """A 4x4 pose in metres from a location in mm and 9 rotation values sent column by column."""
    matrix = np.eye(4, dtype=np.float64)
    matrix[:3, :3] = np.asarray(rotation, dtype=np.float64).reshape(3, 3, order="F")
    matrix[:3, 3] = np.asarray(location_mm, dtype=np.float64) * MM_TO_M
    return matrix


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
    """Everything one datagram said. Lists hold the objects in the order they were sent."""

    frame: int | None = None
    timestamp: float | None = None
    bodies: tuple[Body, ...] = ()
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

_BLOCK = re.compile(r"\[([^\[\]]*)\]")
_BLOCKS_ONLY = re.compile(r"(?:\s*\[[^\[\]]*\])*\s*")


def _int(token: str) -> int:
    try:
        return int(token, 10)
    except ValueError:
        raise DTrackFormatError(f"not an integer: {token!r}") from None


def _float(token: str) -> float:
    try:
        value = float(token)
    except ValueError:
        raise DTrackFormatError(f"not a number: {token!r}") from None
    if not math.isfinite(value):
        raise DTrackFormatError(f"not a finite number: {token!r}")
    return value


def _count(token: str, what: str) -> int:
    n = _int(token)
    if n < 0:
        raise DTrackFormatError(f"negative {what}: {n}")
    return n


def _bits(fields: Sequence[int], n: int) -> tuple[int, ...]:
    """Buttons 0..n-1 from 32-bit fields: bit j of field k is button 32k + j."""
    return tuple((fields[i // 32] >> (i % 32)) & 1 for i in range(n))


class _Line:
    """One line split into its tag, header tokens and bracketed blocks."""

    def __init__(self, line: str) -> None:
        head, bracket, rest = line.partition("[")
        words = head.split()
        if not words:
            raise DTrackFormatError("empty line")
        self.tag = words[0]
        self.header = words[1:]
        tail = bracket + rest
        if not _BLOCKS_ONLY.fullmatch(tail):
            raise DTrackFormatError("unbalanced or stray text between blocks")
        self.blocks = [b.split() for b in _BLOCK.findall(tail)]
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
        return [_float(t) for t in self.block(n)]

    def location(self) -> tuple[float, float, float]:
        x, y, z = self.floats(3)
        return (x, y, z)


class _FrameBuilder:
    """Collects the decoded lines of one datagram."""

    def __init__(self) -> None:
        self.values: dict[str, object] = {}
        self.bodies: list[Body] = []
        self.flysticks: list[Flystick] = []
        self.meatools: list[MeasurementTool] = []
        self.markers: list[Marker] = []
        self.gloves: list[Glove] = []

    def build(self, bad_lines: int) -> DTrackFrame:
        return DTrackFrame(
            bodies=tuple(self.bodies),
            flysticks=tuple(self.flysticks),
            meatools=tuple(self.meatools),
            markers=tuple(self.markers),
            gloves=tuple(self.gloves),
            bad_lines=bad_lines,
            **self.values,  # type: ignore[arg-type]
        )

    # Each method parses one tag into local lists first, so a bad line adds nothing.

    def fr(self, line: _Line) -> None:
        self.values["frame"] = _count(line.head(0), "frame counter")

    def ts(self, line: _Line) -> None:
        self.values["timestamp"] = _float(line.head(0))

    def cal6d(self, line: _Line) -> None:
        self.values["calibrated_bodies"] = _count(line.head(0), "body count")

    def glcal(self, line: _Line) -> None:
        self.values["calibrated_gloves"] = _count(line.head(0), "glove count")

    def body6d(self, line: _Line) -> None:
        found = []
        for _ in range(_count(line.head(0), "body count")):
            ident, quality = line.block(2)
            loc = line.location()
            found.append(
                Body(_count(ident, "id"), _float(quality), loc, pose_matrix(loc, line.floats(9)))
            )
        self.bodies.extend(found)

    def body6di(self, line: _Line) -> None:
        found = []
        for _ in range(_count(line.head(0), "body count")):
            ident, state, error = line.block(3)
            loc = line.location()
            found.append(
                Body(
                    _count(ident, "id"),
                    float(_int(state) - 1),
                    loc,
                    pose_matrix(loc, line.floats(9)),
                    inertial=True,
                    drift_error=_float(error),
                )
            )
        self.bodies.extend(found)

    def flystick6df(self, line: _Line) -> None:
        found = []
        for k in range(_count(line.head(0), "Flystick count")):
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
        calibrated = _count(line.head(0), "calibrated Flystick count")
        found = []
        for k in range(_count(line.head(1), "Flystick count")):
            ident, quality, nbt, nvt = line.block(4)
            if _int(ident) != k:
                raise DTrackFormatError(f"6df2: Flystick id {ident} at index {k}")
            # Fixed: upstream rejected nbt > 8 (it meant nvt); any count the block holds is fine.
            n_buttons, n_valuators = _count(nbt, "button count"), _count(nvt, "valuator count")
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
        for _ in range(_count(line.head(0), "tool count")):
            ident, quality, bt = line.block(3)
            loc = line.location()
            found.append(
                MeasurementTool(
                    _count(ident, "id"),
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
        for _ in range(_count(line.head(0), "tool count")):
            ident, quality, nbt, radius = line.block(4)
            n_buttons = _count(nbt, "button count")
            loc = line.location()
            matrix = pose_matrix(loc, line.floats(9))
            fields = [_int(v) & 0xFFFFFFFF for v in line.block(-(-n_buttons // 32))]
            covariance = tuple(line.floats(6))
            found.append(
                MeasurementTool(
                    _count(ident, "id"),
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
        for _ in range(_count(line.head(0), "marker count")):
            ident, quality = line.block(2)
            found.append(Marker(_count(ident, "id"), _float(quality), line.location()))
        self.markers.extend(found)

    def glove(self, line: _Line) -> None:
        found = []
        for _ in range(_count(line.head(0), "glove count")):
            ident, quality, lr, nf = line.block(4)
            n_fingers = _count(nf, "finger count")
            if n_fingers > 5:
                raise DTrackFormatError(f"gl: {n_fingers} fingers")
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
                Glove(_count(ident, "id"), _float(quality), lr == "1", loc, matrix, tuple(fingers))
            )
        self.gloves.extend(found)


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


def parse_frame(data: bytes | str, truncated: bool = False) -> DTrackFrame | None:
    """Decode one datagram; ``None`` when it holds no valid DTrack line at all.

    Lines with an unknown tag are ignored. Malformed lines are skipped and counted in the
    frame's ``bad_lines``. With ``truncated`` (the datagram did not fit the receive buffer) the
    last line is taken as cut off and counted as bad.
    """
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
    builder = _FrameBuilder()
    good, bad = 0, int(truncated)
    for raw in lines:
        if not raw.strip():
            continue
        try:
            line = _Line(raw)
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
    return builder.build(bad) if good else None


# -- the receiver -----------------------------------------------------------------------------


class DTrackStandalone:
    """Receives DTrack datagrams on a UDP port and optionally starts and stops the tracker.

    ``receive_port`` is a port number (bound on ``bind_address``; 0 lets the OS choose, see
    :attr:`port`) or an already-bound UDP socket, which is switched to non-blocking mode and is
    not closed by :meth:`close`. With a non-empty ``server_name`` and a non-zero
    ``command_port``, :meth:`open` sends "cameras and tracking on", waits ``start_delay`` and
    sends "start sending"; :meth:`close` sends "stop sending" and "cameras off".

    :meth:`sample` waits at most ``receive_timeout`` for data; after ``peer_timeout`` seconds
    without any datagram it raises :class:`DTrackDisconnected` (``None`` never does).
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
    ) -> None:
        self.receive_port = receive_port
        self.bind_address = bind_address
        self.server_name = server_name
        self.command_port = command_port
        self.receive_timeout = receive_timeout
        self.peer_timeout = peer_timeout
        self.start_delay = start_delay
        self.buffer_size = buffer_size
        self.datagrams = 0  # datagrams received
        self.bad_datagrams = 0  # datagrams that held no valid frame
        self.bad_lines = 0  # malformed lines skipped inside otherwise valid frames
        self.truncated_datagrams = 0  # larger than buffer_size
        self.last_frame: DTrackFrame | None = None
        self._sock: socket.socket | None = None
        self._owns_socket = False
        self._last_rx = 0.0

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
                sock.bind((self.bind_address, self.receive_port))
            except BaseException:
                sock.close()
                raise
            self._sock, self._owns_socket = sock, True
        self._sock.setblocking(False)
        self._last_rx = time.monotonic()
        if self.remote_control:
            self.send_command(CMD_CAMERAS_AND_TRACKING_ON)
            time.sleep(self.start_delay)
            self.send_command(CMD_START_SENDING)

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

    def sample_all(self) -> list[DTrackFrame]:
        """Every valid frame among the datagrams waiting, oldest first.

        Waits up to ``receive_timeout`` for the first datagram, then drains the socket.
        """
        if self._sock is None:
            raise RuntimeError("the receiver is not open")
        frames: list[DTrackFrame] = []
        got_any = False
        if self.receive_timeout > 0:
            select.select([self._sock], [], [], self.receive_timeout)
        while True:
            try:
                data, _anc, flags, _addr = self._sock.recvmsg(self.buffer_size)
            except (BlockingIOError, InterruptedError):
                break
            except ConnectionRefusedError:
                continue  # an ICMP error from a command sent earlier; not data
            got_any = True
            self.datagrams += 1
            truncated = bool(flags & socket.MSG_TRUNC)
            self.truncated_datagrams += truncated
            frame = parse_frame(data, truncated=truncated)
            if frame is None:
                self.bad_datagrams += 1
                continue
            self.bad_lines += frame.bad_lines
            frames.append(frame)
        now = time.monotonic()
        if got_any:
            self._last_rx = now
        elif self.peer_timeout is not None and now - self._last_rx > self.peer_timeout:
            raise DTrackDisconnected(f"no DTrack data for {now - self._last_rx:.3f} s")
        if frames:
            self.last_frame = frames[-1]
        return frames


# -- Gadgeteer's unit numbering ------------------------------------------------------------------


@dataclass
class _Slot:
    matrix: np.ndarray = field(default_factory=lambda: np.eye(4))
    quality: float = -1.0
    buttons: list[int] = field(default_factory=list)
    valuators: list[float] = field(default_factory=list)


class DTrackUnits:
    """Frames merged into Gadgeteer's unit layout for position, digital and analog data.

    Position units: Flysticks, then measurement tools, then bodies. Digital: Flystick i button j
    (j < ``buttons_per_flystick``) is unit ``8i + j``, then tool i button j is ``8F + 4i + j``.
    Analog: Flystick i joystick value j is unit ``2i + j``, raw in [-1, 1]. The arrays only grow;
    an object missing from a frame or with quality < 0 keeps its previous matrix (identity
    before it was first seen), and its quality reads -1.
    """

    def __init__(
        self,
        buttons_per_flystick: int = 8,
        valuators_per_flystick: int = 2,
        buttons_per_meatool: int = 4,
    ) -> None:
        self.buttons_per_flystick = buttons_per_flystick
        self.valuators_per_flystick = valuators_per_flystick
        self.buttons_per_meatool = buttons_per_meatool
        self.flysticks: list[_Slot] = []
        self.meatools: list[_Slot] = []
        self.bodies: list[_Slot] = []

    def update(self, frame: DTrackFrame) -> None:
        """Merge one frame."""
        if frame.calibrated_flysticks is not None:
            self._grow(self.flysticks, frame.calibrated_flysticks)
        if frame.calibrated_bodies is not None:
            self._grow(
                self.bodies, frame.calibrated_bodies - frame.old_flysticks - frame.old_meatools
            )
        self._merge(
            self.flysticks, frame.flysticks, self.buttons_per_flystick, self.valuators_per_flystick
        )
        self._merge(self.meatools, frame.meatools, self.buttons_per_meatool, 0)
        self._merge(self.bodies, frame.bodies, 0, 0)

    def positions(self) -> list[np.ndarray]:
        """4x4 matrices (metres) in unit order."""
        return [s.matrix.copy() for s in (*self.flysticks, *self.meatools, *self.bodies)]

    def qualities(self) -> list[float]:
        """Tracking quality per position unit (-1 = not tracked in the last frame)."""
        return [s.quality for s in (*self.flysticks, *self.meatools, *self.bodies)]

    def digital(self) -> list[int]:
        return [b for s in self.flysticks for b in s.buttons] + [
            b for s in self.meatools for b in s.buttons
        ]

    def analog(self) -> list[float]:
        return [v for s in self.flysticks for v in s.valuators]

    @staticmethod
    def _grow(slots: list[_Slot], n: int) -> None:
        while len(slots) < n:
            slots.append(_Slot())

    def _merge(
        self,
        slots: list[_Slot],
        objects: Sequence[Body | Flystick | MeasurementTool],
        n_buttons: int,
        n_valuators: int,
    ) -> None:
        for slot in slots:
            slot.quality = -1.0
        for obj in objects:
            self._grow(slots, obj.id + 1)
        for slot in slots:
            slot.buttons += [0] * (n_buttons - len(slot.buttons))
            slot.valuators += [0.0] * (n_valuators - len(slot.valuators))
        for obj in objects:
            slot = slots[obj.id]
            slot.quality = obj.quality
            if obj.quality >= 0:
                slot.matrix = obj.matrix.copy()
            if isinstance(obj, (Flystick, MeasurementTool)):
                pressed = list(obj.buttons[:n_buttons])
                slot.buttons = pressed + [0] * (n_buttons - len(pressed))
            if isinstance(obj, Flystick):
                values = list(obj.joystick[:n_valuators])
                slot.valuators = values + [0.0] * (n_valuators - len(values))
