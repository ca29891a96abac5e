"""Issue 26 item 9 benchmark: memory of `gadgetctl validate` on a large configuration.

`gadgetctl validate FILE` on a chain of 200,000 aliases (12.7 MB, each naming the one before,
the first a missing name: every alias is checked, wrongly typed and pending, the worst case
of the checks) must stay under 1 KB of peak resident memory per element above the
interpreter's baseline, measured in the same run: the same command on a chain of 1,000
aliases (Python, gadgetctl's imports, the definitions and a small check). Figures of each
run are its own (wait4), best of two; the bare interpreter (`python -c pass`) is printed
for reference.

    python bench/bench_validate_memory.py [ELEMENTS]
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

from bench_validate_scale import HEAD, TAIL, chain
from common import GADGETCTL, Report, command_peak_memory

ELEMENTS = 200_000
BASELINE_ELEMENTS = 1_000
TARGET_BYTES_PER_ELEMENT = 1024
FINDINGS = (0, 1)  # validate exits 1 on the chain's findings


def peak(args: list[str], runs: int = 2) -> tuple[float, float, int]:
    """The run with the smallest peak memory of ``runs`` (another process's load can only
    add to it)."""
    return min((command_peak_memory(args, FINDINGS) for _ in range(runs)), key=lambda r: r[2])


def main() -> None:
    count = int(sys.argv[1]) if len(sys.argv) > 1 else ELEMENTS
    report = Report()
    with tempfile.TemporaryDirectory(prefix="gadgetctl-bench-") as tmp:
        big = Path(tmp) / f"chain-{count}.jconf"
        big.write_text(HEAD + chain(count) + TAIL)
        size = big.stat().st_size
        small = Path(tmp) / f"chain-{BASELINE_ELEMENTS}.jconf"
        small.write_text(HEAD + chain(BASELINE_ELEMENTS) + TAIL)
        bare = peak([sys.executable, "-c", "pass"])
        base = peak([*GADGETCTL, "validate", str(small)])
        run = peak([*GADGETCTL, "validate", str(big)])
    mib = 1024 * 1024
    print(f"gadgetctl validate, a chain of {count:,} aliases ({size / mib:.1f} MiB)")
    report.figure("the interpreter alone (python -c pass), peak", bare[2] / mib, "MiB")
    report.figure(f"baseline: {BASELINE_ELEMENTS:,} aliases, peak", base[2] / mib, "MiB")
    report.figure(f"{count:,} aliases, peak", run[2] / mib, "MiB")
    report.figure(f"{count:,} aliases, CPU time (user + system)", run[1], "s")
    report.figure(
        "peak above the baseline, per element",
        (run[2] - base[2]) / count,
        "B",
        target=TARGET_BYTES_PER_ELEMENT,
    )
    report.ratio(f"peak, {count:,} / {BASELINE_ELEMENTS:,} aliases", run[2], base[2])
    report.exit()


if __name__ == "__main__":
    main()
