"""Helpers shared by the benchmarks."""

from __future__ import annotations

import resource
import shutil
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
CORPUS = REPO.parent / "shared" / "corpus" / "vrjuggler"
GADGETCTL = [sys.executable, "-m", "gadgetctl"]
if (
    shutil.which("gadgetctl")
    and Path(shutil.which("gadgetctl")).parent == Path(sys.executable).parent
):
    GADGETCTL = [shutil.which("gadgetctl")]


def median_time(fn: Callable[[], object], repeat: int = 7) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def command_time(args: list[str], repeat: int = 7, **kwargs) -> float:
    return median_time(lambda: subprocess.run(args, capture_output=True, **kwargs), repeat)


def replicate_corpus(target: Path, copies: int) -> list[Path]:
    """``copies`` copies of the corpus's JCCL files under ``target``."""
    files = []
    for i in range(copies):
        dest = target / f"copy{i}"
        shutil.copytree(CORPUS, dest)
        files += sorted(p for p in dest.rglob("*") if p.suffix in (".jdef", ".jconf"))
    return files


class Report:
    """Prints figures and remembers whether every target was met."""

    def __init__(self) -> None:
        self.ok = True

    def figure(
        self,
        label: str,
        value: float,
        unit: str,
        *,
        target: float | None = None,
        higher_is_better: bool = False,
    ) -> None:
        status = ""
        if target is not None:
            met = value >= target if higher_is_better else value <= target
            self.ok &= met
            status = f"  (target {'>=' if higher_is_better else '<='} {target:g} {unit}: {'met' if met else 'MISSED'})"
        print(f"  {label:<58} {value:>12.4g} {unit}{status}")

    def ratio(self, label: str, ours: float, baseline: float, note: str = "") -> None:
        print(f"  {label:<58} {ours / baseline:>12.3g} x{('  ' + note) if note else ''}")

    def exit(self) -> None:
        sys.exit(0 if self.ok else 1)


def command_cpu(args: list[str], ok: tuple[int, ...] = (0,)) -> tuple[float, float]:
    """Wall-clock and CPU seconds (user + system) of one run of a command; exits the benchmark
    when the command ends with a status outside ``ok`` or reports an internal error."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(args, capture_output=True, text=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode not in ok or "internal error" in done.stderr:
        sys.exit(
            f"{' '.join(args)} failed ({done.returncode}): {(done.stderr or done.stdout)[-500:]}"
        )
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
