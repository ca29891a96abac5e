"""The fuzz campaign behind ``make fuzz``: every target, for a set time, on several cores.

    python tests/fuzz/campaign.py --seconds 600 --workers 2 [--target NAME ...]

Each worker process takes the targets in turn (from a different starting point) and feeds
each a round of inputs (:func:`fuzz.inputs.generate`: the generators the hypothesis tests use,
driven by a seeded ``random.Random``, thousands a second), until the time is up. An input is a failure when
its target raises anything but its modelled errors, takes longer than ``--input-timeout``
seconds, or needs more memory than ``--memory-mb`` (the worker's address-space limit). Each
failing input is saved under ``--failures DIR`` (replay one with ``--replay FILE``). Prints
the inputs tried per target, the time and the failures; exit status 1 when anything failed.
"""

from __future__ import annotations

import argparse
import hashlib
import multiprocessing
import random
import resource
import signal
import sys
import time
import traceback
from pathlib import Path

TESTS = Path(__file__).resolve().parents[1]
REPO = TESTS.parent
for entry in (TESTS, REPO / "drivers"):
    if str(entry) not in sys.path:
        sys.path.insert(0, str(entry))


class InputTimeout(BaseException):
    """An input took longer than the campaign allows (BaseException: no parser swallows it)."""


def _alarm(signum: int, frame: object) -> None:
    raise InputTimeout()


def _worker(args: tuple[int, list[str], float, float, int, int, str, int]) -> dict:
    index, names, until, input_timeout, memory_mb, round_size, failures_dir, seed = args
    limit = memory_mb << 20
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    signal.signal(signal.SIGALRM, _alarm)
    from fuzz.inputs import generate
    from fuzz.targets import TARGETS, feed

    rng = random.Random(seed * 1000 + index)
    counts = dict.fromkeys(names, 0) | dict.fromkeys((f"seconds:{n}" for n in names), 0.0)
    failures: list[dict] = []
    order = names[index % len(names) :] + names[: index % len(names)]
    rounds = 0
    while time.monotonic() < until:
        name = order[rounds % len(order)]
        rounds += 1
        target = TARGETS[name]
        seeds = target.seeds()
        began = time.monotonic()
        for _ in range(round_size):
            if time.monotonic() >= until:
                break
            data = generate(rng, seeds, target.grammar)
            counts[name] += 1
            signal.setitimer(signal.ITIMER_REAL, input_timeout)
            try:
                feed(target, data)
            except (Exception, InputTimeout) as exc:  # a failure: keep the input, go on
                signal.setitimer(signal.ITIMER_REAL, 0)
                failures.append(_failure(name, data, exc, failures_dir, index))
            finally:
                signal.setitimer(signal.ITIMER_REAL, 0)
        counts[f"seconds:{name}"] += time.monotonic() - began
    return {"counts": counts, "failures": failures}


def _failure(name: str, data: bytes, exc: BaseException, failures_dir: str, worker: int) -> dict:
    saved = Path(failures_dir) / f"{name}-{hashlib.sha1(data).hexdigest()[:12]}.bin"
    saved.parent.mkdir(parents=True, exist_ok=True)
    saved.write_bytes(data)
    what = "timeout" if isinstance(exc, InputTimeout) else f"{type(exc).__name__}: {exc}"
    print(f"[worker {worker}] FAILURE {name}: {what[:200]} (input saved as {saved})", flush=True)
    return {
        "target": name,
        "error": what[:300],
        "input": str(saved),
        "trace": "".join(traceback.format_exception(exc))[-1500:],
    }


def _replay(path: Path, name: str | None) -> int:
    from fuzz.targets import TARGETS, feed

    name = name or path.name.rsplit("-", 1)[0]
    feed(TARGETS[name], path.read_bytes())
    print(f"{name}: {path} passes")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "--seconds", type=float, default=600.0, help="how long to run (default 600)"
    )
    parser.add_argument("--workers", type=int, default=2, help="worker processes (default 2)")
    parser.add_argument("--target", action="append", help="only this target (repeatable)")
    parser.add_argument(
        "--input-timeout", type=float, default=10.0, help="seconds one input may take"
    )
    parser.add_argument("--memory-mb", type=int, default=2048, help="address space of a worker")
    parser.add_argument("--round", type=int, default=200, help="inputs per target before the next")
    parser.add_argument(
        "--seed", type=int, default=None, help="random seed (default: from the clock)"
    )
    parser.add_argument(
        "--failures", default="fuzz-failures", help="where failing inputs are saved"
    )
    parser.add_argument("--replay", type=Path, help="run one saved input again and exit")
    parser.add_argument("--list", action="store_true", help="list the targets and exit")
    args = parser.parse_args(argv)

    from fuzz.targets import TARGETS

    if args.replay:
        return _replay(args.replay, (args.target or [None])[0])
    if args.list:
        print("\n".join(sorted(TARGETS)))
        return 0
    names = sorted(args.target or TARGETS)
    unknown = [n for n in names if n not in TARGETS]
    if unknown or args.seconds <= 0 or args.workers < 1:
        parser.error(
            f"unknown target {unknown[0]!r}"
            if unknown
            else "--seconds and --workers must be positive"
        )
    start = time.monotonic()
    until = start + args.seconds
    print(
        f"fuzzing {len(names)} targets for {args.seconds:g} s on {args.workers} workers: {', '.join(names)}",
        flush=True,
    )
    seed = args.seed if args.seed is not None else int(time.time())
    print(f"seed {seed}", flush=True)
    jobs = [
        (i, names, until, args.input_timeout, args.memory_mb, args.round, args.failures, seed)
        for i in range(args.workers)
    ]
    with multiprocessing.get_context("spawn").Pool(args.workers) as pool:
        results = pool.map(_worker, jobs)
    elapsed = time.monotonic() - start
    totals: dict[str, float] = {}
    failures = []
    for result in results:
        for name, count in result["counts"].items():
            totals[name] = totals.get(name, 0) + count
        failures += result["failures"]
    width = max(map(len, names))
    for name in names:
        bad = sum(1 for f in failures if f["target"] == name)
        spent = totals[f"seconds:{name}"]
        print(f"  {name:<{width}}  {totals[name]:>9,.0f} inputs  {spent:7.0f} s  {bad} failures")
    print(
        f"inputs tried: {sum(totals[n] for n in names):,.0f}  time: {elapsed:.0f} s  workers: {args.workers}  "
        f"failures: {len(failures)}"
    )
    for failure in failures:
        print(
            f"--- {failure['target']}: {failure['error']}\n    input: {failure['input']}\n{failure['trace']}"
        )
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
