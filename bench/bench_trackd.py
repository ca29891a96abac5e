"""trackd: 16 sensors in shared memory, polled at 1 kHz (issue 15's target).

The emulator writes the tracker segment 1000 times a second in its own process; this process
runs an input manager whose trackd_sensor device polls the segment every millisecond. Printed:
the poll rate reached, the rate of changed segments decoded, this process's share of one core
(the emulator's is not counted), and the decoder's cost per segment against a baseline measured
in the same run (copying the segment's bytes and unpacking its floats with one struct call).
"""

from __future__ import annotations

import os
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from common import GADGETCTL, REPO, Report

sys.path.insert(0, str(REPO / "drivers"))

from Trackd_drv.emulator import sensor_pose
from Trackd_drv.standalone import encode_tracker, pose_matrices, tracker_poses

from gadgetctl.input import InputManager, ManagerOptions

SENSORS = 16
RATE = 1000.0
SECONDS = float(os.environ.get("BENCH_SECONDS", "5"))
CONFIG = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="bench">
<elements>
<input_manager name="IM" version="2"><driver>Trackd_drv</driver></input_manager>
<trackd_sensor name="Bench" version="1"><shared_memory_key>{key}</shared_memory_key></trackd_sensor>
</elements>
</configuration>
"""


def wait_for(proc: subprocess.Popen, text: str, timeout: float = 30.0) -> None:
    deadline, seen = time.monotonic() + timeout, ""
    while text not in seen:
        if time.monotonic() > deadline:
            raise RuntimeError(f"the emulator did not say {text!r}: {seen!r}")
        line = proc.stdout.readline()
        if not line:
            raise RuntimeError(f"the emulator ended: {seen!r}")
        seen += line


def per_call(fn, n: int = 2000) -> float:
    start = time.perf_counter()
    for _ in range(n):
        fn()
    return (time.perf_counter() - start) / n


def main() -> int:
    report = Report()
    key = 0x4B000000 + (os.getpid() & 0xFFFFF)
    emulator = subprocess.Popen(
        [
            *GADGETCTL,
            "emulate",
            "Trackd_drv",
            "--sensors",
            str(SENSORS),
            "--rate",
            str(RATE),
            "--sensor-key",
            str(key),
            "--controller-key",
            str(key + 1),
        ],
        cwd=REPO,
        stdout=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    try:
        wait_for(emulator, "Press Ctrl-C")
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "bench.jconf"
            path.write_text(CONFIG.format(key=key))
            options = ManagerOptions(retry_interval=None, entry_points=False)
            manager, configuration = InputManager.from_files([path], options=options)
            manager.configure(configuration)
            assert not manager.pending(), [p.message for p in manager.pending()]
            device = manager.device("Bench")
            manager.run(60.0, frames=1)
            polls0, records0 = device.polls, device.records
            cpu0, wall0 = time.process_time(), time.perf_counter()
            manager.run(60.0, frames=int(SECONDS * 60))
            cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
            polls, records = device.polls - polls0, device.records - records0
            bad, faults = device.bad_records, device.faults
            manager.shutdown()
    finally:
        emulator.terminate()
        emulator.wait(15)
    print(
        f"  {SENSORS} sensors, emulator writing at {RATE:g} Hz, device polling every 1 ms, {wall:.1f} s"
    )
    report.figure(
        "polls of the segment per second",
        polls / wall,
        "/s",
        target=0.8 * RATE,
        higher_is_better=True,
    )
    report.figure(
        "changed segments decoded per second",
        records / wall,
        "/s",
        target=0.5 * RATE,
        higher_is_better=True,
    )
    report.figure("driver process CPU (one core = 100 %)", cpu / wall * 100, "%")
    report.figure("bad records, faults", bad + faults, "", target=0)
    data = encode_tracker([sensor_pose(5, i) for i in range(SENSORS)], (1, 2))
    floats = struct.Struct(f"=7I{SENSORS * 10}f")
    baseline = per_call(lambda: floats.unpack(bytes(data)[: floats.size]))
    decode = per_call(lambda: tracker_poses(data))
    matrices = per_call(lambda: pose_matrices(tracker_poses(data)))
    report.figure("decode one 16-sensor segment", decode * 1e6, "us")
    report.figure("decode + 16 matrices", matrices * 1e6, "us")
    report.ratio("decode vs one struct unpack of the same bytes (baseline)", decode, baseline)
    report.ratio("decode + matrices vs the baseline", matrices, baseline)
    return 0 if report.ok else 1


if __name__ == "__main__":
    sys.exit(main())
