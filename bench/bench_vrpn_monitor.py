"""Benchmark (issue 27, goal 1): VRPN ingest by `gadgetctl monitor vrpn:` as a user runs it.

`gadgetctl serve` (its own process, loopback) serves a 32-sensor tracker at 1 kHz (32,000
pose reports/s). `gadgetctl monitor vrpn:Tracker32@127.0.0.1:PORT` reads it the default
way, the UDP connection request with a UDP channel (the poses come by UDP), writing one
ndjson frame record per frame. Measured over a window that leaves out start-up (imports,
the server being asked for the layout):

* the monitor process's share of a core (all its threads), target <= 20 %;
* reports lost, target 0: the monitor's own count of its losses (samples over its per-frame
  cap, datagrams the kernel dropped for its UDP socket), what serve could not queue for it,
  and ticks missing between the first and last sample the monitor published;
* as a baseline measured in the same run: a raw reader of the same kind of socket (lob, a
  UDP channel, a `recv` loop that counts datagrams and decodes nothing), its share of a core
  and its CPU per report, and the monitor's CPU per report over it.

* where one was built by hand outside this repository, a C++ VRPN client as a second
  baseline: set ``VRPN_COUNT_CLIENT`` to a program that takes ``Device@host SECONDS``, reads
  the tracker with VRPN's own ``vrpn_Tracker_Remote`` and prints one line, ``reports cpu_seconds
  wall_seconds``. gadgetctl ships neither VRPN's code nor anything that builds it.

``--load N`` keeps N extra processes spinning meanwhile (N = 2 on this 2-core machine is
"load 2": both cores busy besides the benchmark). Exit status 1 when a target is missed.

Run: python bench/bench_vrpn_monitor.py [--seconds 8] [--load 2]
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import select
import socket
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from bench_vrpn import Served, cpu_seconds, ingest_config
from common import GADGETCTL, REPO, Report

from gadgetctl.vrpn.wire import lob_request, make_cookie, pack_udp_description

RATE = 1000.0
SENSORS = 32
#: Seconds after the monitor starts before its CPU is counted (imports, the probe).
WARM_UP = 3.0


def _spin(stop_at: float) -> None:
    while time.monotonic() < stop_at:
        pass


class RawLobReader:
    """The cheapest reader of the same stream: connects as the C++ client does (lob, then a
    UDP channel), then only receives, counting datagrams and bytes."""

    def __init__(self, port: int) -> None:
        listener = socket.socket()
        listener.bind(("127.0.0.1", 0))
        listener.listen(1)
        self.udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.udp.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4 << 20)
        self.udp.bind(("127.0.0.1", 0))
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as lob:
            lob.sendto(lob_request("127.0.0.1", listener.getsockname()[1]), ("127.0.0.1", port))
        listener.settimeout(10)
        self.tcp, _ = listener.accept()
        listener.close()
        self.tcp.sendall(
            make_cookie() + pack_udp_description("127.0.0.1", self.udp.getsockname()[1])
        )
        self.datagrams = 0
        self.bytes = 0

    def run(self, seconds: float) -> tuple[float, float]:
        """Receive for ``seconds``; (CPU seconds of this thread, wall seconds)."""
        udp, tcp = self.udp, self.tcp
        udp.setblocking(False)
        tcp.setblocking(False)
        cpu0, wall0 = time.thread_time(), time.perf_counter()
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            ready, _, _ = select.select([udp, tcp], [], [], 0.1)
            if tcp in ready:
                try:
                    tcp.recv(1 << 20)
                except BlockingIOError:
                    pass
            if udp in ready:
                while True:
                    try:
                        data = udp.recv(2048)
                    except BlockingIOError:
                        break
                    self.datagrams += 1
                    self.bytes += len(data)
        return time.thread_time() - cpu0, time.perf_counter() - wall0

    def close(self) -> None:
        self.tcp.close()
        self.udp.close()


def reports_in(byte_count: int) -> int:
    """Pose reports in ``byte_count`` bytes of pose datagrams (88 bytes each)."""
    return byte_count // 88


def monitor_run(port: int, seconds: float) -> tuple[float, float, dict, list[dict]]:
    """Run the monitor; (its CPU seconds over the window, the window's wall seconds, its
    stats record, its frame records)."""
    command = [
        *GADGETCTL,
        "monitor",
        f"vrpn:Tracker32@127.0.0.1:{port}",
        "--duration",
        f"{WARM_UP + seconds + 0.5:g}",
        "--format",
        "ndjson",
        "--per-frame",
    ]
    with tempfile.TemporaryFile("w+") as out:
        process = subprocess.Popen(command, cwd=REPO, stdout=out, stderr=subprocess.PIPE, text=True)
        time.sleep(WARM_UP)
        cpu0, wall0 = cpu_seconds(process.pid), time.perf_counter()
        time.sleep(seconds)
        cpu = cpu_seconds(process.pid) - cpu0
        wall = time.perf_counter() - wall0
        _, err = process.communicate(timeout=60)
        if process.returncode not in (0, 1):
            sys.exit(f"monitor failed ({process.returncode}): {err[-500:]}")
        out.seek(0)
        records = [json.loads(line) for line in out if line.strip()]
    (stats,) = [r for r in records if r["type"] == "stats"]
    frames = [r for r in records if r["type"] == "frame"]
    return cpu, wall, stats, frames


def cpp_client(port: int, seconds: float) -> tuple[int, float, float] | None:
    """(reports, CPU seconds, wall seconds) of VRPN's C++ client, when built (see above)."""
    program = os.environ.get("VRPN_COUNT_CLIENT")
    if not program or not Path(program).is_file():
        return None
    done = subprocess.run(
        [program, f"Tracker32@127.0.0.1:{port}", f"{seconds:g}"],
        capture_output=True,
        text=True,
        timeout=seconds + 30,
    )
    if done.returncode != 0:
        sys.exit(f"{program} failed ({done.returncode}): {done.stderr[-500:]}")
    reports, cpu, wall = done.stdout.split()
    return int(reports), float(cpu), float(wall)


def missing_ticks(device: dict) -> int:
    """Ticks missing between the first and the newest sample the monitor published (each
    sample keeps its VRPN time: serve's ticks are exactly 1/RATE apart)."""
    span = float(device["newest_timestamp"]) - float(device["first_timestamp"])
    return max(0, round(span * RATE) + 1 - int(device["count"]))


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--seconds", type=float, default=8.0)
    parser.add_argument("--load", type=int, default=0, help="extra spinning processes")
    args = parser.parse_args()
    print(
        f"load average before the run: {' '.join(f'{x:.2f}' for x in os.getloadavg())} "
        f"on {os.cpu_count()} cores; {args.load} extra spinning processes"
    )
    report = Report()
    spinners = [
        multiprocessing.Process(
            target=_spin, args=(time.monotonic() + 3 * args.seconds + 30,), daemon=True
        )
        for _ in range(args.load)
    ]
    for p in spinners:
        p.start()
    try:
        with tempfile.TemporaryDirectory() as tmp:
            config = Path(tmp) / "ingest.jconf"
            config.write_text(ingest_config(RATE))
            served = Served(config)
            try:
                raw = RawLobReader(served.port)
                measured: list[float] = []
                thread = threading.Thread(
                    target=lambda: measured.extend(raw.run(args.seconds)), name="raw reader"
                )
                thread.start()
                thread.join()
                raw.close()
                raw_cpu, raw_wall = measured
                raw_reports = max(1, reports_in(raw.bytes))
                served.wait_disconnects(1)
                cpp = cpp_client(served.port, args.seconds)
                if cpp is not None:
                    served.wait_disconnects(2)
                cpu, wall, stats, _frames = monitor_run(served.port, args.seconds)
                gone = served.wait_disconnects(3 if cpp is not None else 2)[-1]
            finally:
                served.stop()
    finally:
        for p in spinners:
            p.terminate()
            p.join(5)
    device = next(iter(stats["devices"].values()))
    health = device.get("health", {})
    rate = float(device.get("mean_rate") or 0.0)  # samples over the span they cover
    lost = int(device.get("dropped", 0)) + int(gone.get("dropped", 0)) + missing_ticks(device)
    reports = rate * SENSORS * wall
    print(f"  {SENSORS} sensors at {RATE:g} Hz over the lob and a UDP channel, {args.seconds:g} s")
    report.figure("raw recv loop: share of a core", raw_cpu / raw_wall * 100, "%")
    report.figure("raw recv loop: CPU per report", raw_cpu / raw_reports * 1e6, "us")
    report.figure("monitor: ticks per second published", rate, "ticks/s")
    report.figure("monitor: share of a core (whole process)", cpu / wall * 100, "%", target=20)
    report.figure("monitor: reports lost", lost, "reports", target=0)
    report.figure("monitor: kernel drops on its UDP socket", health.get("kernel_dropped", 0), "")
    report.figure("monitor: p99 interval between samples", device["p99_interval"] * 1e3, "ms")
    report.ratio(
        "monitor CPU per report / raw recv loop",
        cpu / max(1.0, reports),
        raw_cpu / raw_reports,
    )
    if cpp is not None:
        cpp_reports, cpp_cpu, cpp_wall = cpp
        report.figure("C++ vrpn_Tracker_Remote: reports per second", cpp_reports / cpp_wall, "/s")
        report.figure("C++ vrpn_Tracker_Remote: share of a core", cpp_cpu / cpp_wall * 100, "%")
        report.ratio(
            "monitor CPU per report / C++ client",
            cpu / max(1.0, reports),
            cpp_cpu / max(1, cpp_reports),
        )
    else:
        print("  (C++ client not measured: VRPN_COUNT_CLIENT names no built program)")
    report.exit()


if __name__ == "__main__":
    main()
