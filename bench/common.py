"""Helpers shared by the benchmarks."""

from __future__ import annotations

import gc
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


def timed_call(fn: Callable[[], object], clock: Callable[[], float] = time.perf_counter) -> float:
    """Seconds by ``clock`` of one call of ``fn``, which starts without the garbage of the
    calls before it (a full collection first, not timed): a validation's result holds
    reference cycles (elements and their document), which the collector, paused during
    validation, frees only many calls later. Left there, five validations of fifty copies of
    the corpus in one process grew it to 2 GB, and the page faults made the third and later
    calls 30-40 % slower than the first, as no single `gadgetctl validate` process is."""
    gc.collect()
    start = clock()
    fn()
    return clock() - start


def median_time(
    fn: Callable[[], object], repeat: int = 7, clock: Callable[[], float] = time.perf_counter
) -> float:
    """Median seconds of ``repeat`` calls by ``clock`` (``time.process_time``: CPU time of
    this process, steadier than the wall clock on a loaded machine), each a
    :func:`timed_call`."""
    return statistics.median(timed_call(fn, clock) for _ in range(repeat))


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


# Runs a command and reports its own resource use. A child's peak resident memory counts what
# it shared with its parent before exec, so the command is started from this small process,
# never from the benchmark (whose own memory would count).
_PEAK_LAUNCHER = """
import os, sys
pid = os.fork()
if pid == 0:
    try:
        os.execvp(sys.argv[1], sys.argv[1:])
    finally:
        os._exit(127)
_, status, usage = os.wait4(pid, 0)
print(f"@@peak {usage.ru_maxrss} {usage.ru_utime + usage.ru_stime} "
      f"{os.waitstatus_to_exitcode(status)}", file=sys.stderr)
"""


def command_peak_memory(args: list[str], ok: tuple[int, ...] = (0,)) -> tuple[float, float, int]:
    """Wall-clock seconds, CPU seconds (user + system) and peak resident memory in bytes of
    one run of a command (its own figures, from wait4 in a small launcher process); exits
    the benchmark when the command ends with a status outside ``ok`` or reports an internal
    error."""
    start = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-c", _PEAK_LAUNCHER, *args], capture_output=True, text=True
    )
    wall = time.perf_counter() - start
    errors, _, figures = done.stderr.rpartition("@@peak ")
    try:
        maxrss, cpu, status = figures.split()
    except ValueError:
        sys.exit(f"{' '.join(args)}: no figures from the launcher: {done.stderr[-500:]}")
    if int(status) not in ok or "internal error" in errors:
        sys.exit(f"{' '.join(args)} failed ({status}): {(errors or done.stdout)[-500:]}")
    return wall, float(cpu), int(maxrss) * 1024  # (Linux gives KiB)
