"""Ascension Flock of Birds serial protocol, independent of gadgetctl's input manager.

The Flock speaks single-byte commands, some followed by argument bytes (see
``../shared/reference/drivers.md`` section 3.6 for the whole table). This driver uses:

* ``O <param>`` (examine: a reply of fixed length) and ``P <param> <data>`` (change value);
* an FBB address prefix before a command meant for one bird: ``0xF0 + addr`` (addresses
  0..15), ``0xE0 + addr - 16`` (16..30, expanded addressing), ``0xA0 <addr>`` (super-expanded);
* ``L h1 h2`` (hemisphere), ``Y``/``]`` (PosAngles / PosQuaternion records), ``Q R S T``
  (report rate), ``@`` (stream), ``?`` (stop).

Records are 16-bit words sent low byte first, 7 bits per byte; the first byte of each sensor
record has bit 7 set (the phasing bit), every other byte has it clear. A word is
``int16(MS << 9 | LS << 2) / 32768``, in [-1, 1). In group (FBB) mode each record ends with
one more byte: the address of the bird that measured it.

Scaling: position words times the full scale (36 or 72 inches as the POSITION SCALING reply's
low byte says, 144 with an extended range transmitter) in **feet**, as Gadgeteer reports it; angles times 180 degrees (azimuth about z,
elevation about y, roll about x); quaternion words as they are, (q0, q1, q2, q3) with q0 the
scalar part, used as sent: (w, x, y, z) = (q0, q1, q2, q3), the same rotation the angles give.
Ascension's manuals compute the quaternion from the MATRIX output with Shepperd's method, and
VRPN's ``vrpn_Flock.C`` takes it as sent ("According to the Flock manual, the Flock should
report things in the same way other trackers do"; its inverting is an option, no longer the
default). Fixed from VR Juggler's ``FlockStandalone.cpp``, which negates q1..q3 and so turns
every sensor the wrong way round (as our MotionStar driver and VR Juggler's MotionStar do not).

Only the standard library, pyserial (through :mod:`gadgetctl.transport.serialline`, which
imports nothing else from gadgetctl) and numpy are used.
"""

from __future__ import annotations

import math
import re
import time
from dataclasses import dataclass

import numpy as np
import serial

from gadgetctl.transport.records import ResyncScanner, ScannedDevice
from gadgetctl.transport.serialline import LineSettings, SerialLine, SerialLineLost

# -- commands and parameters ------------------------------------------------------------------

#: Full scale in inches by the POSITION SCALING code (examine parameter 3).
SCALE_CODES = {0: 36.0, 1: 72.0}

EXAMINE, CHANGE = ord("O"), ord("P")
HEMISPHERE, STREAM, STREAM_STOP = ord("L"), ord("@"), ord("?")
STATUS, REVISION, SCALING, MODEL = 0x00, 0x01, 0x03, 0x0F
EXPANDED_ERROR, ADDRESSING, MASTER, SYSTEM_STATUS = 0x10, 0x13, 0x15, 0x24
GROUP_MODE, AUTO_CONFIG = 0x23, 0x32
REPLY_SIZES = {
    STATUS: 2,
    REVISION: 2,
    SCALING: 2,
    0x0A: 1,
    MODEL: 10,
    EXPANDED_ERROR: 2,
    ADDRESSING: 1,
    MASTER: 1,
}

NORMAL, EXPANDED, SUPER_EXPANDED = 0, 1, 3
#: Units on the bus per addressing mode (protocol value -> count), also the length of the
#: system status reply.
BUS_UNITS = {NORMAL: 14, EXPANDED: 30, SUPER_EXPANDED: 126}
#: The element's ``addressing_mode`` -> the protocol's value. The jdef (as VR Juggler's) gives
#: "Super Extended" the value 2, while the Flock reports and expects 3; the C++ passed the
#: config value on unchanged, so a super-expanded bus was never recognised. Fixed here.
ADDRESSING_FROM_CONFIG = {0: NORMAL, 1: EXPANDED, 2: SUPER_EXPANDED}

#: The element's ``hemisphere`` enumeration value (Front, Rear, Upper, Lower, Left, Right) ->
#: the two argument bytes of ``L``.
HEMISPHERES = {
    0: b"\x00\x00",
    1: b"\x00\x01",
    2: b"\x0c\x01",
    3: b"\x0c\x00",
    4: b"\x06\x01",
    5: b"\x06\x00",
}
REPORT_RATES = "QRST"  # every cycle, 2nd, 8th, 32nd

POS_ANGLES, POS_QUATERNION = ord("Y"), ord("]")
#: Output format byte -> words per record.
FORMAT_WORDS = {POS_ANGLES: 6, POS_QUATERNION: 7}
FORMAT_NAMES = {POS_ANGLES: "PosAngles", POS_QUATERNION: "PosQuaternion"}
#: A decoded quaternion whose length is further than this from 1 is no measurement.
QUATERNION_TOLERANCE = 0.05
#: Software revision from which the Flock reports its addressing mode and master address.
AUTODETECT_REVISION = (3, 67)
PHASING = re.compile(rb"[\x80-\xff]")


class FlockError(Exception):
    """Base class of the driver's errors."""


class FlockTimeout(FlockError, TimeoutError):
    """The Flock did not answer in time."""


class FlockProtocolError(FlockError):
    """The Flock answered, but not as the protocol says."""


class FlockDisconnected(FlockError):
    """The serial line is gone (EOF, hang-up, unplugged adapter); reopen to recover."""


# -- words and records --------------------------------------------------------------------------


def decode_word(ls: int, ms: int) -> float:
    """One 14-bit word (low byte first, 7 bits each) as a number in [-1, 1)."""
    raw = ((ms & 0x7F) << 9) | ((ls & 0x7F) << 2)
    return (raw - 0x10000 if raw & 0x8000 else raw) / 32768.0


def fbb_prefix(address: int, mode: int = NORMAL) -> bytes:
    """The "to FBB address" prefix that sends the next command to one bird."""
    if mode == SUPER_EXPANDED:
        if not 0 <= address <= 126:
            raise ValueError(f"FBB address {address} is outside 0..126")
        return bytes((0xA0, address))
    if 0 <= address < 16:
        return bytes((0xF0 + address,))
    if mode == EXPANDED and address <= 30:
        return bytes((0xE0 + address - 16,))
    raise ValueError(f"FBB address {address} needs a wider addressing mode")


def quaternion_matrix(w: float, x: float, y: float, z: float) -> np.ndarray:
    """The 3x3 rotation of the unit quaternion (w, x, y, z)."""
    return np.array(
        (
            (1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)),
            (2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)),
            (2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)),
        )
    )


def euler_matrix(azimuth: float, elevation: float, roll: float) -> np.ndarray:
    """The 3x3 rotation Rz(azimuth) Ry(elevation) Rx(roll), angles in degrees."""
    az, el, ro = (math.radians(a) for a in (azimuth, elevation, roll))
    cz, sz, cy, sy, cx, sx = (
        math.cos(az),
        math.sin(az),
        math.cos(el),
        math.sin(el),
        math.cos(ro),
        math.sin(ro),
    )
    return np.array(
        (
            (cz * cy, cz * sy * sx - sz * cx, cz * sy * cx + sz * sx),
            (sz * cy, sz * sy * sx + cz * cx, sz * sy * cx - cz * sx),
            (-sy, cy * sx, cy * cx),
        )
    )


@dataclass(frozen=True)
class BirdRecord:
    """One decoded sensor record: the bird's FBB address (0 in standalone mode), position in
    feet, and either Euler angles in degrees (azimuth, elevation, roll) or the quaternion as
    sent (q0, q1, q2, q3)."""

    address: int
    position: tuple[float, float, float]
    angles: tuple[float, float, float] | None = None
    quaternion: tuple[float, float, float, float] | None = None

    def matrix(self) -> np.ndarray:
        """The 4x4 pose, translation in feet."""
        m = np.eye(4)
        if self.quaternion is not None:
            q0, q1, q2, q3 = self.quaternion
            # as sent (VR Juggler's C++ conjugates here, against the manual: fixed)
            m[:3, :3] = quaternion_matrix(q0, q1, q2, q3)
        elif self.angles is not None:
            m[:3, :3] = euler_matrix(*self.angles)
        m[:3, 3] = self.position
        return m


def record_size(fmt: int, group: bool) -> int:
    """Bytes of one sensor record in format ``fmt`` (with the address byte in group mode)."""
    return 2 * FORMAT_WORDS[fmt] + int(group)


def decode_record(
    record: bytes, fmt: int, scale_feet: float, group: bool, addresses: frozenset[int]
) -> BirdRecord | None:
    """Decode one sensor record; None when it is none (framing, address, numbers)."""
    if len(record) != record_size(fmt, group) or record[0] < 0x80:
        return None
    if PHASING.search(record, 1):
        return None
    address = record[-1] if group else 0
    if address not in addresses:
        return None
    words = [decode_word(record[i], record[i + 1]) for i in range(0, 2 * FORMAT_WORDS[fmt], 2)]
    position = (words[0] * scale_feet, words[1] * scale_feet, words[2] * scale_feet)
    if fmt == POS_ANGLES:
        return BirdRecord(
            address, position, angles=(words[3] * 180.0, words[4] * 180.0, words[5] * 180.0)
        )
    q = tuple(words[3:7])
    if abs(math.sqrt(sum(v * v for v in q)) - 1.0) > QUATERNION_TOLERANCE:
        return None  # not a rotation: junk that happened to frame
    return BirdRecord(address, position, quaternion=q)  # type: ignore[arg-type]


@dataclass
class RecordScanner(ResyncScanner[BirdRecord]):
    """Finds sensor records in the byte stream by their phasing bit. Junk is skipped a whole
    run at a time (one search to the next byte with bit 7 set), counted once per run in
    ``bad_records`` and byte by byte in ``skipped_bytes``; a framed record with a wrong
    address or impossible numbers is junk too."""

    fmt: int = POS_QUATERNION
    scale_feet: float = 3.0
    group: bool = False
    addresses: frozenset[int] = frozenset({0})

    def find_head(self, buffer: bytearray, start: int) -> int:
        found = PHASING.search(buffer, start)
        return found.start() if found else -1

    def record_size(self) -> int:
        return record_size(self.fmt, self.group)

    def decode(self, record: bytes) -> BirdRecord | None:
        return decode_record(record, self.fmt, self.scale_feet, self.group, self.addresses)


@dataclass(frozen=True)
class BusUnit:
    """One entry of the system status: FBB address and its flag bits."""

    address: int
    flags: int

    @property
    def accessible(self) -> bool:
        return bool(self.flags & 0x80)

    @property
    def has_sensor(self) -> bool:
        return bool(self.flags & 0x20)

    @property
    def extended_range(self) -> bool:
        return bool(self.flags & 0x10)


# -- the device -----------------------------------------------------------------------------------


def scale_from_reply(reply: bytes) -> float:
    """The full scale (inches) from the 2-byte answer to ``O 0x03`` (POSITION SCALING).

    Ascension's manuals (EXAMINE VALUE: "If the PARAMETERdata returned is a word then the
    Least Significant byte (LSbyte) is received before the Most Significant byte"; POSITION
    SCALING: "The most significant byte ... is always zero. If the least significant byte = 0,
    the scale factor is 36 inches ... = 1, the full scale output is 72 inches"), and VRPN's
    ``vrpn_Flock.C``, which reads examine words low byte first: the code is the **first**
    byte. Fixed from VR Juggler's ``FlockStandalone.cpp``, which tests the second byte (the
    MSB, always 0) and so reads every 72-inch Flock as 36 inches, halving its positions."""
    code = reply[0]  # the LSB (VR Juggler's C++ reads reply[1], the MSB: a device mismatch)
    if code not in SCALE_CODES or reply[1] != 0:
        raise FlockProtocolError(f"position scaling reply {reply.hex(' ')} is not 36 or 72 inches")
    return SCALE_CODES[code]


class Flock(ScannedDevice):
    """A Flock of Birds on a serial line, streaming PosQuaternion (or PosAngles) records.

    ``port`` is a device path, a pyserial URL or an open ``serial.Serial``-like object.
    ``master_address`` and ``addressing_mode`` (the protocol's value) are used when the
    firmware is older than 3.67 and cannot report them. Delays are settings (the C++
    driver's values by default): ``reset_time`` for each half of the RTS reset pulse (skipped
    when the line has no RTS, as a pseudo-terminal), ``examine_delay`` before each examine,
    ``stop_delay`` after ``?``; ``read_timeout`` for a reply; ``ready_timeout`` for the bus to
    answer after auto-configuration; ``silence_timeout`` of no data after which the Flock
    counts as gone.
    """

    def __init__(
        self,
        port: str | serial.SerialBase,
        baud: int = 38400,
        *,
        hemisphere: int = 3,
        master_address: int = 1,
        addressing_mode: int = NORMAL,
        output_format: int = POS_QUATERNION,
        report_rate: str = "Q",
        reset_time: float = 1.0,
        examine_delay: float = 0.05,
        stop_delay: float = 0.5,
        read_timeout: float = 2.0,
        ready_timeout: float = 5.0,
        silence_timeout: float = 2.0,
        poll_interval: float = 0.02,
    ) -> None:
        if hemisphere not in HEMISPHERES:
            raise ValueError(f"hemisphere {hemisphere} is not one of 0..5")
        if output_format not in FORMAT_WORDS:
            raise ValueError(f"output format {output_format!r} is not PosAngles or PosQuaternion")
        if report_rate not in REPORT_RATES:
            raise ValueError(f"report rate {report_rate!r} is not one of {REPORT_RATES}")
        self.line = SerialLine(port, LineSettings(baud), poll_interval=poll_interval)
        self.hemisphere = hemisphere
        self.master_address = master_address
        self.addressing_mode = addressing_mode
        self.output_format = output_format
        self.report_rate = report_rate
        self.reset_time = reset_time
        self.examine_delay = examine_delay
        self.stop_delay = stop_delay
        self.read_timeout = read_timeout
        self.ready_timeout = ready_timeout
        self.silence_timeout = silence_timeout
        self.revision: tuple[int, int] = (0, 0)
        self.model = ""
        self.units: list[BusUnit] = []
        self.sensors: list[int] = []
        self.extended_range = False
        self.scale_inches = 36.0
        self.scanner = RecordScanner(output_format)
        self._heard_at = 0.0

    @property
    def standalone(self) -> bool:
        return self.master_address == 0

    @property
    def degraded(self) -> list[str]:
        return self.line.degraded

    # -- life cycle -------------------------------------------------------------------------

    def open(self) -> None:
        """Reset the birds, learn the bus, configure every sensor and start streaming."""
        self.line.open_with(self._start, FlockDisconnected)

    def close(self) -> None:
        self.line.close(farewell=bytes((STREAM_STOP,)))

    # -- counters ---------------------------------------------------------------------------

    # -- data -------------------------------------------------------------------------------

    def read(self, timeout: float | None = None) -> list[BirdRecord]:
        """The records that arrived (waiting up to ``timeout`` for the first byte). Raises
        :class:`FlockDisconnected` when the line is lost or silent for ``silence_timeout``."""
        try:
            data = self.line.read(self.line.poll_interval if timeout is None else timeout)
        except SerialLineLost as exc:
            raise FlockDisconnected(str(exc)) from exc
        records = self.scanner.feed(data)
        now = time.monotonic()
        if data:
            self._heard_at = now
        elif now - self._heard_at > self.silence_timeout:
            raise FlockDisconnected(f"no data from the Flock for {self.silence_timeout:g} s")
        return records

    # -- start-up ---------------------------------------------------------------------------

    def _start(self) -> None:
        self._reset()
        self._discover()
        self._configure()
        self._write(self.report_rate.encode("ascii") + bytes((STREAM,)))
        self._heard_at = time.monotonic()

    def _reset(self) -> None:
        """RTS high resets the birds; a line without RTS (a pty) skips the pulse."""
        if self.line.set_lines(rts=True):
            time.sleep(self.reset_time)
            self.line.set_lines(rts=False)
            time.sleep(self.reset_time)
        self.line.discard_input()

    def _discover(self) -> None:
        rev = self.examine(REVISION)
        self.revision = (rev[0], rev[1])
        self.model = self.examine(MODEL).decode("ascii", "replace").strip()
        if self.revision >= AUTODETECT_REVISION:
            mode = self.examine(ADDRESSING)[0]
            if mode not in BUS_UNITS:
                raise FlockProtocolError(f"addressing mode {mode} is not 0, 1 or 3")
            self.addressing_mode = mode
            self.master_address = self.examine(MASTER)[0]
        if self.standalone:
            self.units = [BusUnit(0, 0xE0)]
        else:
            status = self.examine(SYSTEM_STATUS, BUS_UNITS[self.addressing_mode])
            self.units = []
            for address, flags in enumerate(status, start=1):
                if not flags & 0x80:
                    break  # the active units are the leading run of accessible ones
                self.units.append(BusUnit(address, flags))
            if not self.units:
                raise FlockProtocolError("no bird on the bus is accessible")
        self.extended_range = any(u.extended_range for u in self.units)
        self.sensors = [u.address for u in self.units if u.has_sensor or self.standalone]
        if not self.sensors:
            raise FlockProtocolError("no bird on the bus has a sensor")
        for unit in self.units:
            self.examine(STATUS, address=unit.address)
        if self.extended_range:
            self.scale_inches = 144.0
        else:
            self.scale_inches = scale_from_reply(self.examine(SCALING, address=self.sensors[0]))
        self.scanner = RecordScanner(
            self.output_format,
            self.scale_inches / 12.0,
            not self.standalone,
            frozenset(self.sensors),
        )

    def _configure(self) -> None:
        if not self.standalone:
            self._write(bytes((CHANGE, GROUP_MODE, 1)))
            self._check_errors()
        for address in self.sensors:
            self._write(self._to(address) + bytes((HEMISPHERE,)) + HEMISPHERES[self.hemisphere])
            self._write(self._to(address) + bytes((self.output_format,)))
        if not self.standalone:
            self._check_errors()  # the master answers once it took the commands above
            self._write(bytes((CHANGE, AUTO_CONFIG, len(self.units))))
            self._check_errors(self.ready_timeout)

    def _check_errors(self, timeout: float | None = None) -> None:
        """Read the expanded error code until it says none (a bounded number of times)."""
        deadline = time.monotonic() + (timeout if timeout is not None else self.read_timeout)
        for _ in range(16):
            try:
                code, address = self.examine(EXPANDED_ERROR)
            except FlockTimeout:
                if time.monotonic() >= deadline:
                    raise
                continue
            if code == 0:
                return
        raise FlockProtocolError(f"the Flock keeps reporting error {code} (bird {address})")

    def _to(self, address: int) -> bytes:
        return b"" if self.standalone else fbb_prefix(address, self.addressing_mode)

    def examine(self, param: int, size: int | None = None, *, address: int | None = None) -> bytes:
        """Send ``O param`` (to one bird if ``address``) and read its fixed-length reply."""
        size = REPLY_SIZES[param] if size is None else size
        if self.examine_delay > 0:
            time.sleep(self.examine_delay)
        self.line.discard_input()
        prefix = b"" if address is None else self._to(address)
        self._write(prefix + bytes((EXAMINE, param)))
        reply = bytearray()
        deadline = time.monotonic() + self.read_timeout
        while len(reply) < size:
            left = deadline - time.monotonic()
            if left <= 0:
                raise FlockTimeout(f"no {size}-byte answer to examine 0x{param:02X}")
            reply += self.line.read(left)
        if len(reply) > size:
            raise FlockProtocolError(f"examine 0x{param:02X}: {len(reply)} bytes, not {size}")
        return bytes(reply)

    def _write(self, data: bytes) -> None:
        try:
            self.line.write(data)
        except SerialLineLost as exc:
            raise FlockDisconnected(str(exc)) from exc
