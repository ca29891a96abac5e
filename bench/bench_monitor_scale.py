"""Issue 27 goal 3: `monitor --duration 0.5` against `validate` of the same configuration.

N waveform devices (rate 10 Hz, one position path `circle`), each read by a position proxy,
for N = 1,000, 2,000, 5,000 and 10,000. For each N, in the same run and each in its own
process: `gadgetctl validate FILE` (twice), then `gadgetctl monitor FILE --duration 0.5` with
`--format table` and `--format ndjson`, twice each (output to a pipe that is read and thrown
away; of two runs, the least CPU and the most memory count).
Printed: CPU seconds (user + system of that process alone, from wait4) and peak memory
(maxrss), the ratios to validate's, and per doubling of N the ratio of monitor's CPU time
to the previous size's (linear: about 2x; the issue measured 26x for 1,000 -> 2,000).

Targets (at 10,000 devices): CPU <= 3x validate's, peak memory <= 2x validate's, and two
runs of the same command within 20 % of each other in CPU time.

    python bench/bench_monitor_scale.py [N ...]
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from common import GADGETCTL, Report

SIZES = (1_000, 2_000, 5_000, 10_000)
TARGET_SIZE = 10_000
CPU_TARGET = 3.0
MEMORY_TARGET = 2.0
SPREAD_TARGET = 0.20
DURATION = "0.5"
#: Linear growth is 2x per doubling of N (less while start-up dominates).
DOUBLING_TARGET = 2.5


def configuration(count: int) -> str:
    """The repro of issue 27: ``count`` waveform devices, each with a position proxy."""
    out = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        '<?org-vrjuggler-jccl-settings configuration.version="3.0"?>',
        '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="scale">',
        "<elements>",
    ]
    for i in range(count):
        out.append(
            f'<waveform_device name="W{i}" version="1"><rate>10</rate><seed>{i}</seed>'
            "<position_path>circle</position_path></waveform_device>"
        )
        out.append(
            f'<position_proxy name="P{i}" version="1"><device>W{i}</device><unit>0</unit>'
            "</position_proxy>"
        )
    out.append("</elements></configuration>")
    return "\n".join(out) + "\n"


def measure(args: list[str], ok: tuple[int, ...] = (0,)) -> tuple[float, float]:
    """CPU seconds (user + system) and peak resident memory (MB) of one run of ``args``,
    measured for that process alone; output read from a pipe and discarded."""
    with tempfile.TemporaryFile() as err:
        process = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=err)
        assert process.stdout is not None
        while process.stdout.read(1 << 16):
            pass
        _, status, usage = os.wait4(process.pid, 0)
        process.returncode = os.waitstatus_to_exitcode(status)
        process.stdout.close()
        if process.returncode not in ok:
            err.seek(0)
            sys.exit(
                f"{' '.join(args)} failed ({process.returncode}): "
                f"{err.read().decode(errors='replace')[-500:]}"
            )
    return usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024


def main() -> None:
    sizes = [int(a) for a in sys.argv[1:]] or list(SIZES)
    report = Report()
    previous: dict[str, tuple[float, int]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for count in sizes:
            path = Path(tmp) / f"scale{count}.jconf"
            path.write_text(configuration(count), encoding="utf-8")
            # two runs taken as the monitor's are (the least CPU, the most memory): the ratios
            # moved with the noise of a single validate
            bases = [measure([*GADGETCTL, "validate", str(path)]) for _ in range(2)]
            base_cpu, base_mem = min(b[0] for b in bases), max(b[1] for b in bases)
            print(f"N = {count:,}: validate {base_cpu:.2f} s CPU, {base_mem:.0f} MB")
            for fmt in ("table", "ndjson"):
                command = [*GADGETCTL, "monitor", str(path), "--duration", DURATION]
                runs = [measure([*command, "--format", fmt]) for _ in range(2)]
                cpu = min(r[0] for r in runs)
                memory = max(r[1] for r in runs)
                spread = (max(r[0] for r in runs) - cpu) / cpu
                print(
                    f"  monitor --format {fmt}: {', '.join(f'{r[0]:.2f}' for r in runs)} s CPU, "
                    f"{', '.join(f'{r[1]:.0f}' for r in runs)} MB"
                )
                final = count == TARGET_SIZE
                report.figure(
                    f"{fmt}: CPU / validate's",
                    cpu / base_cpu,
                    "x",
                    target=CPU_TARGET if final else None,
                )
                report.figure(
                    f"{fmt}: peak memory / validate's",
                    memory / base_mem,
                    "x",
                    target=MEMORY_TARGET if final else None,
                )
                report.figure(
                    f"{fmt}: CPU spread of two runs",
                    spread * 100,
                    "%",
                    target=SPREAD_TARGET * 100 if final else None,
                )
                if fmt in previous:
                    before, size = previous[fmt]
                    report.figure(
                        f"{fmt}: CPU per doubling of N ({size:,} -> {count:,})",
                        (cpu / before) ** (1 / math.log2(count / size)),
                        "x",
                        target=DOUBLING_TARGET,
                    )
                previous[fmt] = (cpu, count)
    report.exit()


if __name__ == "__main__":
    main()
