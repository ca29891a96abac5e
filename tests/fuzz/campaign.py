"""The fuzz campaign behind ``make fuzz``: every target, for a set time, on several cores.

    python tests/fuzz/campaign.py --seconds 600 --workers 2 --path-seconds 20 [--target NAME ...]

Two kinds of targets. The parser targets (:mod:`fuzz.targets`): each worker process takes
them in turn (from a different starting point) and feeds each a round of inputs
(:func:`fuzz.inputs.generate`: the generators the hypothesis tests use, driven by a seeded
``random.Random``, thousands a second), until ``--seconds`` are up. An input is a failure
when its target raises anything but its modelled errors, takes longer than
``--input-timeout`` seconds, or needs more memory than ``--memory-mb`` (the worker's
address-space limit); it is saved under ``--failures DIR`` (replay one with ``--replay
FILE``).

Then the path targets (:mod:`fuzz.paths`: a hostile VRPN peer against ``serve`` and against
``monitor vrpn:``, floods of mutated datagrams to each UDP driver, mutated pty streams to each
serial driver, hostile recordings through ``replay``), one after the other, each for ``--path-seconds`` in a process of its own.
Each checks its own memory and time caps as it runs (``--list`` prints them); the campaign
also kills one that runs past its time by more than its overrun, or whose resident memory
passes ``--memory-mb``. A failure is saved as ``NAME-seedN.json`` (and the last inputs sent
as ``NAME-seedN.bin``); ``--replay FILE.json`` runs that target again with the same seed.

Prints the inputs tried per target, the time, the peak memory of each path target and the
failures; exit status 1 when anything failed or exceeded a cap, 2 on usage errors. The
default run (``make fuzz``) takes about 17 minutes: 600 s of parser targets, then 19 path
targets of 20 s, each up to 1 s more to start and stop (388 s for the first 18 at load 10).
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


def _path_child(name: str, seconds: float, seed: int, conn) -> None:
    """In a process of its own: run the path target and send back its result."""
    from fuzz.paths import run_path

    conn.send(run_path(name, seconds, seed))
    conn.close()


def _run_path_target(name: str, seconds: float, seed: int, memory_mb: int) -> dict:
    """Run one path target in a child process; kill it when it overruns its time or its
    resident memory passes ``memory_mb`` (each a failure)."""
    from fuzz.memory import MB, rss
    from fuzz.paths import load

    target = load()[name]
    context = multiprocessing.get_context("spawn")
    receive, send = context.Pipe(duplex=False)
    child = context.Process(target=_path_child, args=(name, seconds, seed, send), daemon=True)
    began = time.monotonic()
    child.start()
    send.close()
    limit = began + seconds + target.overrun
    result: dict | None = None
    error = None
    peak = 0
    while result is None:
        if receive.poll(0.05):
            try:
                result = receive.recv()
            except EOFError:
                error = f"internal error: the target's process ended with status {child.exitcode}"
            break
        peak = max(peak, rss(child.pid) or 0)
        if peak > memory_mb * MB:
            error = f"memory cap exceeded: the target's process passed {memory_mb} MB"
        elif time.monotonic() > limit:
            error = (
                f"time cap exceeded: still running {seconds + target.overrun:g} s after it began"
            )
        elif not child.is_alive() and not receive.poll(0.5):
            error = f"internal error: the target's process ended with status {child.exitcode}"
        if error:
            break
    if child.is_alive():
        child.kill()
    child.join(10)
    receive.close()
    if result is None:
        result = {
            "target": name,
            "seed": seed,
            "seconds": seconds,
            "error": error,
            "trace": "",
            "recent": [],
            "figures": {},
        }
    result.setdefault("elapsed", round(time.monotonic() - began, 1))
    return result


def _save_path_failure(result: dict, failures_dir: str) -> dict:
    import json

    folder = Path(failures_dir)
    folder.mkdir(parents=True, exist_ok=True)
    stem = f"{result['target']}-seed{result['seed']}"
    recent = result.pop("recent", [])
    with open(folder / f"{stem}.bin", "wb") as out:  # the last inputs, each length-prefixed
        for data in recent:
            out.write(len(data).to_bytes(4, "big") + data)
    saved = folder / f"{stem}.json"
    saved.write_text(
        json.dumps(
            {
                k: result[k]
                for k in ("target", "seed", "seconds", "error", "trace", "figures")
                if k in result
            },
            indent=1,
        )
    )
    print(f"FAILURE {result['target']}: {result['error'][:300]} (saved as {saved})", flush=True)
    return {
        "target": result["target"],
        "error": result["error"][:300],
        "input": str(saved),
        "trace": result.get("trace", ""),
    }


def _run_paths(
    names: list[str], seconds: float, seed: int, memory_mb: int, failures_dir: str
) -> tuple[list[dict], list[dict]]:
    results, failures = [], []
    for offset, name in enumerate(names):
        print(f"path target {name}: {seconds:g} s", flush=True)
        result = _run_path_target(name, seconds, seed + offset, memory_mb)
        figures = ", ".join(f"{k} {v:g}" for k, v in sorted(result.get("figures", {}).items()))
        print(f"  {name}: {result['elapsed']:g} s; {figures}", flush=True)
        if result.get("error"):
            failures.append(_save_path_failure(result, failures_dir))
        results.append(result)
    return results, failures


def _replay_path(path: Path) -> int:
    import json

    saved = json.loads(path.read_text())
    result = _run_path_target(saved["target"], saved["seconds"], saved["seed"], 2048)
    if result.get("error"):
        print(
            f"{saved['target']} (seed {saved['seed']}): {result['error']}\n{result.get('trace', '')}"
        )
        return 1
    print(f"{saved['target']}: seed {saved['seed']} passes")
    return 0


def _replay(path: Path, name: str | None) -> int:
    from fuzz.targets import TARGETS, feed

    if path.suffix == ".json":
        return _replay_path(path)
    name = name or path.name.rsplit("-", 1)[0]
    feed(TARGETS[name], path.read_bytes())
    print(f"{name}: {path} passes")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "--seconds", type=float, default=600.0, help="how long the parser targets run (default 600)"
    )
    parser.add_argument(
        "--path-seconds",
        type=float,
        default=20.0,
        help="how long each path target runs (default 20; 0: none)",
    )
    parser.add_argument("--workers", type=int, default=2, help="worker processes (default 2)")
    parser.add_argument("--target", action="append", help="only this target (repeatable)")
    parser.add_argument(
        "--input-timeout", type=float, default=10.0, help="seconds one input may take"
    )
    parser.add_argument(
        "--memory-mb",
        type=int,
        default=2048,
        help="address space of a worker; resident memory of a path target's process",
    )
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

    from fuzz.paths import load
    from fuzz.targets import TARGETS

    paths = load()
    if args.replay:
        return _replay(args.replay, (args.target or [None])[0])
    if args.list:
        print("\n".join(sorted(TARGETS)))
        for name in sorted(paths):
            hidden = " (runs only when named)" if paths[name].hidden else ""
            print(f"{name}{hidden}\n    caps: {paths[name].caps}")
        return 0
    chosen = args.target or [*TARGETS, *(n for n in paths if not paths[n].hidden)]
    unknown = [n for n in chosen if n not in TARGETS and n not in paths]
    if unknown or args.seconds <= 0 or args.workers < 1 or args.path_seconds < 0:
        parser.error(
            f"unknown target {unknown[0]!r}"
            if unknown
            else "--seconds and --workers must be positive, --path-seconds not negative"
        )
    names = sorted(n for n in chosen if n in TARGETS)
    path_names = sorted(n for n in chosen if n in paths) if args.path_seconds else []
    seed = args.seed if args.seed is not None else int(time.time())
    start = time.monotonic()
    print(f"seed {seed}", flush=True)
    failures: list[dict] = []
    totals: dict[str, float] = {}
    if names:
        print(
            f"fuzzing {len(names)} parser targets for {args.seconds:g} s on {args.workers} workers: "
            f"{', '.join(names)}",
            flush=True,
        )
        until = time.monotonic() + args.seconds
        jobs = [
            (i, names, until, args.input_timeout, args.memory_mb, args.round, args.failures, seed)
            for i in range(args.workers)
        ]
        with multiprocessing.get_context("spawn").Pool(args.workers) as pool:
            results = pool.map(_worker, jobs)
        for result in results:
            for name, count in result["counts"].items():
                totals[name] = totals.get(name, 0) + count
            failures += result["failures"]
    path_results: list[dict] = []
    if path_names:
        print(
            f"running {len(path_names)} path targets for {args.path_seconds:g} s each: "
            f"{', '.join(path_names)}",
            flush=True,
        )
        path_results, path_failures = _run_paths(
            path_names, args.path_seconds, seed, args.memory_mb, args.failures
        )
        failures += path_failures
    elapsed = time.monotonic() - start
    width = max(map(len, names + path_names))
    for name in names:
        bad = sum(1 for f in failures if f["target"] == name)
        spent = totals[f"seconds:{name}"]
        print(f"  {name:<{width}}  {totals[name]:>9,.0f} inputs  {spent:7.0f} s  {bad} failures")
    for result in path_results:
        figures = result.get("figures", {})
        peak = figures.get("peak_mb", figures.get("growth_mb", 0))
        print(
            f"  {result['target']:<{width}}  {figures.get('inputs', 0):>9,.0f} inputs  "
            f"{result['elapsed']:7.0f} s  peak {peak:g} MB (baseline {figures.get('baseline_mb', 0):g} MB)  "
            f"{1 if result.get('error') else 0} failures"
        )
    print(
        f"inputs tried: {sum(totals.get(n, 0) for n in names):,.0f} (parser targets)  "
        f"time: {elapsed:.0f} s  workers: {args.workers}  failures: {len(failures)}"
    )
    for failure in failures:
        print(
            f"--- {failure['target']}: {failure['error']}\n    input: {failure['input']}\n{failure['trace']}"
        )
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
