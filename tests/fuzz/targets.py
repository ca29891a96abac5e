"""The registry of fuzz targets: every parser and decoder a hostile peer or file can reach.

A target takes one input (bytes) through a parser the way the program does and may raise only
its modelled errors (a bad input is a diagnostic, a counted bad record or a modelled
exception, never anything else). ``seeds`` gives valid inputs to mutate: corpus files,
emulator records. A new driver adds one ``@target`` entry here, next to the others.

Each target also checks what its parser promises about bounds (units that never grow past
their limits, counters that add up), so an input that makes a decoder allocate without limit
fails as surely as one that makes it raise.
"""

from __future__ import annotations

import atexit
import functools
import itertools
import os
import random
import shutil
import struct
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from fuzz.inputs import Grammar

REPO = Path(__file__).resolve().parents[2]
CORPUS = REPO.parent / "shared" / "corpus" / "vrjuggler"
#: Inputs larger than this are cut (a pipe or datagram would not hold more, and hypothesis
#: explores small inputs better).
MAX_INPUT = 60_000


@dataclass(frozen=True)
class Target:
    """One parser under fuzz."""

    name: str
    run: Callable[[bytes], object]
    seeds: Callable[[], list[bytes]]
    errors: tuple[type[BaseException], ...] = ()
    grammar: Grammar | None = None
    #: examples in ``make test`` (the small budget; ``make fuzz`` runs until its time is up)
    examples: int = 60
    #: the driver plug-in whose decoder this is, if any
    driver: str | None = None


TARGETS: dict[str, Target] = {}


def target(
    name: str,
    *,
    seeds: Callable[[], list[bytes]],
    errors: tuple[type[BaseException], ...] = (),
    grammar: Grammar | None = None,
    examples: int = 60,
    driver: str | None = None,
) -> Callable[[Callable[[bytes], object]], Callable[[bytes], object]]:
    """Register ``run`` as the target ``name``."""

    def register(run: Callable[[bytes], object]) -> Callable[[bytes], object]:
        if name in TARGETS:
            raise ValueError(f"fuzz target {name!r} registered twice")
        TARGETS[name] = Target(name, run, functools.cache(seeds), errors, grammar, examples, driver)
        return run

    return register


def feed(t: Target, data: bytes) -> None:
    """Run ``t`` on ``data``; a modelled error is a fine outcome, anything else propagates."""
    try:
        t.run(data[:MAX_INPUT])
    except t.errors:
        pass


@functools.cache
def _workdir() -> Path:
    """An empty directory of this process for the targets that need files (removed at exit)."""
    path = Path(tempfile.mkdtemp(prefix="gadgetctl-fuzz-"))
    atexit.register(shutil.rmtree, path, ignore_errors=True)
    return path


def _as_file(data: bytes, name: str) -> Path:
    path = _workdir() / name
    path.write_bytes(data)
    return path


# -- DTrack ---------------------------------------------------------------------------------------


@functools.cache
def _dtrack_seeds() -> list[bytes]:
    from DTrack_drv.emulator import FrameWriter

    seeds = []
    for scenario in ("motion", "buttons", "garbage"):
        for fmt in ("6df2", "6df"):
            writer = FrameWriter(scenario, 60.0, 3, 2, 12, fmt, 2, 1)
            seeds += [writer.frame(n).encode("ascii") for n in (1, 3, 7)]
    eye = "[1 0 0 0 1 0 0 0 1]"
    seeds.append(
        f"fr 9\r\nts 1.5\r\n6dcal 4\r\n6di 1 [2 2 0.5][1000 0 0]{eye}\r\n"
        f"6dmt 1 [0 0.8 5][0 0 10]{eye}\r\n6dmt2 1 1 [1 0.7 3 2.5][0 0 20]{eye}[6][1 2 3 4 5 6]\r\n"
        f"glcal 1\r\ngl 1 [0 1.0 0 1][0 0 0]{eye}[10 0 0]{eye}[5 30 20 15 10 25]\r\n".encode()
    )
    return seeds


_DTRACK_TAGS = [
    "fr",
    "ts",
    "6dcal",
    "6d",
    "6di",
    "6df",
    "6df2",
    "6dmt",
    "6dmt2",
    "glcal",
    "gl",
    "3d",
    "xx",
]
_DTRACK_ODD = [
    "3000000",
    "2000000",
    "9" * 30,
    "1" * 4400,
    "-0",
    "1e309",
    ".5",
    "nan",
    "-1",
    "127",
    "128",
]


def _dtrack_number(rng: random.Random) -> str:
    kind = rng.randrange(4)
    if kind == 0:
        return str(rng.randint(-5, 300))
    if kind == 1:
        return repr(rng.uniform(-2000, 2000))
    if kind == 2:
        return str(rng.randint(0, 3))
    return rng.choice(_DTRACK_ODD)


def _dtrack_lines(rng: random.Random) -> bytes:
    """A datagram of DTrack-like lines: known tags, header numbers and blocks."""
    lines = []
    for _ in range(rng.randint(1, 6)):
        header = [_dtrack_number(rng) for _ in range(rng.randint(0, 3))]
        blocks = [
            [_dtrack_number(rng) for _ in range(rng.randint(0, 14))]
            for _ in range(rng.randint(0, 8))
        ]
        text = " ".join([rng.choice(_DTRACK_TAGS), *header])
        lines.append(text + "".join("[" + " ".join(b) + "]" for b in blocks))
    return ("\r\n".join(lines) + "\r\n").encode()


@target(
    "dtrack.datagram", seeds=_dtrack_seeds, grammar=_dtrack_lines, examples=120, driver="DTrack_drv"
)
def _dtrack(data: bytes) -> None:
    from DTrack_drv.standalone import DEFAULT_LIMITS, DTrackUnits, parse_frame, parse_frames

    # As received: alone, in a batch with good datagrams (whose numbers are converted
    # together), and cut short as by a small receive buffer.
    good = _dtrack_seeds()[0]
    batch = parse_frames([good, data, good, data[: len(data) // 2]], [False, False, False, True])
    alone = parse_frame(data)
    general = parse_frame(data, fast=False)
    assert (alone is None) == (general is None)
    if alone is not None and general is not None:
        assert alone.bad_lines == general.bad_lines
        assert (
            alone.frame == general.frame
            and alone.bodies.ids.tolist() == general.bodies.ids.tolist()
        )
        assert len(alone.flysticks) == len(general.flysticks)
    units = DTrackUnits(extra_units=True)
    units.merge([f for f in batch if f is not None])
    if alone is not None:
        units.update(alone)
    assert max(units.counts) <= DEFAULT_LIMITS.objects
    assert len(units.digital()) <= 2 * DEFAULT_LIMITS.objects * DEFAULT_LIMITS.buttons


# -- MotionStar -----------------------------------------------------------------------------------


def _motionstar_seeds() -> list[bytes]:
    from MotionStar_drv.standalone import (
        DATA_PACKET_MULTI,
        FORMAT_WORDS,
        RSP_GET_STATUS,
        Header,
    )

    seeds = []
    payload = bytearray()
    for address, (code, words) in enumerate(FORMAT_WORDS.items(), start=1):
        payload += bytes([address | 0x80, words << 4 | int(code)])
        payload += struct.pack(f">{words}h", *range(-words * 1000, words * 1000, 2000)[:words])
        payload += bytes([1, 0])
    seeds.append(Header(7, DATA_PACKET_MULTI, length=len(payload)).pack() + payload)
    for code, words in FORMAT_WORDS.items():
        record = bytes([1, words << 4 | int(code)]) + struct.pack(f">{words}h", *([16000] * words))
        seeds.append(Header(8, DATA_PACKET_MULTI, length=len(record)).pack() + record)
    status = bytes([0, 0, 3, 1, 1]) + b"086100" + bytes([1, 3, 1, 3, 0]) + bytes([0xE0, 0xE0, 0x90])
    seeds.append(Header(2, RSP_GET_STATUS, length=len(status)).pack() + status)
    bird = bytearray(70)
    bird[6], bird[8], bird[9] = 0x64, 0x00, 144
    seeds.append(Header(3, RSP_GET_STATUS, xtype=1, length=70).pack() + bytes(bird))
    return seeds


@target("motionstar.packet", seeds=_motionstar_seeds, examples=100, driver="MotionStar_drv")
def _motionstar(data: bytes) -> None:
    from MotionStar_drv.standalone import (
        BIRD_STATUS_SIZE,
        HEADER,
        BirdStatus,
        Header,
        MotionStarCommandError,
        SystemStatus,
        carries_pose,
        decode_record,
        parse_records,
    )

    if len(data) < HEADER.size:
        return
    header = Header.unpack(data)
    header.plausible()
    payload = data[HEADER.size : HEADER.size + header.length]
    records = parse_records(payload)
    for unit, record in enumerate(records or ()):
        if carries_pose(record.format_code):  # the rest is stepped over, as the driver does
            sample = decode_record(record, unit, float(header.milliseconds & 0xFFF))
            assert sample.matrix.shape == (4, 4)
    try:
        status = SystemStatus.parse(payload)
    except MotionStarCommandError:
        pass
    else:
        assert status.measurement_rate >= 0 and len(status.devices) == status.flock_number
        status.with_rate(status.measurement_rate)
    if len(payload) >= BIRD_STATUS_SIZE:
        bird = BirdStatus(1, payload[:BIRD_STATUS_SIZE])
        assert 0 <= bird.full_scale < 4096
        bird.configured(4, bird.report_rate, bird.hemisphere)


# -- PinchGlove -----------------------------------------------------------------------------------


def _pinch_seeds() -> list[bytes]:
    from PinchGlove_drv.emulator import encode_frame, touch_steps

    seeds = []
    for scenario in ("touches", "motion"):
        steps = list(itertools.islice(touch_steps(scenario), 8))
        seeds.append(b"".join(encode_frame(g, 100 + i) for i, g in enumerate(steps)))
        seeds.append(b"".join(encode_frame(g, None) for g in steps))
    seeds.append(b"\x82version 1\x8f\x81\x01\x02\x00\x05\x8f\x80\x8f")
    return seeds


@target("pinchglove.stream", seeds=_pinch_seeds, examples=100, driver="PinchGlove_drv")
def _pinch(data: bytes) -> None:
    import serial
    from PinchGlove_drv.standalone import DIGITAL_UNITS, PinchGlove, _SerialLink, decode_frame

    data = data[:4000]  # pyserial's loop:// holds 4096 bytes; a write beyond that waits
    port = serial.serial_for_url("loop://", timeout=0)
    try:
        glove = PinchGlove(port, read_timeout=0.0, sample_timeout=0.0, poll_interval=0.0)
        glove._link = _SerialLink(port, 0.0)  # the stream side only: no handshake with loop://
        port.write(data)
        frames = 0
        while glove.sample() is not None:
            frames += 1
            assert frames <= len(data)
            assert len(glove.last.digital) == DIGITAL_UNITS
        assert glove.frames == frames
    finally:
        port.close()
    for start in (0x80, 0x81):
        frame = decode_frame(start, data[:64])
        assert frame is None or len(frame.digital) == DIGITAL_UNITS


# -- IS-900 ---------------------------------------------------------------------------------------


def _is900_seeds() -> list[bytes]:
    from IS900_drv.emulator import GARBAGE_CHUNKS, controls, encode_record, pose

    def records(scenario: str) -> bytes:
        out = b""
        for step in range(8):
            for station in (0, 1):
                buttons, analog = controls(scenario, station, step)
                out += encode_record(station, *pose(scenario, station, step), buttons, analog)
        return out

    return [records("motion"), records("buttons"), b"".join(GARBAGE_CHUNKS) + records("motion")]


@target("is900.records", seeds=_is900_seeds, examples=100, driver="IS900_drv")
def _is900(data: bytes) -> None:
    from IS900_drv.standalone import RECORD_SIZE, RecordScanner

    scanner = RecordScanner(stations=frozenset({0, 1, 2}))
    got = []
    for start in range(0, len(data), 97):  # arbitrary chunks, as reads split the line
        got += scanner.feed(data[start : start + 97])
        assert len(scanner.buffer) < RECORD_SIZE
    assert scanner.records == len(got) <= len(data) // RECORD_SIZE
    assert scanner.skipped_bytes + RECORD_SIZE * len(got) + len(scanner.buffer) == len(data)
    assert scanner.bad_records <= scanner.skipped_bytes
    for record in got:
        assert record.station in (0, 1, 2) and set(record.digital) <= {0, 1}
        assert all(abs(v) <= 1e5 for v in record.position) and all(
            0 <= a < 256 for a in record.analog
        )


# -- Flock of Birds ---------------------------------------------------------------------------------


def _flock_seeds() -> list[bytes]:
    from Flock_drv.emulator import GARBAGE_CHUNKS, encode_record, pose

    def frames(scenario: str, fmt: int) -> bytes:
        return b"".join(
            encode_record(fmt, *pose(scenario, bird, step), 3.0, bird + 1)
            for step in range(8)
            for bird in (0, 1)
        )

    return [
        frames("motion", ord("]")),
        frames("buttons", ord("]")),
        b"".join(GARBAGE_CHUNKS) + frames("motion", ord("]")),
    ]


@target("flock.records", seeds=_flock_seeds, examples=100, driver="Flock_drv")
def _flock(data: bytes) -> None:
    from Flock_drv.standalone import POS_QUATERNION, RecordScanner, record_size

    scanner = RecordScanner(POS_QUATERNION, 3.0, True, frozenset({1, 2}))
    size = record_size(POS_QUATERNION, True)
    got = []
    for start in range(0, len(data), 97):  # arbitrary chunks, as reads split the line
        got += scanner.feed(data[start : start + 97])
        assert len(scanner.buffer) < size
    assert scanner.records == len(got) <= len(data) // size
    assert scanner.skipped_bytes + size * len(got) + len(scanner.buffer) == len(data)
    assert scanner.bad_records <= scanner.skipped_bytes
    for record in got:
        assert record.address in (1, 2) and all(abs(v) <= 3.0 for v in record.position)
        assert record.quaternion is not None and all(abs(v) <= 1.0 for v in record.quaternion)


# -- Immersion IBox -------------------------------------------------------------------------------


def _ibox_seeds() -> list[bytes]:
    from IBox_drv.emulator import GARBAGE_CHUNKS, controls, encode_packet

    def packets(scenario: str) -> bytes:
        return b"".join(encode_packet(0x08, *controls(scenario, step)) for step in range(12))

    return [packets("motion"), packets("buttons"), b"".join(GARBAGE_CHUNKS) + packets("motion")]


@target("ibox.packets", seeds=_ibox_seeds, examples=100, driver="IBox_drv")
def _ibox(data: bytes) -> None:
    from IBox_drv.standalone import PacketScanner, packet_size

    scanner = PacketScanner()
    size = packet_size(scanner.query)
    got = []
    for start in range(0, len(data), 97):  # arbitrary chunks, as reads split the line
        got += scanner.feed(data[start : start + 97])
        assert len(scanner.buffer) < size
    assert scanner.records == len(got) <= len(data) // size
    assert scanner.skipped_bytes + size * len(got) + len(scanner.buffer) == len(data)
    assert scanner.bad_records <= scanner.skipped_bytes
    for packet in got:
        assert set(packet.buttons) <= {0, 1} and len(packet.analog) == 4
        assert all(0 <= a <= 255 for a in packet.analog)


# -- Ascension Wanda ------------------------------------------------------------------------------


def _wanda_seeds() -> list[bytes]:
    from Wanda_drv.emulator import GARBAGE_CHUNKS, controls, encode_packet

    def packets(scenario: str) -> bytes:
        return b"".join(encode_packet(*controls(scenario, step)) for step in range(30))

    return [packets("motion"), packets("buttons"), b"".join(GARBAGE_CHUNKS) + packets("motion")]


@target("wanda.packets", seeds=_wanda_seeds, examples=100, driver="Wanda_drv")
def _wanda(data: bytes) -> None:
    from Wanda_drv.standalone import LIMIT, PacketScanner

    scanner = PacketScanner()
    got = []
    for start in range(0, len(data), 97):  # arbitrary chunks, as reads split the line
        got += scanner.feed(data[start : start + 97])
        assert len(scanner.buffer) <= 3
    got += scanner.feed(b"", quiet=True)
    assert not scanner.buffer or len(scanner.buffer) < 3
    assert scanner.records == len(got) <= len(data) // 3
    assert scanner.bad_records <= scanner.skipped_bytes <= len(data)
    for packet in got:
        assert set(packet.buttons) <= {0, 1} and all(-LIMIT <= a <= LIMIT for a in packet.axes)


# -- SpaceBall / SpaceMouse -----------------------------------------------------------------------


def _spaceball_seeds() -> list[bytes]:
    from SpaceBall_drv.emulator import (
        MODELS,
        button_pattern,
        encode_axes,
        encode_buttons,
        motion_axes,
    )

    seeds = []
    for model in MODELS:
        records = [encode_axes(model, motion_axes(model, i), timer=i) for i in range(6)]
        records += [encode_buttons(model, button_pattern(i)) for i in range(6)]
        seeds.append(b"".join(records))
    return seeds


@target("spaceball.records", seeds=_spaceball_seeds, examples=100, driver="SpaceBall_drv")
def _spaceball(data: bytes) -> None:
    from SpaceBall_drv.standalone import AXES, BUTTONS, MAX_RECORD, MODELS, RecordSplitter

    for model in MODELS:
        splitter = RecordSplitter(model)
        samples = splitter.feed(data[: len(data) // 2]) + splitter.feed(data[len(data) // 2 :])
        assert len(splitter._partial) <= MAX_RECORD
        assert splitter.records == len(samples) <= data.count(b"\r")
        for sample in samples:
            if sample.axes is not None:
                assert len(sample.axes) == AXES and all(-32768 <= a <= 32768 for a in sample.axes)
            else:
                assert len(sample.buttons) == BUTTONS and set(sample.buttons) <= {0, 1}


# -- Fastrak --------------------------------------------------------------------------------------


def _fastrak_seeds() -> list[bytes]:
    from Fastrak_drv.emulator import GARBAGE_CHUNKS, encode_record, pose, stylus

    def records(scenario: str) -> bytes:
        return b"".join(
            encode_record(s, *pose(scenario, s, i), stylus(scenario, s, i))
            for i in range(8)
            for s in (1, 2)
        )

    return [records("motion"), records("buttons"), b"".join(GARBAGE_CHUNKS) + records("motion")]


@target("fastrak.records", seeds=_fastrak_seeds, examples=100, driver="Fastrak_drv")
def _fastrak(data: bytes) -> None:
    from Fastrak_drv.standalone import RECORD_SIZE, STATIONS, RecordScanner

    scanner = RecordScanner()
    got = []
    for start in range(0, len(data), 101):
        got += scanner.feed(data[start : start + 101])
        assert len(scanner.buffer) < RECORD_SIZE
    assert scanner.records == len(got)
    assert scanner.skipped_bytes + RECORD_SIZE * len(got) + len(scanner.buffer) == len(data)
    for record in got:
        assert 1 <= record.station <= STATIONS and record.stylus in (0, 1)
        assert record.matrix().shape == (4, 4)


# -- 5DT DataGlove --------------------------------------------------------------------------------


def _dataglove_seeds() -> list[bytes]:
    from DataGlove_drv.emulator import GARBAGE, encode_packet, pose

    motion = b"".join(encode_packet(pose("motion", i)) for i in range(12))
    return [motion, b"".join(g + encode_packet(pose("buttons", i)) for i, g in enumerate(GARBAGE))]


@target("dataglove.packets", seeds=_dataglove_seeds, examples=100, driver="DataGlove_drv")
def _dataglove(data: bytes) -> None:
    from DataGlove_drv.standalone import NO_GESTURE, PACKET_SIZE, PacketScanner

    scanner = PacketScanner()
    got = []
    for start in range(0, len(data), 13):  # arbitrary chunks, as reads split the line
        got += scanner.feed(data[start : start + 13])
        assert len(scanner.buffer) <= PACKET_SIZE
    assert scanner.records == len(got) <= len(data) // PACKET_SIZE
    taken = len(data) - scanner.skipped_bytes - len(scanner.buffer)  # 9 or 10 bytes a packet
    assert PACKET_SIZE * len(got) <= taken <= (PACKET_SIZE + 1) * len(got)
    assert scanner.bad_records <= scanner.skipped_bytes
    for sample in got:
        assert all(0.0 <= f <= 1.0 for f in sample.flexure) and 0 <= sample.pitch <= 180
        assert 0 <= sample.gesture <= NO_GESTURE and 0 <= sample.capability <= 0xFF
        assert sample.capability != 0x80  # a header is never a packet's 10th byte


# -- US Digital SEI encoders ----------------------------------------------------------------------


def _encoder_seeds() -> list[bytes]:
    from SerialEncoder_drv.emulator import JUNK, encode_reply, table_position

    replies = [
        encode_reply(a, table_position("motion", i)[a - 1]) for i in range(6) for a in (1, 2)
    ]
    return [b"".join(replies), b"".join(j + r for j, r in zip(JUNK * 4, replies, strict=False))]


@target("serialencoder.replies", seeds=_encoder_seeds, examples=100, driver="SerialEncoder_drv")
def _encoder(data: bytes) -> None:
    import math

    from SerialEncoder_drv.standalone import MAX_POSITION, SerialEncoderBus

    class Bus:
        """A pyserial-like port: each command is answered by the next piece of ``data``."""

        timeout = 0.0

        def __init__(self) -> None:
            self.pending = bytearray()
            self.rest = memoryview(data)

        @property
        def in_waiting(self) -> int:
            return len(self.pending)

        def read(self, size: int = 1) -> bytes:
            out = bytes(self.pending[:size])
            del self.pending[:size]
            return out

        def write(self, command: bytes) -> None:
            cut = 1 + (command[0] * 7 + len(self.rest)) % 11
            self.pending += self.rest[:cut]
            self.rest = self.rest[cut:]

        def flush(self) -> None:
            pass

    port = Bus()
    bus = SerialEncoderBus(port, reply_timeout=0.001, poll_interval=0.0)
    bus.open()
    for _ in range(len(data) // 5 + 2):
        value = bus.position(1)
        assert value is None or (math.isfinite(value) and abs(value) <= MAX_POSITION)
    c = bus.counters
    assert c.records + c.bad_records + c.timeouts >= len(data) // 5 + 2
    consumed = len(data) - len(port.rest)
    assert c.skipped_bytes + 5 * c.records <= consumed  # every byte counted once at most


# -- Logitech 3D mouse ----------------------------------------------------------------------------


def _three_d_mouse_seeds() -> list[bytes]:
    from ThreeDMouse_drv.emulator import GARBAGE_CHUNKS, encode_report, state

    def reports(scenario: str) -> bytes:
        return b"".join(encode_report(*state(scenario, i)) for i in range(12))

    return [reports("motion"), reports("buttons"), b"".join(GARBAGE_CHUNKS) + reports("motion")]


@target("three_d_mouse.reports", seeds=_three_d_mouse_seeds, examples=100, driver="ThreeDMouse_drv")
def _three_d_mouse(data: bytes) -> None:
    from ThreeDMouse_drv.standalone import REPORT_SIZE, ReportScanner

    scanner = ReportScanner()
    got = []
    for start in range(0, len(data), 37):
        got += scanner.feed(data[start : start + 37])
        assert len(scanner.buffer) < REPORT_SIZE
    assert scanner.records == len(got)
    assert scanner.skipped_bytes + REPORT_SIZE * len(got) + len(scanner.buffer) == len(data)
    for report in got:
        assert set(report.buttons) <= {0, 1} and all(0 <= a <= 360 for a in report.angles)
        assert all(abs(v) <= (1 << 20) / 1000 * 0.0254 for v in report.position)


# -- 5DT Data Glove Ultra Wireless ----------------------------------------------------------------


def _ultraglove_seeds() -> list[bytes]:
    from DataGloveUltraWireless_drv.emulator import GARBAGE, encode_record, readings

    records = [encode_record(i % 2, readings("motion", i % 2, i)) for i in range(8)]
    return [b"".join(records), b"".join(g + r for g, r in zip(GARBAGE * 2, records, strict=True))]


@target(
    "ultraglove.records", seeds=_ultraglove_seeds, examples=100, driver="DataGloveUltraWireless_drv"
)
def _ultraglove(data: bytes) -> None:
    from DataGloveUltraWireless_drv.standalone import (
        RECORD_SIZE,
        SENSORS,
        AutoRange,
        RecordScanner,
        gesture,
    )

    scanner, ranged = RecordScanner(), AutoRange(auto_reset=True)
    got = []
    for start in range(0, len(data), 17):  # arbitrary chunks, as reads split the line
        got += scanner.feed(data[start : start + 17])
        assert len(scanner.buffer) < RECORD_SIZE
    assert scanner.records == len(got) <= len(data) // RECORD_SIZE
    assert scanner.skipped_bytes + RECORD_SIZE * len(got) + len(scanner.buffer) == len(data)
    for record in got:
        assert record.port in (0, 1) and len(record.raw) == SENSORS
        scaled = ranged.scale(record)
        number = gesture(scaled)
        assert all(v is None or 0.0 <= v <= 1.0 for v in scaled) and -1 <= number <= 15
        ranged.after_gesture(record, number)


# -- Linux joystick -------------------------------------------------------------------------------


def _joystick_seeds() -> list[bytes]:
    from LinuxJoydev_drv.standalone import JoystickEvent

    burst = [JoystickEvent(0, 0, 0x81, i) for i in range(12)]
    burst += [JoystickEvent(0, 0, 0x82, i) for i in range(6)]
    live = [JoystickEvent(10 + i, (i * 5000) % 32767, 0x02, i % 6) for i in range(20)]
    live += [JoystickEvent(40 + i, i % 2, 0x01, i % 12) for i in range(20)]
    return [
        b"".join(e.pack() for e in burst + live),
        b"".join(e.pack() for e in live),
        b"".join(e.pack() for e in burst)[3:],
    ]


# -- OptiTrack (NatNet) ---------------------------------------------------------------------------


_NATNET_VERSIONS = ((2, 0), (2, 5), (2, 7), (3, 0), (4, 1))


def _natnet_seeds() -> list[bytes]:
    from OptiTrack_drv.emulator import FrameWriter, encode_frame

    return [
        FrameWriter("motion", 3, 4, version=(2, 0)).frame(5),
        FrameWriter("buttons", 4, 0, version=(3, 0)).frame(1),
        FrameWriter("motion", 2, 3, version=(4, 1)).frame(7),
        encode_frame(
            1, [(1, (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0))], [(1.0, 2.0, 3.0)], version=(2, 5)
        ),
    ]


@target("natnet.frame", seeds=_natnet_seeds, examples=100, driver="OptiTrack_drv")
def _natnet(data: bytes) -> None:
    from OptiTrack_drv.standalone import DEFAULT_LIMITS, NatNetReceiver, NatNetUnits

    for version in _NATNET_VERSIONS:  # each datagram is one good frame or one bad datagram
        receiver = NatNetReceiver(0, group=None, version=version)
        frames = receiver.handle(data, ("127.0.0.1", 1510))
        counted = receiver.frames + receiver.bad_datagrams + receiver.other_messages
        assert counted + receiver.server_infos == 1
        for frame in frames:
            assert len(frame.bodies) <= DEFAULT_LIMITS.rigid_bodies
            assert len(frame.markers) <= DEFAULT_LIMITS.markers
            units = NatNetUnits([1, 2, 1 << 31 - 1], [1000, 1199, 5])
            assert units.update(frame).shape == (6, 4, 4)


# -- TUIO (OSC through TUIO_drv.osc) ------------------------------------------------------------


def _tuio_seeds() -> list[bytes]:
    from TUIO_drv.emulator import frame_bundle, message, osc_bundle

    return [
        frame_bundle(3, 4, "motion"),
        frame_bundle(5, 3, "buttons"),
        message("set", 1, 0.5, 0.5, 0.0, 0.0, 0.0),
        osc_bundle(osc_bundle(frame_bundle(7, 2, "motion", source=1))),
    ]


@target("tuio.datagram", seeds=_tuio_seeds, examples=100, driver="TUIO_drv")
def _tuio(data: bytes) -> None:
    from TUIO_drv.standalone import TuioReceiver

    receiver = TuioReceiver(0, 4)
    good = _tuio_seeds()[0]
    for datagram in (good, data, data[: len(data) // 2]):
        receiver.feed(datagram)
    slots = receiver.slots
    assert len(slots.digital()) == 4 and len(slots.analog()) == 8
    assert set(slots.digital()) <= {0, 1} and slots.sessions <= 4
    ledger = receiver.ledger
    assert ledger.decoded_count + ledger.bad_count == 3  # every datagram judged, once


# -- Elexol Ether I/O 24 -------------------------------------------------------------------------


def _ether24_seeds() -> list[bytes]:
    return [b"A\x05", b"B\xff", b"C\x00", b"IO24\x00\x0a\xbc\x12\x34\x56\x01\x05"]


@target("ether24.reply", seeds=_ether24_seeds, examples=100, driver="ElexolEther24_drv")
def _ether24(data: bytes) -> None:
    from ElexolEther24_drv.standalone import Ether24Board, lines

    board = Ether24Board("127.0.0.1")
    for piece in (data, data[:2], data[2:4]):
        port = board._classify(piece)
        assert port is None or 0 <= port < 3
    assert board.replies + board.bad_replies == 3
    assert set(lines(board._values, [0, 0xFF, 0x0F])) <= {0, 1}


@target("joystick.events", seeds=_joystick_seeds, examples=100, driver="LinuxJoydev_drv")
def _joystick(data: bytes) -> None:
    from LinuxJoydev_drv.standalone import (
        EVENT_SIZE,
        EventDecoder,
        JoystickDisconnected,
        LinuxJoydevStandalone,
    )

    decoder = EventDecoder(clock=lambda: 0.0)
    events = []
    for at in range(0, len(data), 37):  # in pieces that cut records
        events += decoder.feed(data[at : at + 37])
    decoder.finish()
    assert len(events) * EVENT_SIZE + decoder.skipped_bytes <= len(data)
    assert decoder.num_buttons <= 256 and decoder.num_axes <= 256
    # the device side: through a pipe, until the end of the stream
    read_end, write_end = os.pipe()
    try:
        os.write(write_end, data[:60000])
        os.close(write_end)
        write_end = -1
        with os.fdopen(read_end, "rb", buffering=0, closefd=False) as stream:
            device = LinuxJoydevStandalone(stream, connect_timeout=0.0)
            device.open()
            try:
                for _ in range(len(data) + 2):
                    sample = device.sample()
                    assert len(sample.buttons) <= 256 and len(sample.axes) <= 256
            except JoystickDisconnected:
                pass
            else:
                raise AssertionError("the stream never ended")
            finally:
                device.close()
    finally:
        os.close(read_end)
        if write_end >= 0:
            os.close(write_end)


# -- trackd shared memory -------------------------------------------------------------------------


def _trackd_seeds() -> list[bytes]:
    from Trackd_drv.emulator import sensor_pose
    from Trackd_drv.standalone import encode_controller, encode_tracker

    return [
        encode_tracker([sensor_pose(3, i) for i in range(16)], (1, 2)),
        encode_tracker([sensor_pose(0, 0)], claimed=5),
        encode_controller([1, 0, 1, 0], [0.5, -0.5], (1, 2)),
        encode_controller([1], [], claimed_buttons=70000),
    ]


@target("trackd.segment", seeds=_trackd_seeds, examples=100, driver="Trackd_drv")
def _trackd(data: bytes) -> None:
    from Trackd_drv.standalone import MAX_UNITS, BadSegment, decode_controller, decode_tracker

    for decode in (decode_tracker, decode_controller):
        try:
            state = decode(data)
        except BadSegment:
            continue
        units = (state.sensors,) if hasattr(state, "sensors") else (state.buttons, state.valuators)
        assert all(len(u) <= MAX_UNITS for u in units)
        assert sum(len(u) for u in units) * 4 <= len(data)


# -- SDL joystick hats --------------------------------------------------------------------------


def _sdl_hat_seeds() -> list[bytes]:
    from SdlJoystick_drv.emulator import HAT_STEPS, IMPOSSIBLE_HATS

    return [
        bytes([2, *HAT_STEPS, 0]),
        bytes([1, *IMPOSSIBLE_HATS, 4, 4, 5]),
        bytes([4, 255, 0, 3, 12]),
    ]


@target("sdl_joystick.hats", seeds=_sdl_hat_seeds, examples=100, driver="SdlJoystick_drv")
def _sdl_hats(data: bytes) -> None:
    """What SDL hands the driver is polled state, not bytes; its one check of hostile values
    is of hat bits (SDL passes any byte a virtual or broken device reports). The first byte
    is the number of hats, the rest successive polls of them."""
    from SdlJoystick_drv.standalone import VALID_HATS, HatChecker

    if not data:
        return
    width = data[0] % 17
    checker, impossible = HatChecker(), 0
    polls = [tuple(data[i : i + width]) for i in range(1, len(data) - width + 1, max(width, 1))]
    for poll in polls if width else [()] * len(data):
        checked = checker.check(poll)
        assert len(checked) == len(poll) and set(checked) <= VALID_HATS
        assert all(c == p for c, p in zip(checked, poll, strict=True) if p in VALID_HATS)
        impossible += sum(p not in VALID_HATS for p in poll)
    assert checker.bad <= impossible


# -- JCCL files -----------------------------------------------------------------------------------


def _jccl_seeds() -> list[bytes]:
    files = sorted(CORPUS.rglob("*.jconf")) + sorted(CORPUS.rglob("*.jdef"))
    files += (
        sorted((REPO / "examples").glob("*.jconf"))
        + sorted((REPO / "definitions").glob("*.jdef"))[:20]
    )
    assert files, f"no corpus at {CORPUS}"
    return [f.read_bytes() for f in files if f.stat().st_size <= MAX_INPUT]


@functools.cache
def _repository():
    from gadgetctl.jccl.repository import default_repository

    return default_repository()


@functools.cache
def _element_types() -> list[tuple[str, int, list]]:
    """(type, newest version, effective property definitions) of every bundled definition."""
    repo = _repository()
    types = []
    for definition in repo.all_newest():
        props = [p.definition for p in repo.effective_properties(definition.name)]
        types.append((definition.name, definition.version, props))
    return sorted(types, key=lambda t: t[0])


_XML_ODD = ["1e999", "-1e999", "NaN", "inf", "9" * 5000, "-0", "0x1F", " 1 ", "", "tRuE", "2",
            "&#0;", "&lt;", "\u202e", "${UNDEFINED}", "$(HOME)/x", "..", "/", "a" * 300]  # fmt: skip


def _jccl_value(rng: random.Random, prop, names: list[str]) -> str:
    from gadgetctl.jccl.definitions import ValueType

    kind = rng.randrange(6)
    if kind == 0:
        return rng.choice(_XML_ODD)
    if prop.enumeration is not None and prop.enumeration.choices and kind == 1:
        choice = rng.choice(prop.enumeration.choices)
        return str(rng.choice([choice.label, choice.value, choice.label.upper()]))
    if prop.valuetype is ValueType.BOOLEAN:
        return rng.choice(["true", "false", "1", "0", "yes", "TRUE"])
    if prop.valuetype is ValueType.INTEGER:
        return str(rng.choice([rng.randint(-5, 300), 2**31, -(2**63), 10**30]))
    if prop.valuetype is ValueType.FLOAT:
        return repr(rng.choice([rng.uniform(-1e3, 1e3), 1e308, -0.0, 5e-324]))
    if prop.valuetype is ValueType.POINTER and names:
        return rng.choice([*names, "missing", ""])
    return rng.choice(["x", "Wand", "/dev/ttyS0", "localhost", "\t", "a b", "é"])


def _jccl_configuration(rng: random.Random) -> bytes:
    """A configuration of bundled element types with values of every kind, good and bad:
    pointers to each other, embedded elements, unknown properties, odd counts."""
    from xml.sax.saxutils import escape, quoteattr

    types = _element_types()
    names = [f"E{i}" for i in range(rng.randint(1, 8))]
    out = ['<?xml version="1.0" encoding="UTF-8"?>',
           f'<?org-vrjuggler-jccl-settings configuration.version="{rng.choice(["3.0", "3.0", "2.0", "x"])}"?>',
           '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="fuzz">']  # fmt: skip
    if rng.random() < 0.2:
        out.append(
            f"<include>{escape(rng.choice(['other.jconf', 'E0.jconf', '', '../x.jconf']))}</include>"
        )
    out.append("<elements>")

    def element(name: str, depth: int) -> str:
        type_name, version, props = rng.choice(types)
        version = rng.choice([version, version, 1, 0, 99])
        body = []
        for prop in rng.sample(props, min(len(props), rng.randint(0, 6))):
            for _ in range(rng.choice([1, 1, 1, 0, 2, 5])):
                if prop.valuetype.value == "configelement" and depth < 2:
                    body.append(
                        f"<{prop.name}>{element(f'{name}.{prop.name}', depth + 1)}</{prop.name}>"
                    )
                else:
                    body.append(
                        f"<{prop.name}>{escape(_jccl_value(rng, prop, names))}</{prop.name}>"
                    )
        if rng.random() < 0.1:
            body.append("<no_such_property>1</no_such_property>")
        return (
            f'<{type_name} name={quoteattr(name)} version="{version}">{"".join(body)}</{type_name}>'
        )

    out += [element(name, 0) for name in names]
    out += ["</elements>", "</configuration>"]
    return "\n".join(out).encode("utf-8")


@target("jccl.document", seeds=_jccl_seeds, grammar=_jccl_configuration, examples=40)
def _jccl_document(data: bytes) -> None:
    from gadgetctl.jccl.configcheck import check_documents
    from gadgetctl.jccl.defchecks import check_cycles, check_definition
    from gadgetctl.jccl.defparser import read_definition
    from gadgetctl.jccl.xmlload import FileKind, parse_bytes
    from gadgetctl.validate import ValidateOptions, check_document

    for name in ("fuzz.jconf", "fuzz.jdef"):
        path = _as_file(data, name)
        doc = parse_bytes(data, str(path), FileKind.UNKNOWN)
        check_document(doc, ValidateOptions())
        if doc.root is None:
            assert doc.diagnostics
            continue
        if doc.kind is FileKind.DEFINITION:
            definition = read_definition(doc)
            if definition is not None and definition.name:
                repo = _repository().overlay([definition])
                check_definition(definition, definition.order, repo)
                check_cycles([definition], repo)
        check_documents([doc], _repository(), environ={}, plugin_definitions=None)


@target("jccl.upgrade", seeds=_jccl_seeds, grammar=_jccl_configuration, examples=25)
def _jccl_upgrade(data: bytes) -> None:
    from gadgetctl.jccl.upgrade import upgrade_bytes

    result = upgrade_bytes(_workdir() / "fuzz.jconf", data, _repository(), environ={})
    assert result is not None


@target("lsp.document", seeds=_jccl_seeds, grammar=_jccl_configuration, examples=25)
def _lsp_document(data: bytes) -> None:
    """What the language server does with a document as an editor holds it: validate's
    findings, then completion, hover, navigation and fixes at positions across it."""
    from gadgetctl.lsp import actions, completion, hover, navigation
    from gadgetctl.lsp.analysis import Engine
    from gadgetctl.lsp.findings import findings
    from gadgetctl.lsp.text import LineIndex

    text = data.decode("utf-8", errors="replace")
    for name in ("fuzz.jconf", "fuzz.jdef"):
        path = _as_file(data, name)
        engine = Engine()
        engine.set_text(path, text)
        found = engine.diagnose(path)
        model = engine.good_model(path)
        for offset in sorted({len(text) * k // 7 for k in range(8)}):
            completion.complete(model, text, offset)
            hover.hover(model, text, offset, found)
            navigation.definition(model, text, offset)
            navigation.references(model, text, offset, True)
            navigation.rename_range(model, text, offset)
        assert len(navigation.symbols(text)) <= navigation.MAX_SYMBOLS
        navigation.folding(text)
        problems = [
            actions.Problem(f.diagnostic.code, f.start, f.end)
            for f in findings(found, LineIndex(text, utf16=False))
        ]
        actions.actions(model, text, problems[:20])


# -- recordings -----------------------------------------------------------------------------------


def _recording_seeds() -> list[bytes]:
    from gadgetctl.monitor.recording import Recorder
    from gadgetctl.monitor.records import FrameDevice, FrameRecord, SampleRecord, StatusRecord

    path = _workdir() / "seed.gadgetrec"
    path.unlink(missing_ok=True)
    info = {
        "elements": {
            "Wave": {
                "element": "device",
                "type": "waveform_device",
                "kinds": ["analog", "digital", "position"],
                "units": {"analog": 2},
            }
        }
    }
    with Recorder(path, info) as recorder:
        recorder.write_status(
            StatusRecord(0.5, "Wave", "device", "waveform_device", "running", None)
        )
        for n in range(6):
            t = 1.0 + n / 60
            recorder.write_sample(SampleRecord("Wave", "analog", n % 2, t, 0.25 * n, 0.25 * n))
            recorder.write_sample(SampleRecord("Wave", "digital", 0, t, n % 2, n % 2))
            pose = [
                [1.0, 0.0, 0.0, n / 10],
                [0.0, 1.0, 0.0, 0.0],
                [0.0, 0.0, 1.0, 0.0],
                [0.0, 0.0, 0.0, 1.0],
            ]
            recorder.write_sample(SampleRecord("Wave", "position", 0, t, pose, pose))
            recorder.write_frame(FrameRecord(n, t, {"Wave": FrameDevice(3, {"analog": {0: 0.5}})}))
        recorder.write_marker("halfway", 1.05)
        recorder.write_stats({"Wave": {"count": 18, "dropped": 0}})
    return [path.read_bytes()]


def _recording_lines(rng: random.Random) -> bytes:
    """A recording whose records have the known fields with values of any JSON type."""
    import json

    def value(depth: int = 0) -> object:
        kind = rng.randrange(9 if depth < 2 else 6)
        return [
            lambda: rng.randint(-(2**70), 2**70),
            lambda: rng.choice([0, 1, -1, 2**31, 10**9]),
            lambda: rng.uniform(-1e6, 1e6),
            lambda: rng.choice(["x", "", "Wave", "analog", "position", "header", "1.5", "device"]),
            lambda: rng.choice([True, False, None]),
            lambda: rng.choice([1e308, -1e308]),
            lambda: [value(depth + 1) for _ in range(rng.randint(0, 4))],
            lambda: {rng.choice(_RECORD_KEYS): value(depth + 1) for _ in range(rng.randint(0, 4))},
            lambda: {str(rng.randint(-3, 300)): value(depth + 1) for _ in range(rng.randint(0, 3))},
        ][kind]()

    header = {"v": 1, "type": "header", "format": "gadgetctl-recording"}
    for key in rng.sample(
        ["created", "wall_time", "monotonic", "generator", "info"], rng.randint(0, 5)
    ):
        header[key] = value()
    lines = [header]
    for _ in range(rng.randint(0, 12)):
        record = {"v": rng.choice([1, 1, 1, 0, 2, "1"]), "type": rng.choice(_RECORD_TYPES)}
        for key in rng.sample(_RECORD_KEYS, rng.randint(0, len(_RECORD_KEYS))):
            record[key] = value()
        lines.append(record)
    return b"".join(json.dumps(line).encode() + b"\n" for line in lines)


_RECORD_TYPES = ["sample", "frame", "marker", "stats", "status", "end", "header", "other"]
_RECORD_KEYS = [
    "device", "kind", "unit", "timestamp", "value", "raw", "frame", "devices", "count", "values",
    "name", "element", "element_type", "state", "reason", "samples", "markers", "frames",
    "info", "elements", "units", "kinds", "min", "max", "wall_time", "monotonic", "created",
]  # fmt: skip


@target("recording.reader", seeds=_recording_seeds, grammar=_recording_lines, examples=80)
def _recording(data: bytes) -> None:
    from gadgetctl.monitor.recording import RecordingError, read_recording
    from gadgetctl.monitor.records import REPLAY_UNITS
    from gadgetctl.monitor.replaydevice import make_schedule, recorded_devices
    from gadgetctl.monitor.summary import summarize_recording

    path = _as_file(data, "fuzz.gadgetrec")
    try:
        summarize_recording(path)
        recording = read_recording(path)
        schedule = make_schedule(recording.records, speed=1.0, loop=False, mapping=None)
        devices = recorded_devices(recording.header, schedule, {})
        assert all(0 < n <= REPLAY_UNITS for d in devices.values() for n in d.units.values())
    except RecordingError:
        pass


# -- VRPN -----------------------------------------------------------------------------------------


@functools.cache
def _vrpn_seeds() -> list[bytes]:
    from gadgetctl.vrpn import codecs, wire

    stream = wire.make_cookie()
    stream += wire.pack_description(wire.SENDER_DESCRIPTION, 0, "Tracker0")
    for ident, name in enumerate(codecs.CLIENT_TYPES):
        stream += wire.pack_description(wire.TYPE_DESCRIPTION, ident, name)
    types = {name: ident for ident, name in enumerate(codecs.CLIENT_TYPES)}
    reports = [
        (codecs.TRACKER_POS_QUAT, codecs.encode_pose(1, (0.1, 0.2, 0.3))),
        (codecs.TRACKER_VELOCITY, codecs.encode_velocity(0, (1.0, 0.0, 0.0))),
        (codecs.BUTTON_CHANGE, codecs.encode_button_change(3, 1)),
        (codecs.BUTTON_STATES, codecs.encode_button_states([1, 0, 1])),
        (codecs.ANALOG_CHANNEL, codecs.encode_analog([0.5, -0.25])),
        (codecs.DIAL_UPDATE, codecs.encode_dial(0, 0.125)),
        (codecs.TEXT_MESSAGE, codecs.encode_text("hello")),
    ]
    messages = b"".join(wire.pack_message(types[name], 0, payload) for name, payload in reports)
    return [
        stream + messages + wire.pack_disconnect(),
        messages,
        wire.pack_udp_description("127.0.0.1", 4000) + messages[:200],
        wire.lob_request("127.0.0.1", 4500),
    ]


def _vrpn_messages(messages: list, types: dict[int, str]) -> None:
    from gadgetctl.vrpn import codecs, wire

    for message in messages:
        if message.type_id in (wire.SENDER_DESCRIPTION, wire.TYPE_DESCRIPTION):
            name = wire.decode_description(message.payload)
            if message.type_id == wire.TYPE_DESCRIPTION and 0 <= message.sender_id < wire.MAX_IDS:
                types[message.sender_id] = name
        elif message.type_id == wire.UDP_DESCRIPTION:
            try:
                wire.decode_udp_description(message)
            except ValueError:
                pass
        else:
            for name in {types.get(message.type_id), *codecs.CLIENT_TYPES}:
                try:
                    codecs.decode(name, message.payload)
                except codecs.CodecError:
                    pass


@target("vrpn.stream", seeds=_vrpn_seeds, examples=80)
def _vrpn_stream(data: bytes) -> None:
    from gadgetctl.vrpn import wire

    for probe in (wire.check_cookie, wire.parse_lob):
        try:
            probe(data)
        except (wire.CookieError, wire.LobError):
            pass
    decoder = wire.StreamDecoder()
    types: dict[int, str] = {}
    body = data[wire.COOKIE_SIZE :] if data.startswith(b"vrpn:") else data
    try:
        for at in range(0, len(body), 61):  # in pieces that cut messages
            _vrpn_messages(decoder.feed(body[at : at + 61]), types)
    except wire.FramingError:
        pass
    assert decoder.pending <= wire.HEADER_SIZE + wire.MAX_PADDED_PAYLOAD + 61
    try:
        _vrpn_messages(wire.decode_datagram(body[: wire.MAX_DATAGRAM]), types)
    except wire.FramingError:
        pass


@functools.cache
def _vrpn_log_seeds() -> list[bytes]:
    import io

    from gadgetctl.vrpn import codecs
    from gadgetctl.vrpn.logfile import LogWriter

    out = io.BytesIO()
    writer = LogWriter(out)
    for n in range(4):
        writer.write(
            "Tracker0", codecs.TRACKER_POS_QUAT, codecs.encode_pose(n, (0.1 * n, 0.2, 0.3))
        )
        writer.write("Button0", codecs.BUTTON_CHANGE, codecs.encode_button_change(n, n % 2))
        writer.write("Analog0", codecs.ANALOG_CHANNEL, codecs.encode_analog([0.5, -0.25 * n]))
    writer.disconnect()
    writer.write("Tracker0", codecs.TEXT_MESSAGE, codecs.encode_text("again"))
    writer.close()
    return [out.getvalue()]


@target("vrpn.logfile", seeds=_vrpn_log_seeds, examples=60)
def _vrpn_log(data: bytes) -> None:
    import io

    from gadgetctl.vrpn.logfile import LogFormatError, LogReader

    try:
        reader = LogReader(io.BytesIO(data))
        for _message in reader:
            pass
    except LogFormatError:
        pass


@target("vrpn.driver", seeds=_vrpn_seeds, examples=60, driver="VRPN_drv")
def _vrpn_driver(data: bytes) -> None:
    """What VRPN_drv makes of a server's messages (names and reports as its client gives them)."""
    from VRPN_drv.standalone import Batch, ServerClock, VrpnInput

    from gadgetctl.vrpn import codecs, wire

    senders: dict[int, str] = {}
    types: dict[int, str] = {}
    messages = []
    body = data[wire.COOKIE_SIZE :] if data.startswith(b"vrpn:") else data
    try:
        for message in wire.StreamDecoder().feed(body):
            if message.type_id in (wire.SENDER_DESCRIPTION, wire.TYPE_DESCRIPTION):
                table = senders if message.type_id == wire.SENDER_DESCRIPTION else types
                table[message.sender_id] = wire.decode_description(message.payload)
            elif message.type_id >= 0:
                name = types.get(message.type_id)
                try:
                    report = codecs.decode(name, message.payload)
                except codecs.CodecError:
                    continue
                sender = senders.get(message.sender_id)
                messages.append(message._replace(sender=sender, type=name, report=report))
    except wire.FramingError:
        pass
    device = VrpnInput("Tracker0@localhost", 2, "Tracker0@localhost", 4, "Tracker0@localhost", 3)
    batch = Batch()
    device._take(messages, batch)
    # the same poses framed in blocks and unpacked at once, as the client leaves them
    bulk = {
        (sender_id, type_id): (("Tracker0", codecs.TRACKER_POS_QUAT), wire.HEADER_SIZE + 64)
        for sender_id, sender in senders.items()
        for type_id, type_name in types.items()
        if sender == "Tracker0" and type_name == codecs.TRACKER_POS_QUAT
    }
    if bulk:
        try:
            _pos, _rest, found = wire.split_messages(
                body, 0, len(body), 0.0, dict(list(bulk.items())[:64])
            )
        except wire.FramingError:
            found = {}
        for (sender, type_name), offsets in found.items():
            device._take_block(
                wire.Block(body, offsets, sender, type_name, 0.0), batch, ServerClock()
            )
    assert all(pose.shape == (2, 4, 4) for _, pose in batch.positions)
    assert all(len(values) == 4 for _, values in batch.digital)
    assert all(len(values) == 3 for _, values in batch.analog)
