"""Benchmark of the bundled OptiTrack (NatNet) driver through the input manager.

A sender process sends 240 NatNet frames/s, each with 32 moving rigid bodies and 100
unidentified markers, to an optitrack device (32 body units and 100 marker units) on
loopback while the input manager runs frames at 60 Hz. Targets: the rate is sustained, no
frame is lost (frames sent = frames decoded = samples in the frames, no gap in the frame
numbers). Prints the driver process's share of one core and the decoder's rate against a
baseline measured in the same run (a bare struct unpack of the same packets' numbers).

Run from the repository root: python bench/bench_natnet.py [--seconds 3]
Exit status 1 when a target is missed.
"""

from __future__ import annotations

import argparse
import socket
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from common import REPO, Report

sys.path.insert(0, str(REPO / "drivers"))

from OptiTrack_drv.emulator import FrameWriter
from OptiTrack_drv.standalone import decode_frame

from gadgetctl.input import DeviceKind, InputManager, ManagerOptions

RATE = 240.0
BODIES, MARKERS = 32, 100
FRAME_RATE = 60.0


def send(port: int, seconds: float) -> None:
    writer = FrameWriter("motion", BODIES, MARKERS)
    packets = [writer.frame(n) for n in range(1, 241)]
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    print("ready", flush=True)
    sys.stdin.readline()
    total, start = int(RATE * seconds), time.perf_counter()
    for i in range(total):
        delay = start + i / RATE - time.perf_counter()
        if delay > 0:
            time.sleep(delay)
        packet = packets[i % len(packets)]
        sock.sendto(packet[:4] + struct.pack("<i", i + 1) + packet[8:], ("127.0.0.1", port))
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
        f'</input_manager><optitrack name="Bench" version="2"><port>{port}</port>{bodies}{markers}'
        "</optitrack></elements></configuration>\n"
    )


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--seconds", type=float, default=3.0)
    parser.add_argument("--send", nargs=2, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.send:
        send(int(args.send[0]), float(args.send[1]))
        return 0
    report = Report()
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    child = subprocess.Popen(
        [sys.executable, __file__, "--send", str(port), str(args.seconds)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    assert child.stdout.readline().strip() == "ready"
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bench.jconf"
        path.write_text(device_xml(port))
        options = ManagerOptions(retry_interval=None, entry_points=False)
        manager, configuration = InputManager.from_files([path], options=options)
        manager.configure(configuration)
        assert not manager.pending(), [p.message for p in manager.pending()]
        dev = manager.device("Bench")
        in_frames = 0

        def count(m: InputManager) -> bool:
            nonlocal in_frames
            in_frames += len(dev.store.frame(DeviceKind.POSITION))
            return True

        manager.run(FRAME_RATE, frames=1, on_frame=count)
        cpu0, wall0 = time.process_time(), time.perf_counter()
        child.stdin.write("go\n")
        child.stdin.flush()
        sent_line: list[str] = []
        import threading

        reader = threading.Thread(target=lambda: sent_line.append(child.stdout.readline()))
        reader.start()
        manager.run(FRAME_RATE, on_frame=lambda m: count(m) and not sent_line)
        cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
        sent, elapsed = int(sent_line[0].split()[0]), float(sent_line[0].split()[1])
        deadline = time.perf_counter() + 1.0
        while dev.counters["frames"] < sent and time.perf_counter() < deadline:
            manager.update()
            count(manager)
            time.sleep(1 / FRAME_RATE)
        for _ in range(2):
            manager.update()
            count(manager)
        counters = dev.counters
        manager.shutdown()
    child.wait(10)
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
            decode_frame(p)
    decoded = 1000 / (time.perf_counter() - start)
    plain = struct.Struct(f"<{len(packets[0]) // 4}i")
    start = time.perf_counter()
    for _ in range(10):
        for p in packets:
            plain.unpack_from(p[: plain.size])
    baseline = 1000 / (time.perf_counter() - start)
    report.figure("OptiTrack: frames decoded per second", decoded, "/s")
    report.ratio("OptiTrack: decoding / bare struct unpack", decoded, baseline)
    report.exit()
    return 0


if __name__ == "__main__":
    sys.exit(main())
