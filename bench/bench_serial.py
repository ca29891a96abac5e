"""Serial-line drivers at their devices' fastest documented rates, through the input manager.

Each row runs the driver's emulator in a child process (its pty behind a link in a temporary
folder) at the device's fastest documented rate, and a configured input manager here running
frames at 60 Hz. Targets: the device's rate is sustained (at least 95 %) and no record is
lost (records the emulator sent against records the driver decoded). Each row prints the
rate, the share of one core this process used (the emulator runs in its own) and the
decoder against a bare ``struct`` unpack of the same records, measured in the same run.

A new serial driver adds one :class:`Row` to :data:`ROWS`.

Run from the repository root: python bench/bench_serial.py [--seconds 3] [--only NAME]
Exit status 1 when a target is missed.
"""

from __future__ import annotations

import argparse
import struct
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from common import REPO, Report

sys.path.insert(0, str(REPO / "drivers"))

from gadgetctl.input import InputManager, ManagerOptions

FRAME_RATE = 60.0
HEAD = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="bench">
<elements>
<input_manager name="IM" version="2"><driver>{driver}</driver></input_manager>
{device}
</elements>
</configuration>
"""


@dataclass(frozen=True)
class Row:
    """One driver: its device's rate, how to make its emulator and count what it sent, the
    element that reads it, what the driver decoded, and a decoder benchmark."""

    driver: str
    rate: float  # the device's fastest documented rate, emulator units per second
    rate_note: str
    emulator: Callable[[str, float], object]  # (link, rate) -> a started emulator, in the child
    sent: Callable[[object], int]  # records the emulator sent
    element: Callable[[str], str]  # link -> the device element, named "Bench"
    received: Callable[[object], int]  # records the device decoded
    per_rate: int = 1  # records per emulator unit (stations per poll)
    decoder: Callable[[], tuple[Callable[[], object], Callable[[], object], int]] | None = None


# -- IS-900 -------------------------------------------------------------------------------------


def _is900_emulator(link: str, rate: float) -> object:
    from IS900_drv.emulator import IS900Emulator

    return IS900Emulator("motion", rate, link=link).start()


def _is900_element(link: str) -> str:
    stations = "".join(
        f'<stations><intersense_station name="S{i}" version="1"><enabled>true</enabled>'
        f"<station_index>{i}</station_index><digital_count>4</digital_count>"
        f"<analog_first>{2 * i}</analog_first><analog_count>2</analog_count>"
        "</intersense_station></stations>"
        for i in range(2)
    )
    return f'<intersense name="Bench" version="1"><port>{link}</port>{stations}</intersense>'


def _is900_decoder() -> tuple[Callable[[], object], Callable[[], object], int]:
    from IS900_drv.emulator import encode_record, pose
    from IS900_drv.standalone import RECORD_SIZE, RecordScanner

    data = b"".join(encode_record(i % 2, *pose("motion", i % 2, i)) for i in range(2000))
    body = struct.Struct("<2x1x6fBBBB2x")

    def ours() -> object:
        return RecordScanner(stations=frozenset({0, 1})).feed(data)

    def baseline() -> object:
        return [body.unpack_from(data, i) for i in range(0, len(data), RECORD_SIZE)]

    return ours, baseline, 2000


# -- SpaceBall 4000 FLX ------------------------------------------------------------------------


def _spaceball_emulator(link: str, rate: float) -> object:
    from SpaceBall_drv.emulator import SpaceBallEmulator

    return SpaceBallEmulator("motion", rate, model="SpaceBall 4000 FLX", link=link).start()


def _spaceball_element(link: str) -> str:
    return (
        '<puck_device name="Bench" version="1"><device>SpaceBall 4000 FLX</device>'
        f"<port>{link}</port><baud>9600</baud></puck_device>"
    )


def _spaceball_decoder() -> tuple[Callable[[], object], Callable[[], object], int]:
    from SpaceBall_drv.emulator import encode_axes, motion_axes
    from SpaceBall_drv.standalone import RecordSplitter

    model = "SpaceBall 4000 FLX"
    data = b"".join(encode_axes(model, motion_axes(model, i), timer=i) for i in range(1, 2001))
    words = struct.Struct(">H6h")

    def ours() -> object:
        return RecordSplitter(model).feed(data)

    def baseline() -> object:
        return [words.unpack_from(r, 1) for r in data.split(b"\r") if len(r) == 15]

    return ours, baseline, 2000


# -- Fastrak ------------------------------------------------------------------------------------


def _fastrak_emulator(link: str, rate: float) -> object:
    from Fastrak_drv.emulator import FastrakEmulator

    return FastrakEmulator("motion", rate, link=link).start()


def _fastrak_decoder() -> tuple[Callable[[], object], Callable[[], object], int]:
    from Fastrak_drv.emulator import encode_record, pose
    from Fastrak_drv.standalone import RECORD_SIZE, RecordScanner

    data = b"".join(encode_record(1 + i % 2, *pose("motion", 1 + i % 2, i)) for i in range(2000))
    body = struct.Struct("<3x7f2x2x")

    def ours() -> object:
        return RecordScanner().feed(data)

    def baseline() -> object:
        return [body.unpack_from(data, i) for i in range(0, len(data), RECORD_SIZE)]

    return ours, baseline, 2000


# -- 5DT DataGlove ------------------------------------------------------------------------------


def _dataglove_emulator(link: str, rate: float) -> object:
    from DataGlove_drv.emulator import DataGloveEmulator

    return DataGloveEmulator("motion", rate, link=link).start()


def _dataglove_decoder() -> tuple[Callable[[], object], Callable[[], object], int]:
    from DataGlove_drv.emulator import encode_packet, pose
    from DataGlove_drv.standalone import PacketScanner

    data = b"".join(encode_packet(pose("motion", i)) for i in range(2000))
    packet = struct.Struct("<x7BBB")

    def ours() -> object:
        return PacketScanner().feed(data)

    def baseline() -> object:
        return [packet.unpack_from(data, i) for i in range(0, len(data), 10)]

    return ours, baseline, 2000


# -- US Digital SEI encoders ---------------------------------------------------------------------


def _encoder_emulator(link: str, rate: float) -> object:
    from SerialEncoder_drv.emulator import SerialEncoderEmulator

    return SerialEncoderEmulator("motion", 10 * rate, link=link).start()  # answers, not polls


def _encoder_decoder() -> tuple[Callable[[], object], Callable[[], object], int]:
    from SerialEncoder_drv.emulator import encode_reply
    from SerialEncoder_drv.standalone import decode_reply

    replies = [encode_reply(1 + i % 2, i / 7) for i in range(2000)]
    word = struct.Struct(">xf")

    def ours() -> object:
        return [decode_reply(1 + i % 2, r) for i, r in enumerate(replies)]

    def baseline() -> object:
        return [word.unpack(r) for r in replies]

    return ours, baseline, 2000


# -- Logitech 3D mouse ------------------------------------------------------------------------


def _three_d_mouse_emulator(link: str, rate: float) -> object:
    from ThreeDMouse_drv.emulator import ThreeDMouseEmulator

    return ThreeDMouseEmulator("motion", rate, link=link).start()


def _three_d_mouse_decoder() -> tuple[Callable[[], object], Callable[[], object], int]:
    from ThreeDMouse_drv.emulator import encode_report, state
    from ThreeDMouse_drv.standalone import REPORT_SIZE, ReportScanner

    data = b"".join(encode_report(*state("motion", i)) for i in range(2000))
    body = struct.Struct("16B")

    def ours() -> object:
        return ReportScanner().feed(data)

    def baseline() -> object:
        return [body.unpack_from(data, i) for i in range(0, len(data), REPORT_SIZE)]

    return ours, baseline, 2000


# -- Flock of Birds ------------------------------------------------------------------------------


def _flock_emulator(link: str, rate: float) -> object:
    from Flock_drv.emulator import FlockEmulator

    return FlockEmulator("motion", rate, birds=4, link=link).start()


def _flock_element(link: str) -> str:
    return f'<flock name="Bench" version="2"><port>{link}</port><baud>115200</baud></flock>'


def _flock_decoder() -> tuple[Callable[[], object], Callable[[], object], int]:
    from Flock_drv.emulator import encode_record, pose
    from Flock_drv.standalone import POS_QUATERNION, RecordScanner

    data = b"".join(
        encode_record(POS_QUATERNION, *pose("motion", i % 4, i), 3.0, i % 4 + 1)
        for i in range(2000)
    )
    words = struct.Struct("<14B1x")

    def ours() -> object:
        return RecordScanner(POS_QUATERNION, 3.0, True, frozenset({1, 2, 3, 4})).feed(data)

    def baseline() -> object:
        return [words.unpack_from(data, i) for i in range(0, len(data), 15)]

    return ours, baseline, 2000


# -- 5DT Data Glove Ultra Wireless ----------------------------------------------------------------


def _ultraglove_emulator(link: str, rate: float) -> object:
    from DataGloveUltraWireless_drv.emulator import UltraGloveEmulator

    return UltraGloveEmulator("motion", rate, link=link).start()


def _ultraglove_decoder() -> tuple[Callable[[], object], Callable[[], object], int]:
    from DataGloveUltraWireless_drv.emulator import encode_record, readings
    from DataGloveUltraWireless_drv.standalone import RECORD_SIZE, RecordScanner

    data = b"".join(encode_record(i % 2, readings("motion", i % 2, i)) for i in range(2000))
    record = struct.Struct(">3x21s4xx")

    def ours() -> object:
        return RecordScanner().feed(data)

    def baseline() -> object:
        return [record.unpack_from(data, i) for i in range(0, len(data), RECORD_SIZE)]

    return ours, baseline, 2000


# -- Immersion IBox ------------------------------------------------------------------------------


def _ibox_emulator(link: str, rate: float) -> object:
    from IBox_drv.emulator import IBoxEmulator

    return IBoxEmulator("motion", rate, link=link).start()


def _ibox_decoder() -> tuple[Callable[[], object], Callable[[], object], int]:
    from IBox_drv.emulator import controls, encode_packet
    from IBox_drv.standalone import PacketScanner

    data = b"".join(encode_packet(0x08, *controls("motion", i)) for i in range(2000))
    packet = struct.Struct("<x6B")

    def ours() -> object:
        return PacketScanner().feed(data)

    def baseline() -> object:
        return [packet.unpack_from(data, i) for i in range(0, len(data), 7)]

    return ours, baseline, 2000


# -- Ascension Wanda -----------------------------------------------------------------------------


def _wanda_emulator(link: str, rate: float) -> object:
    from Wanda_drv.emulator import WandaEmulator

    # the joystick held off centre all along: a packet every step, the line's fastest rate
    # (``motion`` lets the ball go a quarter of the time, and a Wanda at rest is silent: it
    # sent 33 packets a second, which the rate figure read as a driver falling behind); the
    # ``disconnect`` scenario moves without rest, and never hangs up here
    return WandaEmulator("disconnect", rate, disconnect_after=1 << 30, link=link).start()


def _wanda_decoder() -> tuple[Callable[[], object], Callable[[], object], int]:
    from Wanda_drv.emulator import controls, encode_packet
    from Wanda_drv.standalone import PacketScanner

    data = b"".join(encode_packet(*controls("motion", i)) for i in range(2000))
    packet = struct.Struct("<3B")

    def ours() -> object:
        return PacketScanner().feed(data, quiet=True)

    def baseline() -> object:
        return [packet.unpack_from(data, i) for i in range(0, len(data), 3)]

    return ours, baseline, 2000


ROWS: list[Row] = [
    Row(
        "IS900_drv",
        180.0,
        "IS-900: 180 Hz updates (InterSense's data sheet), 2 stations per poll",
        _is900_emulator,
        lambda emu: len(emu.sent),  # type: ignore[attr-defined]
        _is900_element,
        lambda device: device.records,  # type: ignore[attr-defined]
        per_rate=2,
        decoder=_is900_decoder,
    ),
    Row(
        "SpaceBall_drv",
        54.0,
        "SpaceBall 4000 FLX: 16-byte records fill 9600 baud 8N2 at 54/s (SpaceMouse: 26 bytes, 33/s)",
        _spaceball_emulator,
        lambda emu: len(emu.sent),  # type: ignore[attr-defined]
        _spaceball_element,
        lambda device: device.records,  # type: ignore[attr-defined]
        decoder=_spaceball_decoder,
    ),
    Row(
        "Fastrak_drv",
        120.0,
        "Fastrak: 120 records/s in all (Polhemus: 120 Hz for one station, shared by the active ones)",
        _fastrak_emulator,
        lambda emu: len(emu.sent),  # type: ignore[attr-defined]
        lambda link: f'<fastrak name="Bench" version="2"><port>{link}</port></fastrak>',
        lambda device: device.records,  # type: ignore[attr-defined]
        decoder=_fastrak_decoder,
    ),
    Row(
        "DataGlove_drv",
        384.0,
        "5DT DataGlove: 10-byte packets fill its default 38400 baud 8N1 at 384/s",
        _dataglove_emulator,
        lambda emu: len(emu.sent),  # type: ignore[attr-defined]
        lambda link: f'<data_glove name="Bench" version="1"><port>{link}</port></data_glove>',
        lambda device: device.records,  # type: ignore[attr-defined]
        decoder=_dataglove_decoder,
    ),
    Row(
        "SerialEncoder_drv",
        96.0,
        "SEI encoders: 96 polls/s of tilt and height fill 9600 baud (5-byte answers, 2 per poll)",
        _encoder_emulator,
        lambda emu: len(emu.sent),  # type: ignore[attr-defined]
        lambda link: (
            f'<serial_encoder name="Bench" version="1"><port>{link}</port></serial_encoder>'
        ),
        lambda device: device.records,  # type: ignore[attr-defined]
        per_rate=2,
        decoder=_encoder_decoder,
    ),
    Row(
        "ThreeDMouse_drv",
        109.0,
        "3D mouse: 16-byte reports fill 19200 baud 8N2 at 109/s (the line's limit)",
        _three_d_mouse_emulator,
        lambda emu: len(emu.sent),  # type: ignore[attr-defined]
        lambda link: (
            f'<three_d_mouse name="Bench" version="1"><port>{link}</port><baud>19200</baud></three_d_mouse>'
        ),
        lambda device: device.records,  # type: ignore[attr-defined]
        decoder=_three_d_mouse_decoder,
    ),
    Row(
        "Flock_drv",
        144.0,
        "Flock of Birds: 4 birds in group mode at 144 Hz (PosQuaternion, 15 bytes per bird)",
        _flock_emulator,
        lambda emu: len(emu.sent),  # type: ignore[attr-defined]
        _flock_element,
        lambda device: device.records,  # type: ignore[attr-defined]
        per_rate=4,
        decoder=_flock_decoder,
    ),
    Row(
        "DataGloveUltraWireless_drv",
        397.0,
        "Data Glove Ultra Wireless: 29-byte records fill 115200 baud 8N1 at 397/s, both gloves"
        " (5DT states at least 75 Hz a glove)",
        _ultraglove_emulator,
        lambda emu: len(emu.sent),  # type: ignore[attr-defined]
        lambda link: (
            f'<data_glove_ultra_wireless name="Bench" version="2"><port>{link}</port>'
            "</data_glove_ultra_wireless>"
        ),
        lambda device: device.records,  # type: ignore[attr-defined]
        decoder=_ultraglove_decoder,
    ),
    Row(
        "IBox_drv",
        548.0,
        "IBox: 7-byte HCI packets (buttons, 4 analogs) fill 38400 baud 8N1 at 548/s",
        _ibox_emulator,
        lambda emu: len(emu.sent),  # type: ignore[attr-defined]
        lambda link: f'<ibox name="Bench" version="1"><port>{link}</port></ibox>',
        lambda device: device.records,  # type: ignore[attr-defined]
        decoder=_ibox_decoder,
    ),
    Row(
        "Wanda_drv",
        44.0,
        "Wanda: 3-byte packets fill 1200 baud 7N1 at 44/s",
        _wanda_emulator,
        lambda emu: len(emu.sent),  # type: ignore[attr-defined]
        lambda link: f'<wanda name="Bench" version="1"><port>{link}</port></wanda>',
        lambda device: device.records,  # type: ignore[attr-defined]
        decoder=_wanda_decoder,
    ),
]


# -- the child: one emulator until stdin closes -------------------------------------------------


def child(driver: str, link: str, rate: float) -> None:
    row = next(r for r in ROWS if r.driver == driver)
    emu = row.emulator(link, rate)
    print("ready", flush=True)
    sys.stdin.readline()  # "count": the measured window is over
    if hasattr(emu, "pause") and hasattr(emu, "unread"):  # emulators that can hold still
        emu.pause()
        deadline = time.monotonic() + 2.0
        while emu.unread() and time.monotonic() < deadline:
            time.sleep(0.01)  # the driver reads what was sent (a hang-up would drop it)
    print(row.sent(emu), flush=True)
    sys.stdin.read()  # until the benchmark has counted
    emu.stop()  # type: ignore[attr-defined]


# -- measuring -------------------------------------------------------------------------------


def bench_row(report: Report, row: Row, seconds: float) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        link = str(Path(tmp) / "tty")
        proc = subprocess.Popen(
            [sys.executable, __file__, "--child", row.driver, link, str(row.rate)],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        try:
            assert proc.stdout is not None and proc.stdin is not None
            assert proc.stdout.readline().strip() == "ready"
            path = Path(tmp) / "bench.jconf"
            path.write_text(HEAD.format(driver=row.driver, device=row.element(link)))
            options = ManagerOptions(retry_interval=None, entry_points=False)
            manager, configuration = InputManager.from_files([path], options=options)
            try:
                manager.configure(configuration)
                assert not manager.pending(), [p.message for p in manager.pending()]
                device = manager.device("Bench")
                manager.run(FRAME_RATE, frames=1)
                start_records = row.received(device)
                cpu0, wall0 = time.process_time(), time.perf_counter()
                manager.run(FRAME_RATE, frames=int(seconds * FRAME_RATE))
                cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
                window = row.received(device) - start_records
                proc.stdin.write("count\n")
                proc.stdin.flush()
                sent = int(proc.stdout.readline())
                settle = time.perf_counter() + 1.0
                while row.received(device) < sent and time.perf_counter() < settle:
                    manager.update()
                    time.sleep(0.01)
                received = row.received(device)
            finally:
                manager.shutdown()
        finally:
            if proc.stdin is not None:
                proc.stdin.close()
            proc.wait(10)
    print(f"{row.driver}: {row.rate_note}")
    rate = window / wall / row.per_rate
    report.figure(f"{row.driver} rate", rate, "Hz", target=0.95 * row.rate, higher_is_better=True)
    report.figure(f"{row.driver} records lost (sent {sent})", sent - received, "records", target=0)
    report.figure(f"{row.driver} share of one core", 100.0 * cpu / wall, "%")
    if row.decoder is not None:
        ours, baseline, items = row.decoder()
        report.ratio(
            f"{row.driver} decoder time vs bare struct unpack",
            _time(ours),
            _time(baseline),
            f"({items} records)",
        )


def _time(fn: Callable[[], object], repeat: int = 5) -> float:
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return best


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=3.0)
    parser.add_argument("--only", action="append", default=[], help="a driver plug-in name")
    parser.add_argument(
        "--child", nargs=3, metavar=("DRIVER", "LINK", "RATE"), help=argparse.SUPPRESS
    )
    args = parser.parse_args(argv)
    if args.child:
        child(args.child[0], args.child[1], float(args.child[2]))
        return 0
    report = Report()
    for row in ROWS:
        if not args.only or row.driver in args.only:
            bench_row(report, row, args.seconds)
    report.exit()
    return 0


if __name__ == "__main__":
    sys.exit(main())
