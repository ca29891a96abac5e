"""Issue 12 benchmark: start-up of the embedded input manager is linear in configuration size.

For N = 1,000, 5,000 and 20,000 elements (groups of four: a `waveform_device`, a
`position_proxy` and a `digital_proxy` of it, and an alias of the position proxy, written
alias first so that the alias waits for its proxy), each size in a fresh process: load the
configuration, configure and start the manager through a monitor session (what `monitor`
does) and run the first frame. Prints the time per element of each phase and in total, the
peak resident memory, and the ratio of the time per element at the largest size to that at
the smallest (target: within 1.5x), the smallest size being the baseline of the same run.

    python bench/bench_startup.py [--sizes 1000 5000 20000]
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import tempfile
from pathlib import Path

from common import Report

HEAD = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="startup">
   <elements>
"""
GROUP = """      <alias name="Alias {i}" version="1"><proxy>Wave {i} Position</proxy></alias>
      <position_proxy name="Wave {i} Position" version="1"><device>Wave {i}</device><unit>0</unit></position_proxy>
      <digital_proxy name="Wave {i} Button" version="1"><device>Wave {i}</device><unit>0</unit></digital_proxy>
      <waveform_device name="Wave {i}" version="1"><rate>60.0</rate><seed>{i}</seed><button_period>0.5</button_period><position_path>circle</position_path></waveform_device>
"""
PER_GROUP = 4
SIZES = (1_000, 5_000, 20_000)
TARGET_RATIO = 1.5


def configuration_text(elements: int) -> str:
    groups = elements // PER_GROUP
    return (
        HEAD
        + "".join(GROUP.format(i=i) for i in range(groups))
        + "   </elements>\n</configuration>\n"
    )


def measure_one(elements: int) -> dict[str, float]:
    """Start-up phases of one size, in this process (peak memory is the process's)."""
    from gadgetctl.input.clock import now
    from gadgetctl.input.manager import InputManager, ManagerOptions
    from gadgetctl.monitor.session import MonitorSession

    with tempfile.TemporaryDirectory(prefix="gadgetctl-bench-") as tmp:
        path = Path(tmp) / "startup.jconf"
        path.write_text(configuration_text(elements))
        t0 = now()
        manager, configuration = InputManager.from_files(
            [path], options=ManagerOptions(retry_interval=None)
        )
        t1 = now()
        session = MonitorSession(manager, configuration)
        selected = session.start()
        t2 = now()
        session.step()
        t3 = now()
    try:
        assert len(configuration.elements) == elements, len(configuration.elements)
        assert not manager.pending(), [p.message for p in manager.pending()[:3]]
        assert len(selected) == elements, len(selected)
    finally:
        manager.shutdown()
    peak_kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return {
        "load": t1 - t0,
        "configure": t2 - t1,
        "frame": t3 - t2,
        "total": t3 - t0,
        "peak_mb": peak_kb / 1024,
    }


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--sizes", type=int, nargs="+", default=list(SIZES))
    parser.add_argument(
        "--one", type=int, help=argparse.SUPPRESS
    )  # child: measure one size, print JSON
    args = parser.parse_args()
    if args.one:
        print(json.dumps(measure_one(args.one)))
        return 0

    report = Report()
    results: dict[int, dict[str, float]] = {}
    print(
        "start-up: load, configure and start (monitor session), first frame; one process per size"
    )
    for size in args.sizes:
        done = subprocess.run(
            [sys.executable, __file__, "--one", str(size)], capture_output=True, text=True
        )
        if done.returncode != 0:
            print(done.stderr)
            return 1
        results[size] = figures = json.loads(done.stdout.strip().splitlines()[-1])
        per = {k: figures[k] / size * 1e6 for k in ("load", "configure", "frame", "total")}
        print(
            f"  N = {size:>6}: total {figures['total']:7.2f} s  per element: total {per['total']:6.1f} us "
            f"(load {per['load']:.1f}, configure {per['configure']:.1f}, first frame {per['frame']:.1f})  "
            f"peak {figures['peak_mb']:.0f} MB"
        )
    small, large = min(results), max(results)
    per_small = results[small]["total"] / small
    per_large = results[large]["total"] / large
    report.figure(f"time per element, N = {small}", per_small * 1e6, "us")
    report.figure(f"time per element, N = {large}", per_large * 1e6, "us")
    report.figure(
        f"ratio per element N = {large} / N = {small}",
        per_large / per_small,
        "x",
        target=TARGET_RATIO,
    )
    report.figure(f"peak memory, N = {large}", results[large]["peak_mb"], "MB")
    report.figure(
        f"peak memory per element above N = {small}",
        (results[large]["peak_mb"] - results[small]["peak_mb"]) * 1024 / (large - small),
        "KB",
    )
    report.exit()
    return 0


if __name__ == "__main__":
    sys.exit(main())
