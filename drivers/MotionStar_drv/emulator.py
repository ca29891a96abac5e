"""An Ascension MotionStar chassis on a loopback TCP server, independent of gadgetctl's input
manager (the command line comes from the shared emulator scaffolding, :mod:`gadgetctl.emulation`).

The server answers wake-up, status, setup, single-shot, run-continuous, stop,
shut-down and sequence-sync messages, and streams data packets while running.
One client is served at a time; after a client leaves, the next may connect.

Scenarios (poses are deterministic functions of the packet count):

``idle``        every sensor holds a fixed pose
``motion``      sensors move and turn smoothly
``buttons``     fixed poses, the first button byte steps through presses/releases; while
                a button is held each sensor's record is followed by a feed-through
                record (``0xE1``: format code 14, one word)
``garbage``     ``motion`` with junk, broken headers and cut-short packets in between
``disconnect``  ``disconnect_after`` data packets, then the connection is closed
"""

from __future__ import annotations

import contextlib
import math
import queue
import random
import select
import socket
import struct
import sys
import threading
import time
from collections import deque
from dataclasses import dataclass, field
from types import TracebackType

from gadgetctl.emulation import Console, emulator_parser, run
from gadgetctl.transport.udp import bind_named

# The emulator keeps its own copy of the wire constants so that a mistake in the
# driver cannot be mirrored here and go unnoticed by the tests.
MSG_WAKE_UP, RSP_WAKE_UP = 10, 20
MSG_SHUT_DOWN, RSP_SHUT_DOWN = 11, 21
MSG_SYNC_SEQUENCE, RSP_SYNC_SEQUENCE = 30, 31
RSP_ILLEGAL, RSP_UNKNOWN = 40, 50
MSG_GET_STATUS, RSP_GET_STATUS = 101, 201
MSG_SEND_SETUP, RSP_SEND_SETUP = 102, 202
MSG_SINGLE_SHOT = 103
MSG_RUN_CONTINUOUS, RSP_RUN_CONTINUOUS = 104, 204
MSG_STOP_DATA, RSP_STOP_DATA = 105, 205
DATA_PACKET_MULTI = 210
PROTOCOL = 3
HEADER = struct.Struct(">HH4sBBBBHH")
ERR_NO_DEVICE = 8
ERR_ILLEGAL_SETUP = 9

#: The port ``main`` listens on unless told otherwise (the chassis's TCP port, example.jconf's).
DEFAULT_PORT = 6000

WORDS = {0: 0, 1: 3, 2: 3, 3: 9, 4: 6, 5: 12, 7: 4, 8: 7}
#: The data info byte of a feed-through record: format code 14, one word. An independent
#: MotionStar driver built on Ascension's sample code met it while a wand button was held.
FEED_THROUGH = 0xE1
BUTTON_STEPS = (0x00, 0x01, 0x00, 0x02, 0x00, 0x04, 0x03, 0x00)
SCENARIOS = ("idle", "motion", "buttons", "garbage", "disconnect")

Pose = tuple[tuple[float, float, float], tuple[float, float, float]]


def pose(scenario: str, unit: int, k: int) -> Pose:
    """Position (x, y, z) in inches and angles (z, y, x) in degrees of a sensor."""
    if scenario in ("idle", "buttons"):
        return (12.0 + 6.0 * unit, -8.0 + 3.0 * unit, 24.0 - 2.0 * unit), (
            30.0 + 10.0 * unit,
            -20.0,
            45.0,
        )
    phase = 2 * math.pi * k
    position = (
        30.0 * math.sin(phase / 200) + 6.0 * unit,
        20.0 * math.cos(phase / 200),
        10.0 + 5.0 * math.sin(phase / 50),
    )
    angles = (
        170.0 * math.sin(phase / 300 + unit),
        80.0 * math.sin(phase / 170),
        170.0 * math.cos(phase / 230),
    )
    return position, angles


def _word(value: float) -> int:
    return max(-32768, min(32767, round(value)))


def ascension_matrix(angles: tuple[float, float, float]) -> list[list[float]]:
    """The manual's rotation matrix M for azimuth (z), elevation (y), roll (x)."""
    a, e, r = (math.radians(v) for v in angles)
    ca, sa, ce, se, cr, sr = (
        math.cos(a),
        math.sin(a),
        math.cos(e),
        math.sin(e),
        math.cos(r),
        math.sin(r),
    )
    return [
        [ce * ca, ce * sa, -se],
        [-cr * sa + sr * se * ca, cr * ca + sr * se * sa, sr * ce],
        [sr * sa + cr * se * ca, -sr * ca + cr * se * sa, cr * ce],
    ]


def ascension_quaternion(m: list[list[float]]) -> tuple[float, float, float, float]:
    """q0..q3 for M (q0 = scalar part, kept >= 0).

    They are built to describe the sensor orientation (M transposed), which is
    how the C++ driver reads them: as (w, x, y, z) with no conjugation.
    """
    trace = m[0][0] + m[1][1] + m[2][2]
    if trace > 0:
        s = math.sqrt(1.0 + trace) * 2
        q = (s / 4, (m[1][2] - m[2][1]) / s, (m[2][0] - m[0][2]) / s, (m[0][1] - m[1][0]) / s)
    elif m[0][0] > m[1][1] and m[0][0] > m[2][2]:
        s = math.sqrt(1.0 + m[0][0] - m[1][1] - m[2][2]) * 2
        q = ((m[1][2] - m[2][1]) / s, s / 4, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s)
    elif m[1][1] > m[2][2]:
        s = math.sqrt(1.0 + m[1][1] - m[0][0] - m[2][2]) * 2
        q = ((m[2][0] - m[0][2]) / s, (m[0][1] + m[1][0]) / s, s / 4, (m[1][2] + m[2][1]) / s)
    else:
        s = math.sqrt(1.0 + m[2][2] - m[0][0] - m[1][1]) * 2
        q = ((m[0][1] - m[1][0]) / s, (m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, s / 4)
    return q if q[0] >= 0 else (-q[0], -q[1], -q[2], -q[3])


def encode_words(
    code: int, position: tuple[float, ...], angles: tuple[float, float, float], full_scale: int
) -> tuple[int, ...]:
    """The data words of one record in format ``code``."""
    pos = tuple(_word(p * 32767 / full_scale) for p in position)
    ang = tuple(_word(a * 32767 / 180) for a in angles)
    m = ascension_matrix(angles)
    mat = tuple(_word(m[row][col] * 32768) for col in range(3) for row in range(3))
    quat = tuple(_word(q * 32768) for q in ascension_quaternion(m))
    return {
        0: (),
        1: pos,
        2: ang,
        3: mat,
        4: pos + ang,
        5: pos + mat,
        7: quat,
        8: pos + quat,
    }[code]


@dataclass
class Device:
    """One FBB device of the emulated chassis."""

    address: int
    erc: bool = False
    status: bytearray = field(default_factory=bytearray)

    @property
    def fbb_byte(self) -> int:
        return 0x80 | 0x40 | (0x11 if self.erc else 0x20)  # accessible, running, ERC+ERT0 / sensor


def bird_status(address: int, full_scale: int) -> bytearray:
    """A 70-byte bird status: position/angles, inches, the given full scale."""
    block = bytearray(70)
    block[0] = 0x40  # running
    block[1] = 0x03  # device id
    block[2:4] = bytes([3, 67])  # software revision
    block[6] = 0x64  # 6 words, position/angles
    block[7] = 1  # report rate
    block[8:10] = bytes([full_scale >> 8 & 0x0F, full_scale & 0xFF])  # units 0 (inches)
    block[11] = address  # FBB address
    tables = [0x0000] * 7 + [0x0800] * 7 + [0x0032] * 7 + [0] * 6
    struct.pack_into(">27H", block, 16, *tables)
    return block


class MotionStarEmulator:
    """A MotionStar chassis with ``birds`` sensors (and an ERC if ``erc``).

    ``address`` is ``"127.0.0.1:PORT"`` once started. ``rate`` is data packets per
    second while running continuously. ``received`` logs ``(type, xtype,
    sequence)`` of each client message; ``sent_data`` maps a data packet's
    sequence number to ``{address: (format code, words, buttons)}``.

    For junk tests: :meth:`inject` sends bytes as they are between two messages, and
    while ``noise`` is set a running stream carries random bytes instead of data packets.
    """

    def __init__(
        self,
        scenario: str = "motion",
        rate: float = 100.0,
        *,
        birds: int = 2,
        erc: bool = False,
        host: str = "127.0.0.1",
        port: int = 0,
        full_scale: int = 144,
        measurement_rate: float = 86.1,
        disconnect_after: int = 5,
        seed: int = 7,
    ) -> None:
        if scenario not in SCENARIOS:
            raise ValueError(f"unknown scenario {scenario!r}; choose from {', '.join(SCENARIOS)}")
        if rate <= 0:
            raise ValueError("rate must be positive")
        self.scenario = scenario
        self.rate = rate
        self.host = host
        self.port = port
        self.full_scale = full_scale
        self.measurement_rate = measurement_rate
        self.disconnect_after = disconnect_after
        self.devices: list[Device] = []
        if erc:
            self.devices.append(Device(1, erc=True))
        for _ in range(birds):
            address = len(self.devices) + 1
            self.devices.append(Device(address, status=bird_status(address, full_scale)))
        self.received: list[tuple[int, int, int]] = []
        self.sent_data: dict[
            int, dict[int, tuple[int, tuple[int, ...], tuple[int, int] | None]]
        ] = {}
        self._sent_order: deque[int] = deque()
        self.connections = 0
        self.console = Console()
        self.disconnected = threading.Event()
        self.client_left = threading.Event()
        self._rng = random.Random(seed)
        self.noise = threading.Event()
        self._injections: queue.SimpleQueue[bytes] = queue.SimpleQueue()
        self._listener: socket.socket | None = None
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._packets = 0

    @property
    def address(self) -> str:
        return f"{self.host}:{self.port}"

    @property
    def sensors(self) -> list[Device]:
        return [d for d in self.devices if not d.erc]

    # -- life cycle -------------------------------------------------------------------

    def start(self) -> MotionStarEmulator:
        """Bind and listen, then serve in a background thread."""
        if self._thread is not None:
            return self
        listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        bind_named(listener, self.host, self.port)
        listener.listen(1)
        self.port = listener.getsockname()[1]
        self._listener = listener
        self._stop.clear()
        self._thread = threading.Thread(target=self._serve, name="motionstar-emulator", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5)
            self._thread = None
        if self._listener is not None:
            self._listener.close()
            self._listener = None

    def __enter__(self) -> MotionStarEmulator:
        return self.start()

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.stop()

    # -- server -------------------------------------------------------------------------

    def _serve(self) -> None:
        assert self._listener is not None
        while not self._stop.is_set():
            ready, _, _ = select.select([self._listener], [], [], 0.05)
            if not ready:
                continue
            conn, peer = self._listener.accept()
            who = f"{peer[0]}:{peer[1]}"
            self.connections += 1
            self.client_left.clear()
            self.console.client_connected(who)
            why = "closed by the client"
            with conn:
                conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                conn.settimeout(1.0)  # a client that stops reading ends the session
                try:
                    _Session(self, conn).run()
                except OSError as exc:
                    why = f"connection lost: {exc.strerror or exc}"
            if self.disconnected.is_set():
                why = "closed by the disconnect scenario"
            elif self._stop.is_set():
                why = "emulator stopping"
            self.console.client_disconnected(who, why)
            self.client_left.set()

    def inject(self, data: bytes) -> None:
        """Send ``data`` to the connected client as it is, before the next message."""
        self._injections.put(data)

    def _record_sent(self, sequence: int, records: dict) -> None:
        self.sent_data[sequence] = records
        self._sent_order.append(sequence)
        if len(self._sent_order) > 4096:
            self.sent_data.pop(self._sent_order.popleft(), None)


class _Session:
    """The protocol state of one client connection."""

    def __init__(self, emu: MotionStarEmulator, conn: socket.socket) -> None:
        self.emu = emu
        self.conn = conn
        self.buffer = bytearray()
        self.awake = False
        self.running = False
        self.data_sequence = 0
        self.next_due = 0.0
        self.k = 0

    def run(self) -> None:
        while not self.emu._stop.is_set():
            wait = 0.05
            if self.running:
                wait = max(0.0, min(wait, self.next_due - time.monotonic()))
            ready, _, _ = select.select([self.conn], [], [], wait)
            if ready:
                chunk = self.conn.recv(65536)
                if not chunk:
                    return
                self.buffer += chunk
                self._handle_messages()
            self._send_injections()
            if self.running and time.monotonic() >= self.next_due:
                self.next_due += 1.0 / self.emu.rate
                if not self._stream_one():
                    return

    def _send_injections(self) -> None:
        injections = self.emu._injections
        while not injections.empty():
            data = injections.get()
            self.conn.settimeout(60.0)  # however slowly the client reads junk
            try:
                self.conn.sendall(data)
            finally:
                self.conn.settimeout(1.0)

    def _handle_messages(self) -> None:
        while len(self.buffer) >= HEADER.size:
            seq, _ms, _t, kind, xtype, proto, _err, _ext, length = HEADER.unpack_from(self.buffer)
            if len(self.buffer) < HEADER.size + length:
                return
            payload = bytes(self.buffer[HEADER.size : HEADER.size + length])
            del self.buffer[: HEADER.size + length]
            self.emu.received.append((kind, xtype, seq))
            if proto != PROTOCOL:
                self._send(RSP_UNKNOWN, seq)
            else:
                self._answer(kind, xtype, seq, payload)

    def _answer(self, kind: int, xtype: int, seq: int, payload: bytes) -> None:
        if kind == MSG_WAKE_UP:
            self.awake = True
            self._send(RSP_WAKE_UP, seq)
        elif kind == MSG_SHUT_DOWN:
            self.awake = self.running = False
            self._send(RSP_SHUT_DOWN, seq)
        elif kind == MSG_SYNC_SEQUENCE:
            self._send(RSP_SYNC_SEQUENCE, seq)
        elif kind not in (
            MSG_GET_STATUS,
            MSG_SEND_SETUP,
            MSG_SINGLE_SHOT,
            MSG_RUN_CONTINUOUS,
            MSG_STOP_DATA,
        ):
            self._send(RSP_UNKNOWN, seq)
        elif not self.awake:
            self._send(RSP_ILLEGAL, seq)
        elif kind == MSG_GET_STATUS:
            self._status(xtype, seq)
        elif kind == MSG_SEND_SETUP:
            self._setup(xtype, seq, payload)
        elif kind == MSG_SINGLE_SHOT:
            self.data_sequence = seq
            self._send_data(seq)
        elif kind == MSG_RUN_CONTINUOUS:
            self._send(RSP_RUN_CONTINUOUS, seq)
            self.running = True
            self.data_sequence = seq
            self.next_due = time.monotonic()
        elif kind == MSG_STOP_DATA:
            self.running = False
            self._send(RSP_STOP_DATA, seq)

    def _status(self, xtype: int, seq: int) -> None:
        emu = self.emu
        if xtype == 0:
            rate = f"{round(emu.measurement_rate * 1000):06d}".encode("ascii")[:6]
            # all, error, FBB devices, servers, transmitter | rate x 1000 as text |
            # chassis number, devices in chassis, first address, software revision
            block = (
                bytes([0x40, 0, len(emu.devices), 1, 0])
                + rate
                + bytes([1, len(emu.devices), 1, 3, 67])
            )
            self._send(RSP_GET_STATUS, seq, 0, block + bytes(d.fbb_byte for d in emu.devices))
        elif 1 <= xtype <= len(emu.devices) and not emu.devices[xtype - 1].erc:
            self._send(RSP_GET_STATUS, seq, xtype, bytes(emu.devices[xtype - 1].status))
        else:
            self._send(RSP_GET_STATUS, seq, xtype, error=ERR_NO_DEVICE)

    def _setup(self, xtype: int, seq: int, payload: bytes) -> None:
        emu = self.emu
        if xtype == 0 and len(payload) >= 16:
            with contextlib.suppress(ValueError):
                emu.measurement_rate = int(payload[5:11].decode("ascii")) / 1000.0
            self._send(RSP_SEND_SETUP, seq)
            return
        device = emu.devices[xtype - 1] if 1 <= xtype <= len(emu.devices) else None
        fmt = payload[6] if len(payload) == 70 else 0xFF
        if device is None or device.erc or WORDS.get(fmt & 0x0F) != fmt >> 4:
            self._send(RSP_SEND_SETUP, seq, xtype, error=ERR_ILLEGAL_SETUP)
            return
        device.status[:] = payload
        self._send(RSP_SEND_SETUP, seq, xtype)

    def _stream_one(self) -> bool:
        """Send the next continuous packet (plus scenario junk); False to hang up."""
        emu = self.emu
        if emu.scenario == "disconnect" and self.k >= emu.disconnect_after:
            emu.console.stopped_sending(f"closed the connection after {self.k} data packets")
            self.conn.shutdown(socket.SHUT_RDWR)
            emu.disconnected.set()
            return False
        if emu.noise.is_set():
            self._send_raw(emu._rng.randbytes(1024))
            return True
        self.data_sequence = (self.data_sequence + 1) % 65536
        if emu.scenario == "garbage":
            self._send_raw(self._junk())
        self._send_data(self.data_sequence)
        return True

    def _records(self) -> tuple[bytes, dict]:
        emu = self.emu
        out = bytearray()
        log = {}
        for unit, device in enumerate(emu.sensors):
            code = device.status[6] & 0x0F
            position, angles = pose(emu.scenario, unit, self.k)
            words = encode_words(code, position, angles, emu.full_scale)
            buttons = None
            if device.status[5] & 0x08:
                buttons = (
                    BUTTON_STEPS[self.k % len(BUTTON_STEPS)] if emu.scenario == "buttons" else 0,
                    0,
                )
            out.append(device.address | (0x80 if buttons else 0))
            out.append(code << 4 | len(words))
            out += struct.pack(f">{len(words)}h", *words)
            if buttons:
                out += bytes(buttons)
                # while a wand button is held a chassis adds a feed-through record:
                # format code 14, one word (0xE1)
                out += bytes((device.address, FEED_THROUGH)) + struct.pack(">h", buttons[0])
            log[device.address] = (code, words, buttons)
        return bytes(out), log

    def _send_data(self, seq: int) -> None:
        payload, log = self._records()
        self.emu._record_sent(seq, log)
        self._send(DATA_PACKET_MULTI, seq, 0, payload)
        self.k += 1

    def _junk(self) -> bytes:
        """Something that is not a valid packet; the kind rotates with the count."""
        rng = self.emu._rng
        kind = self.k % 4
        if kind == 0:  # random bytes
            return bytes(rng.randrange(256) for _ in range(5 + self.k % 13))
        payload, _log = self._records()
        if kind == 1 and payload:  # a packet cut short: the next one follows at once
            return self._packet(DATA_PACKET_MULTI, 0xFFFF, 0, payload)[
                : HEADER.size + len(payload) // 2
            ]
        if kind == 2:  # a header with the wrong protocol byte
            return self._packet(DATA_PACKET_MULTI, 0, 0, payload, protocol=7)
        # records that do not add up: the word count nibble is off by one
        broken = bytearray(payload)
        if len(broken) >= 2:
            broken[1] += 1
        return self._packet(DATA_PACKET_MULTI, 0, 0, bytes(broken))

    def _packet(
        self,
        kind: int,
        seq: int,
        xtype: int = 0,
        payload: bytes = b"",
        error: int = 0,
        protocol: int = PROTOCOL,
    ) -> bytes:
        now = time.time()
        stamp = int(now).to_bytes(4, "big")
        header = HEADER.pack(
            seq, int(now * 1000) % 1000, stamp, kind, xtype, protocol, error, 0, len(payload)
        )
        return header + payload

    def _send(
        self, kind: int, seq: int, xtype: int = 0, payload: bytes = b"", error: int = 0
    ) -> None:
        self._send_raw(self._packet(kind, seq, xtype, payload, error))

    def _send_raw(self, data: bytes) -> None:
        self.conn.sendall(data)


def main(argv: list[str] | None = None) -> int:
    """Run the emulator until Ctrl-C, SIGTERM, SIGHUP or ``--duration`` seconds."""
    parser = emulator_parser(
        "MotionStar_drv.emulator",
        "Emulate an Ascension MotionStar chassis on a loopback TCP port.",
        scenarios=SCENARIOS,
        default_scenario="motion",
        rate=100.0,
        rate_help="data packets per second",
    )
    parser.add_argument(
        "--port",
        type=int,
        default=DEFAULT_PORT,
        help=f"TCP port (default {DEFAULT_PORT}, where drivers/MotionStar_drv/example.jconf "
        "looks; 0: the OS chooses)",
    )
    parser.add_argument("--birds", type=int, default=2, help="number of sensors")
    parser.add_argument(
        "--erc", action="store_true", help="put an extended range controller at address 1"
    )
    parser.add_argument(
        "--disconnect-after", type=int, default=5, help="data packets before closing"
    )
    args = parser.parse_args(argv)
    emulator = MotionStarEmulator(
        args.scenario,
        args.rate,
        birds=args.birds,
        erc=args.erc,
        port=args.port,
        disconnect_after=args.disconnect_after,
    )

    def announce() -> None:
        print(
            f"MotionStar emulator ({args.scenario}, {args.birds} sensors) on {emulator.address}",
            flush=True,
        )
        print(
            f"point the motion_star element at it: <address>{emulator.host}</address> "
            f"<server_port>{emulator.port}</server_port>",
            flush=True,
        )
        if emulator.port == 5000:
            print(
                "note: Gadgeteer treats server_port 5000 as UDP; this emulator is TCP", flush=True
            )

    return run(emulator, duration=args.duration, announce=announce)


if __name__ == "__main__":
    sys.exit(main())
