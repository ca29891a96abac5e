"""Benchmarks of the bundled DTrack and Linux joystick drivers, through the input manager.

1. DTrack: a sender process sends 10,000 datagrams/s, each a frame with 10 bodies and a
   Flystick, to a dtrack device on loopback while the input manager runs frames at 60 Hz.
   Targets: the rate is sustained, no datagram is lost at the driver (frame counters sent
   against received) and every decoded datagram reaches the frames as one sample per kind.
2. Linux joystick: a writer process writes 20,000 js_event records/s into the FIFO of a
   linux_joydev device. Targets: the rate is sustained and every record reaches the frames.

Each prints the rates, the driver process's share of one core (the sender runs in its own
process) and the decoder against a baseline measured in the same run: DTrack's body lines
through the general parser, js_event records through a bare struct unpack.

Run from the repository root: python bench/bench_drivers.py [--seconds 3]
Exit status 1 when a target is missed.
"""

from __future__ import annotations

import argparse
import os
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path

from common import REPO, Report

sys.path.insert(0, str(REPO / "drivers"))

from DTrack_drv.emulator import FrameWriter
from DTrack_drv.standalone import parse_frame, parse_frames
from LinuxJoydev_drv.standalone import EVENT_FORMAT, EventDecoder

from gadgetctl.input import DeviceKind, InputManager, ManagerOptions

DTRACK_RATE = 10_000
JOYSTICK_RATE = 20_000
BODIES = 10
BUTTONS, AXES = 12, 6
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


# -- the senders (child processes of this script) -----------------------------------------------


def paced(
    rate: float, seconds: float, send: Callable[[int], None], burst_limit: int = 200
) -> tuple[int, float]:
    """Call ``send(i)`` ``rate`` times a second for ``seconds``; returns (count, elapsed)."""
    total = int(rate * seconds)
    start = time.perf_counter()
    sent = 0
    while sent < total:
        due = min(total, int((time.perf_counter() - start) * rate) + 1, sent + burst_limit)
        if due <= sent:
            time.sleep(0.0002)
            continue
        for i in range(sent, due):
            send(i)
        sent = due
    return sent, time.perf_counter() - start


def handshake() -> None:
    """Tell the benchmark this sender is ready and wait for its go."""
    print("ready", flush=True)
    sys.stdin.readline()


def send_dtrack(port: int, rate: float, seconds: float) -> None:
    """Frames numbered from 1, each with 10 moving bodies and a Flystick, to 127.0.0.1:port."""
    writer = FrameWriter("motion", rate, bodies=BODIES, flysticks=1, markers=0, gloves=0)
    # 64 frames' lines after fr/ts, reused with fresh counters and timestamps
    bodies = [writer.frame(n).split("\r\n", 2)[2].encode() for n in range(64)]
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    target = ("127.0.0.1", port)

    def send(i: int) -> None:
        n = i + 1
        sock.sendto(b"fr %d\r\nts %.6f\r\n" % (n, 36000.0 + n / rate) + bodies[n % 64], target)

    handshake()
    print(*paced(rate, seconds, send), flush=True)


def send_joystick(path: str, rate: float, seconds: float) -> None:
    """The initial burst, then axis motion and button toggles, into the FIFO at ``path``."""
    pack = struct.Struct(EVENT_FORMAT).pack
    base = 5_000_000
    burst = [pack(base, 0, 0x81, b) for b in range(BUTTONS)] + [
        pack(base, 0, 0x82, a) for a in range(AXES)
    ]
    chunk: list[bytes] = []
    handshake()
    fd = os.open(path, os.O_WRONLY)  # the device has the FIFO open for reading by now
    os.write(fd, b"".join(burst))

    def send(i: int) -> None:
        t = base + 1 + i * 1000 // int(rate)
        if i % 10 == 9:
            chunk.append(pack(t, (i // 10) % 2, 0x01, (i // 20) % BUTTONS))
        else:
            chunk.append(pack(t, (i * 37) % 65535 - 32767, 0x02, i % AXES))
        if len(chunk) >= 16:
            os.write(fd, b"".join(chunk))
            chunk.clear()

    sent, elapsed = paced(rate, seconds, send)
    if chunk:
        os.write(fd, b"".join(chunk))
    print(sent, elapsed, flush=True)
    sys.stdin.read()  # keep the FIFO open until the benchmark has counted
    os.close(fd)


# -- measuring --------------------------------------------------------------------------------


class Run:
    """A configured input manager, and a sender process that waits for the go."""

    def __init__(self, driver: str, device: str, kind: DeviceKind, sender: list[str]) -> None:
        self.child = subprocess.Popen(
            [sys.executable, __file__, *sender],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        assert self.child.stdout.readline().strip() == "ready"  # before the device listens
        self.tmp = tempfile.TemporaryDirectory()
        path = Path(self.tmp.name) / "bench.jconf"
        path.write_text(HEAD.format(driver=driver, device=device))
        options = ManagerOptions(retry_interval=None, entry_points=False)
        self.manager, configuration = InputManager.from_files([path], options=options)
        self.manager.configure(configuration)
        assert not self.manager.pending(), [p.message for p in self.manager.pending()]
        self.device = self.manager.device("Bench")
        self.kind = kind
        self.in_frames = 0  # samples seen in the frames

    def count(self, _manager: InputManager) -> None:
        self.in_frames += len(self.device.store.frame(self.kind))

    def measure(self) -> tuple[int, float, float, float]:
        """Run frames while the sender sends; returns (sent, its seconds, our CPU, wall)."""
        reported: list[str] = []
        reader = threading.Thread(
            target=lambda: reported.append(self.child.stdout.readline()), daemon=True
        )
        # a first run() collects and freezes the garbage collector's generations; that pause
        # must come before the stream, as in an application that starts its frame loop once
        self.manager.run(FRAME_RATE, frames=1, on_frame=self.count)
        cpu0, wall0 = time.process_time(), time.perf_counter()
        self.child.stdin.write("go\n")
        self.child.stdin.flush()
        reader.start()

        def frame(manager: InputManager) -> bool:
            self.count(manager)
            return not reported

        self.manager.run(FRAME_RATE, on_frame=frame)
        cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
        sent, elapsed = reported[0].split()
        return int(sent), float(elapsed), cpu, wall

    def settle(self, arrived: Callable[[], int], sent: int, timeout: float = 1.0) -> None:
        """Frames until ``arrived()`` reaches ``sent`` or stops growing, then two more."""
        last, still = arrived(), time.perf_counter()
        while last < sent and time.perf_counter() - still < timeout:
            self.manager.update()
            self.count(self.manager)
            time.sleep(1.0 / FRAME_RATE)
            if arrived() != last:
                last, still = arrived(), time.perf_counter()
        for _ in range(2):
            self.manager.update()
            self.count(self.manager)

    def close(self) -> None:
        self.manager.shutdown()
        self.child.stdin.close()
        self.child.wait(10)
        self.tmp.cleanup()


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def bench_dtrack(report: Report, seconds: float) -> None:
    port = free_port()
    device = f'<dtrack name="Bench" version="1"><receive_port>{port}</receive_port></dtrack>'
    run = Run(
        "DTrack_drv",
        device,
        DeviceKind.POSITION,
        ["--send-dtrack", str(port), str(DTRACK_RATE), str(seconds)],
    )
    try:
        sent, elapsed, cpu, wall = run.measure()
        run.settle(lambda: run.device.counters["datagrams"], sent)
        counters = run.device.counters
        samples = run.device.store.total(DeviceKind.POSITION)
        in_frames, dropped, faults = run.in_frames, run.device.store.dropped(), run.device.faults
        error = run.device.error
    finally:
        run.close()
    print(
        f"DTrack: {sent:,} datagrams of {BODIES} bodies and a Flystick in {elapsed:.2f} s, frames at {FRAME_RATE:g} Hz"
    )
    report.figure(
        "DTrack: datagrams sent per second",
        sent / elapsed,
        "/s",
        target=DTRACK_RATE * 0.99,
        higher_is_better=True,
    )
    report.figure(
        "DTrack: datagrams lost at the driver (sent - received)",
        sent - counters["datagrams"],
        "",
        target=0,
    )
    report.figure("DTrack: gaps in the frame counter", counters["missed_frames"], "", target=0)
    report.figure("DTrack: bad datagrams", counters["bad_datagrams"], "", target=0)
    report.figure(
        "DTrack: decoded samples that never reached a frame", samples - in_frames, "", target=0
    )
    report.figure("DTrack: samples dropped over the per-frame cap", dropped, "", target=0)
    report.figure(
        "DTrack: datagrams not decoded into samples", counters["datagrams"] - samples, "", target=0
    )
    report.figure("DTrack: device faults", faults, "", target=0)
    if error:
        print(f"  last fault: {error}")
    report.figure("DTrack: driver process CPU (one core = 100 %)", cpu / wall * 100, "%")
    report.figure("DTrack: CPU per datagram", cpu / max(1, sent) * 1e6, "us")

    writer = FrameWriter("motion", DTRACK_RATE, bodies=BODIES, flysticks=1, markers=0, gloves=0)
    datagrams = [writer.frame(n).encode() for n in range(1, 101)]
    batched = _rate(lambda: parse_frames(datagrams), len(datagrams))
    single = _rate(lambda: [parse_frame(d) for d in datagrams], len(datagrams))
    general = _rate(lambda: [parse_frame(d, fast=False) for d in datagrams], len(datagrams))
    report.figure("DTrack: datagrams decoded per second, batches of 100", batched, "/s")
    report.figure("DTrack: ... one at a time", single, "/s")
    report.figure("DTrack: ... general line parser only (baseline)", general, "/s")
    report.ratio("DTrack: batched decoding / general parser", batched, general)


def bench_joystick(report: Report, seconds: float) -> None:
    tmp = tempfile.TemporaryDirectory()
    fifo = Path(tmp.name) / "js0"
    os.mkfifo(fifo)
    device = f'<linux_joydev name="Bench" version="1"><port_name>{fifo}</port_name></linux_joydev>'
    sender = ["--send-joystick", str(fifo), str(JOYSTICK_RATE), str(seconds)]
    run = Run("LinuxJoydev_drv", device, DeviceKind.DIGITAL, sender)
    try:
        sent, elapsed, cpu, wall = run.measure()
        run.settle(lambda: run.device.store.total(DeviceKind.DIGITAL), sent + 1)  # + the burst
        samples = run.device.store.total(DeviceKind.DIGITAL)
        in_frames, dropped = run.in_frames, run.device.store.dropped()
        counters, faults = run.device.counters, run.device.faults
    finally:
        run.close()
        tmp.cleanup()
    print(
        f"Linux joystick: {sent:,} events through a FIFO in {elapsed:.2f} s, frames at {FRAME_RATE:g} Hz"
    )
    report.figure(
        "joystick: events written per second",
        sent / elapsed,
        "/s",
        target=JOYSTICK_RATE * 0.99,
        higher_is_better=True,
    )
    report.figure(
        "joystick: events without a sample (sent - received)", sent + 1 - samples, "", target=0
    )
    report.figure("joystick: samples that never reached a frame", samples - in_frames, "", target=0)
    report.figure("joystick: samples dropped over the per-frame cap", dropped, "", target=0)
    report.figure("joystick: bytes skipped as garbage", counters["skipped_bytes"], "", target=0)
    report.figure("joystick: device faults", faults, "", target=0)
    report.figure("joystick: driver process CPU (one core = 100 %)", cpu / wall * 100, "%")
    report.figure("joystick: CPU per event", cpu / max(1, sent) * 1e6, "us")

    pack = struct.Struct(EVENT_FORMAT).pack
    burst = b"".join(
        [pack(0, 0, 0x81, b) for b in range(BUTTONS)] + [pack(0, 0, 0x82, a) for a in range(AXES)]
    )
    stream = b"".join(
        pack(1 + i // 20, (i * 37) % 65535 - 32767, 0x02, i % AXES) for i in range(20_000)
    )

    def decode() -> None:
        decoder = EventDecoder()
        decoder.feed(burst)
        decoder.feed(stream)

    decoded = _rate(decode, 20_000)
    unpacked = _rate(lambda: list(struct.iter_unpack(EVENT_FORMAT, stream)), 20_000)
    report.figure("joystick: events decoded per second (standalone)", decoded, "/s")
    report.figure("joystick: ... bare struct unpack (baseline)", unpacked, "/s")
    report.ratio("joystick: decoder / bare unpack", decoded, unpacked)


def _rate(fn: Callable[[], object], items: int, repeat: int = 5) -> float:
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return items / best


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=3.0, help="length of each run (default 3)")
    parser.add_argument(
        "--send-dtrack", nargs=3, metavar=("PORT", "RATE", "SECONDS"), help=argparse.SUPPRESS
    )
    parser.add_argument(
        "--send-joystick", nargs=3, metavar=("FIFO", "RATE", "SECONDS"), help=argparse.SUPPRESS
    )
    args = parser.parse_args(argv)
    if args.send_dtrack:
        port, rate, seconds = args.send_dtrack
        send_dtrack(int(port), float(rate), float(seconds))
        return 0
    if args.send_joystick:
        path, rate, seconds = args.send_joystick
        send_joystick(path, float(rate), float(seconds))
        return 0
    report = Report()
    bench_dtrack(report, args.seconds)
    bench_joystick(report, args.seconds)
    report.exit()
    return 0


if __name__ == "__main__":
    sys.exit(main())
