"""Benchmarks of the bundled OptiTrack (NatNet) and TUIO drivers through the input manager.

1. OptiTrack: a sender process sends 240 NatNet frames/s, each with 32 moving rigid bodies and 100
unidentified markers, to an optitrack device (32 body units and 100 marker units) on
loopback while the input manager runs frames at 60 Hz. Targets: the rate is sustained, no
frame is lost (frames sent = frames decoded = samples in the frames, no gap in the frame
numbers). Prints the driver process's share of one core and the decoder's rate against a
baseline measured in the same run (a bare struct unpack of the same packets' numbers).

2. TUIO: a sender process sends 200 bundles/s, each with 10 moving cursors, to a TUIO_drv
device with 10 points. Targets: the rate is sustained and every bundle becomes a sample.

Run from the repository root: python bench/bench_net_drivers.py [--seconds 3]
Exit status 1 when a target is missed.
"""

from __future__ import annotations

import argparse
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

from OptiTrack_drv.emulator import FrameWriter
from OptiTrack_drv.standalone import decode_frame
from TUIO_drv.emulator import frame_bundle

from gadgetctl.input import DeviceKind, InputManager, ManagerOptions

RATE = 240.0
BODIES, MARKERS = 32, 100
FRAME_RATE = 60.0
TUIO_RATE, CURSORS = 200.0, 10


def send(kind: str, port: int, seconds: float) -> None:
    if kind == "tuio":
        rate = TUIO_RATE
        packets = [frame_bundle(n, CURSORS, "motion") for n in range(1, 201)]
    else:
        rate = RATE
        writer = FrameWriter("motion", BODIES, MARKERS)
        packets = [writer.frame(n) for n in range(1, 241)]
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    print("ready", flush=True)
    sys.stdin.readline()
    total, start = int(rate * seconds), time.perf_counter()
    for i in range(total):
        delay = start + i / rate - time.perf_counter()
        if delay > 0:
            time.sleep(delay)
        packet = packets[i % len(packets)]
        if kind != "tuio":  # frame numbers that never repeat
            packet = packet[:4] + struct.pack("<i", i + 1) + packet[8:]
        sock.sendto(packet, ("127.0.0.1", port))
    print(total, time.perf_counter() - start, flush=True)


def device_xml(port: int) -> str:
    bodies = "".join(
        f'<rigid_body><optitrack_rigid_body name="b{i}" version="1"><body_index>{i + 1}'
        "</body_index></optitrack_rigid_body></rigid_body>"
        for i in range(BODIES)
    )
    markers = "".join(
        f'<marker><optitrack_marker name="m{k}" version="1"><marker_index>{1000 + k}'
        "</marker_index></optitrack_marker></marker>"
        for k in range(MARKERS)
    )
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
        '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="b">'
        '<elements><input_manager name="IM" version="2"><driver>Optitrack_drv</driver>'
        f'</input_manager><optitrack name="Bench" version="2"><port>{port}</port>'
        f"<natnet_version>4.1</natnet_version>{bodies}{markers}"
        "</optitrack></elements></configuration>\n"
    )


def tuio_xml(port: int) -> str:
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
        '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="b">'
        '<elements><input_manager name="IM" version="2"><driver>TUIO_drv</driver>'
        f'</input_manager><TUIO_drv name="Bench" version="1"><points>{CURSORS}</points>'
        f"<port>{port}</port></TUIO_drv></elements></configuration>\n"
    )


def stream(kind: str, seconds: float, xml: Callable[[int], str], sample_kind: DeviceKind):
    """Send ``kind``'s stream to a device while frames run; returns (sent, sender seconds,
    our CPU seconds, wall seconds, the device's counters, samples seen in the frames)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    child = subprocess.Popen(
        [sys.executable, __file__, "--send", kind, str(port), str(seconds)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    assert child.stdout.readline().strip() == "ready"
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bench.jconf"
        path.write_text(xml(port))
        options = ManagerOptions(retry_interval=None, entry_points=False)
        manager, configuration = InputManager.from_files([path], options=options)
        manager.configure(configuration)
        assert not manager.pending(), [p.message for p in manager.pending()]
        dev = manager.device("Bench")
        in_frames = 0

        def count(_m: InputManager) -> bool:
            nonlocal in_frames
            in_frames += len(dev.store.frame(sample_kind))
            return True

        manager.run(FRAME_RATE, frames=1, on_frame=count)
        in_frames = 0
        cpu0, wall0 = time.process_time(), time.perf_counter()
        child.stdin.write("go\n")
        child.stdin.flush()
        said: list[str] = []
        reader = threading.Thread(target=lambda: said.append(child.stdout.readline()))
        reader.start()
        manager.run(FRAME_RATE, on_frame=lambda m: count(m) and not said)
        cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
        sent, elapsed = int(said[0].split()[0]), float(said[0].split()[1])
        deadline = time.perf_counter() + 1.0
        decoded = "frames" if kind == "natnet" else "datagrams"
        while (
            dev.counters["datagrams"] < sent or in_frames < dev.counters[decoded]
        ) and time.perf_counter() < deadline:
            manager.update()
            count(manager)
            time.sleep(1 / FRAME_RATE)
        for _ in range(2):
            manager.update()
            count(manager)
        counters = dev.counters
        manager.shutdown()
    child.wait(10)
    return sent, elapsed, cpu, wall, counters, in_frames


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--seconds", type=float, default=3.0)
    parser.add_argument("--send", nargs=3, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.send:
        send(args.send[0], int(args.send[1]), float(args.send[2]))
        return 0
    report = Report()
    sent, elapsed, cpu, wall, counters, in_frames = stream(
        "natnet", args.seconds, device_xml, DeviceKind.POSITION
    )
    print(f"OptiTrack: {sent:,} frames of {BODIES} bodies and {MARKERS} markers in {elapsed:.2f} s")
    report.figure(
        "OptiTrack: frames sent per second",
        sent / elapsed,
        "/s",
        target=RATE * 0.99,
        higher_is_better=True,
    )
    report.figure(
        "OptiTrack: frames lost (sent - decoded)", sent - counters["frames"], "", target=0
    )
    report.figure("OptiTrack: gaps in the frame numbers", counters["missed_frames"], "", target=0)
    report.figure(
        "OptiTrack: decoded frames not in the frames", counters["frames"] - in_frames, "", target=0
    )
    report.figure("OptiTrack: driver process CPU (one core = 100 %)", cpu / wall * 100, "%")

    writer = FrameWriter("motion", BODIES, MARKERS)
    packets = [writer.frame(n) for n in range(1, 101)]
    start = time.perf_counter()
    for _ in range(10):
        for p in packets:
            decode_frame(p, (4, 1))
    decoded = 1000 / (time.perf_counter() - start)
    plain = struct.Struct(f"<{len(packets[0]) // 4}i")
    start = time.perf_counter()
    for _ in range(10):
        for p in packets:
            plain.unpack_from(p[: plain.size])
    baseline = 1000 / (time.perf_counter() - start)
    report.figure("OptiTrack: frames decoded per second", decoded, "/s")
    report.ratio("OptiTrack: decoding / bare struct unpack", decoded, baseline)

    sent, elapsed, cpu, wall, counters, in_frames = stream(
        "tuio", args.seconds, tuio_xml, DeviceKind.DIGITAL
    )
    print(f"TUIO: {sent:,} bundles of {CURSORS} cursors in {elapsed:.2f} s")
    report.figure(
        "TUIO: bundles sent per second",
        sent / elapsed,
        "/s",
        target=TUIO_RATE * 0.99,
        higher_is_better=True,
    )
    report.figure(
        "TUIO: bundles lost (sent - received)", sent - counters["datagrams"], "", target=0
    )
    report.figure("TUIO: bad datagrams", counters["bad_datagrams"], "", target=0)
    report.figure(
        "TUIO: received bundles not in the frames", counters["datagrams"] - in_frames, "", target=0
    )
    report.figure("TUIO: driver process CPU (one core = 100 %)", cpu / wall * 100, "%")
    report.exit()
    return 0


if __name__ == "__main__":
    sys.exit(main())
