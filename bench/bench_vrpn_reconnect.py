"""Issue 11 item 2 benchmark: how soon VRPN_drv samples resume after its server returns.

A VRPN server (the driver's scripted emulator, 100 Hz tracker) runs in a child process on a
fixed loopback port; an input manager with one ``vrpn`` element reads it and runs frames at
60 Hz. The server is killed (SIGKILL, no goodbye), the device must show faulted, then the
server is started again: the figure is the time from the restarted server's first moment
of listening to the first new position sample in the input manager's frames, for the
default connection (UDP request and call-back) and for ``tcp://``. Target: at most 2 s.

Baseline, measured in the same run: a bare :class:`gadgetctl.vrpn.VrpnClient` connecting to
an already running server (the least a reconnection can take).

Run from the repository root: python bench/bench_vrpn_reconnect.py [--rounds 3]
Exit status 1 when a target is missed.
"""

from __future__ import annotations

import argparse
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from common import REPO, Report

from gadgetctl.input import DeviceKind, InputManager, ManagerOptions
from gadgetctl.vrpn import VrpnClient

SERVER = f"""
import sys, time
sys.path.insert(0, {str(REPO / "drivers")!r})
from VRPN_drv.emulator import VrpnEmulator
emu = VrpnEmulator(int(sys.argv[1]), scenario="motion", rate=100, sensors=2, buttons=0, channels=0)
emu.start()
print("ready", time.monotonic(), flush=True)
while True:
    time.sleep(1)
"""

CONFIG = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="bench">
<elements>
<input_manager name="IM" version="2"><driver>VRPN_drv</driver></input_manager>
<vrpn name="V" version="3"><tracker_server>Tracker0@{location}</tracker_server>
<button_server></button_server><analog_server></analog_server>
<tracker_count>2</tracker_count><button_count>0</button_count><analog_count>0</analog_count></vrpn>
</elements>
</configuration>
"""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start_server(port: int) -> tuple[subprocess.Popen, float]:
    proc = subprocess.Popen(
        [sys.executable, "-c", SERVER, str(port)], stdout=subprocess.PIPE, text=True
    )
    line = proc.stdout.readline().split()
    if not line or line[0] != "ready":
        raise RuntimeError("the VRPN server did not start")
    return proc, float(line[1])


def frames_until(manager: InputManager, done, timeout: float) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        manager.update()
        if done():
            return True
        time.sleep(1 / 60)
    return False


def resume_times(scheme: str, rounds: int, workdir: Path) -> list[float]:
    port = free_port()
    path = workdir / f"bench{len(scheme)}.jconf"
    path.write_text(CONFIG.format(location=f"{scheme}127.0.0.1:{port}"))
    manager, configuration = InputManager.from_files(
        [path], options=ManagerOptions(entry_points=False)
    )
    times = []
    server, _ = start_server(port)
    try:
        manager.configure(configuration)
        device = manager.device("V")
        total = lambda: device.store.total(DeviceKind.POSITION)  # noqa: E731
        if not frames_until(manager, lambda: total() > 10, 10):
            raise RuntimeError("no samples from the first server")
        for _ in range(rounds):
            server.kill()
            server.wait()
            if not frames_until(
                manager, lambda: manager.status("V").state in ("faulted", "reconnecting"), 10
            ):
                raise RuntimeError("the device did not notice the server going away")
            time.sleep(0.5)  # the server stays away a moment
            before = total()
            server, ready = start_server(port)
            if not frames_until(manager, lambda b=before: total() > b + 1, 10):
                raise RuntimeError("samples did not resume within 10 s")
            times.append(time.monotonic() - ready)
    finally:
        server.kill()
        server.wait()
        manager.shutdown()
    return times


def baseline(rounds: int) -> float:
    port = free_port()
    server, _ = start_server(port)
    try:
        times = []
        for _ in range(rounds):
            start = time.monotonic()
            client = VrpnClient(f"127.0.0.1:{port}", ["Tracker0"])
            if not client.wait_connected(5):
                raise RuntimeError("baseline client did not connect")
            while not any(m.type == "vrpn_Tracker Pos_Quat" for m in client.poll(0.05)):
                pass
            times.append(time.monotonic() - start)
            client.close()
        return statistics.median(times)
    finally:
        server.kill()
        server.wait()


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    report = Report()
    base = baseline(args.rounds)
    report.figure("baseline: fresh client to first pose (running server)", base * 1000, "ms")
    with tempfile.TemporaryDirectory() as tmp:
        for scheme, label in (("", "lob"), ("tcp://", "tcp")):
            times = resume_times(scheme, args.rounds, Path(tmp))
            report.figure(
                f"{label}: server back -> samples again, median of {len(times)}",
                statistics.median(times) * 1000,
                "ms",
                target=2000,
            )
            report.figure(
                f"{label}: server back -> samples again, worst",
                max(times) * 1000,
                "ms",
                target=2000,
            )
            report.ratio(f"{label}: median resume / baseline", statistics.median(times), base)
    report.exit()
    return 0


if __name__ == "__main__":
    sys.exit(main())
