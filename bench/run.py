"""Run every benchmark in this folder (`make bench`): each prints its figures, each figure
with its target where it has one (`common.Report`), and exits non-zero when one is missed.
At the end, the figures that missed are listed again with their benchmark, and the exit
status is 1 when any benchmark missed a target or failed.

    python bench/run.py [NAME ...]   # only the benchmarks whose name contains a NAME
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def main() -> int:
    failed: list[str] = []
    missed: list[str] = []
    selected = sys.argv[1:]
    for script in sorted(HERE.glob("bench_*.py")):
        if selected and not any(s in script.stem for s in selected):
            continue
        print(f"\n=== {script.name}", flush=True)
        process = subprocess.Popen(
            [sys.executable, str(script)], cwd=HERE.parent, stdout=subprocess.PIPE, text=True
        )
        assert process.stdout is not None
        for line in process.stdout:  # shown as it comes, kept when it says a target was missed
            sys.stdout.write(line)
            sys.stdout.flush()
            if "MISSED" in line:
                missed.append(f"{script.name}: {line.strip()}")
        if process.wait() != 0:
            failed.append(script.name)
    if missed:
        print("\nfigures that missed their target:")
        for line in missed:
            print(f"  {line}")
    if failed:
        print(f"\nbenchmarks that missed a target or failed: {', '.join(failed)}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
