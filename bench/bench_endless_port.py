"""A joystick port that never runs dry (/dev/zero): junk skipping and the monitor's duration.

1. Decoder: 16 MB of zeros fed in 8 KB chunks (one sample()'s bound) to the joydev decoder;
   the rate at which junk is skipped, against a baseline measured in the same run (copying
   the same chunks into a bytearray and dropping them, the least any reader does).
2. End to end: `gadgetctl monitor --duration 1` with the joystick's port_name set to
   /dev/zero, against the same command on the bundled waveform example (no hardware). The
   campaign of issue 13 measured 3.7 s: the device thread read /dev/zero for ever.

Run from the repository root: python bench/bench_endless_port.py
Exit status 1 when a target is missed.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

from common import GADGETCTL, REPO, Report, command_time

sys.path.insert(0, str(REPO / "drivers"))

from LinuxJoydev_drv.standalone import EventDecoder

JUNK = 16 << 20
CHUNK = 8 << 10
TARGET_MB_S = 50.0
TARGET_EXTRA_S = 0.5  # over the waveform run, which starts no device thread of a driver


def decoder_rate() -> tuple[float, float]:
    junk = bytes(JUNK)
    best, base = float("inf"), float("inf")
    for _ in range(3):
        decoder = EventDecoder(clock=lambda: 0.0)
        start = time.perf_counter()
        for i in range(0, JUNK, CHUNK):
            assert not decoder.feed(junk[i : i + CHUNK])
        best = min(best, time.perf_counter() - start)
        buffer = bytearray()
        start = time.perf_counter()
        for i in range(0, JUNK, CHUNK):
            buffer += junk[i : i + CHUNK]
            del buffer[: len(buffer) - 7]
        base = min(base, time.perf_counter() - start)
    return JUNK / 1e6 / best, JUNK / 1e6 / base


def main() -> int:
    report = Report()
    ours, baseline = decoder_rate()
    report.figure("joydev decoder skipping zeros", ours, "MB/s", target=TARGET_MB_S,
                  higher_is_better=True)  # fmt: skip
    report.ratio("decoder against copy-and-drop", ours, baseline)
    example = (REPO / "drivers" / "LinuxJoydev_drv" / "example.jconf").read_text()
    with tempfile.TemporaryDirectory() as tmp:
        config = Path(tmp) / "zero.jconf"
        config.write_text(example.replace("/tmp/gadgetctl-js0", "/dev/zero"))
        run = ["monitor", "--duration", "1", "--format", "ndjson"]
        zero = command_time([*GADGETCTL, *run[:1], str(config), *run[1:]], repeat=3, cwd=REPO)
        waveform = command_time(
            [*GADGETCTL, *run[:1], str(REPO / "examples" / "waveform.jconf"), *run[1:]],
            repeat=3,
            cwd=REPO,
        )
    report.figure("monitor --duration 1, joystick on /dev/zero", zero, "s")
    report.figure("monitor --duration 1, waveform example (baseline)", waveform, "s")
    report.figure("extra time for /dev/zero", zero - waveform, "s", target=TARGET_EXTRA_S)
    report.ratio("/dev/zero against the waveform example", zero, waveform)
    return 0 if report.ok else 1


if __name__ == "__main__":
    sys.exit(main())
