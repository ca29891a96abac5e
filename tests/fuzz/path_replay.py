"""Path target of recordings: hostile recordings and VRPN logs through a real ``gadgetctl
replay`` process (``replay.recording``), reading, scheduling, the replay devices, the input
manager and the NDJSON writer together.

Inputs: the recording and VRPN log targets' seeds (:mod:`fuzz.targets`) mutated by
:func:`fuzz.inputs.generate`, and recordings made hostile on purpose (a far unit, a header
claiming many units, huge or reversed timestamps, deep nesting, a long run of one instant).
Each is replayed by ``gadgetctl replay FILE --format ndjson --speed 100 --duration 3`` in a
process of its own, one after the other.

Checks, each a failure of the run:

- the replay's peak resident memory (its own ``ru_maxrss``) stays within ``GROWTH_CAP`` of a
  well-behaved recording's, measured in the same run;
- it exits within ``EXIT_CAP`` seconds of its ``--duration``, writes at most ``OUTPUT_CAP``
  bytes (an amplification), and exits 0, 1 or 2;
- stderr holds no traceback and no internal error, at most ``STDERR_LINES`` lines.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from fuzz.inputs import generate
from fuzz.memory import MB
from fuzz.paths import CapExceeded, PathFailure, Run, path_target

#: seconds of replay each input gets (``--duration``)
DURATION = 3.0
#: seconds past DURATION a replay may take to start and end
EXIT_CAP = 30.0
#: resident memory a hostile recording may add over a well-behaved one's replay
GROWTH_CAP = 128 * MB
#: bytes a replay may write to stdout (a small file must not make millions of lines)
OUTPUT_CAP = 32 * MB
#: lines on stderr (one-line diagnostics; a line per bad record is bounded by the input)
STDERR_LINES = 200
#: hostile replays run however short the time (each takes a few seconds)
MIN_INPUTS = 2

_HEADER = {"v": 1, "type": "header", "format": "gadgetctl-recording", "created": "now"}


def _sample(unit: int, t: float, kind: str = "analog", device: str = "W") -> dict:
    value: object = 0.5
    if kind == "position":
        value = [[1.0, 0, 0, 0], [0, 1.0, 0, 0], [0, 0, 1.0, 0], [0, 0, 0, 1.0]]
    return {"v": 1, "type": "sample", "device": device, "kind": kind, "unit": unit,
            "timestamp": t, "value": value}  # fmt: skip


def _lines(records: list[dict], header: dict | None = None) -> bytes:
    return _text(header or _HEADER) + b"".join(_text(r) for r in records)


def _text(record: dict) -> bytes:
    return json.dumps(record).encode() + b"\n"


def _well_behaved() -> bytes:
    return _lines([_sample(u, 1 + 0.01 * i, "position") for i in range(300) for u in (0, 1)])


def _hostile(rng) -> bytes:
    """A recording made hostile on purpose, in one of the ways the campaign found."""
    kind = rng.choice(["analog", "position", "glove", "string"])
    base = [_sample(0, 1 + 0.01 * i, kind) for i in range(rng.randint(1, 400))]
    choice = rng.randrange(6)
    if choice == 0:  # one far unit among many samples
        base.insert(
            rng.randrange(len(base) + 1), _sample(rng.choice([1023, 1024, 65535]), 1.5, kind)
        )
    elif choice == 1:  # a header claiming far more units than samples
        units = {kind: rng.choice([1024, 65536, 2**31])}
        elements = {"W": {"element": "device", "type": "x", "kinds": [kind], "units": units}}
        return _lines(base, {**_HEADER, "info": {"elements": elements}})
    elif choice == 2:  # huge, tiny or reversed timestamps
        for record in base:
            record["timestamp"] = rng.choice([0.0, 1e308, -1e308, 1e9, 5e-324, record["timestamp"]])
    elif choice == 3:  # a header nested deep
        depth = rng.choice([100, 1000, 200_000])
        nested = "[" * depth + "]" * depth
        header = json.dumps({**_HEADER, "info": {"x": 0}}).replace('"x": 0', f'"x": {nested}')
        return header.encode() + b"\n" + b"".join(_text(r) for r in base)
    elif choice == 4:  # every sample at one instant
        for record in base:
            record["timestamp"] = 1.0
    else:  # many devices
        base = [
            _sample(0, 1 + 0.001 * i, kind, device=f"D{i}") for i in range(rng.randint(1, 2000))
        ]
    return _lines(base)


def _inputs(run: Run):
    """Endless hostile recordings and VRPN logs, with the suffix each is replayed under."""
    from fuzz.targets import TARGETS

    recording, vrpn_log = TARGETS["recording.reader"], TARGETS["vrpn.logfile"]
    while True:
        pick = run.rng.randrange(3)
        if pick == 0:
            yield _hostile(run.rng), ".ndjson"
        elif pick == 1:
            yield generate(run.rng, recording.seeds(), recording.grammar), ".ndjson"
        else:
            yield generate(run.rng, vrpn_log.seeds(), vrpn_log.grammar), ".vrpn"


def _replay(path: Path) -> dict:
    """``gadgetctl replay`` of ``path`` in a process of its own; its exit status, peak memory
    (bytes), stdout size, stderr and seconds; killed past its caps (``killed``)."""
    env = {**os.environ, "NO_COLOR": "1"}
    env.pop("GADGETCTL_DEBUG", None)
    command = [sys.executable, "-m", "gadgetctl", "replay", str(path), "--format", "ndjson",
               "--speed", "100", "--duration", str(DURATION)]  # fmt: skip
    began = time.monotonic()
    child = subprocess.Popen(
        command, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env
    )
    written, errors, killed = [0], [b""], [""]

    def drain_stdout() -> None:
        while chunk := child.stdout.read(1 << 16):
            written[0] += len(chunk)
            if written[0] > OUTPUT_CAP and not killed[0]:
                killed[0] = f"wrote more than {OUTPUT_CAP // MB} MB"
                child.kill()

    def drain_stderr() -> None:
        errors[0] = child.stderr.read(1 << 20)
        child.stderr.read()  # the rest, unkept

    readers = [threading.Thread(target=f, daemon=True) for f in (drain_stdout, drain_stderr)]
    for reader in readers:
        reader.start()
    deadline = began + DURATION + EXIT_CAP
    while True:
        pid, status, usage = os.wait4(child.pid, os.WNOHANG)
        if pid:
            break
        if time.monotonic() > deadline:
            killed[0] = killed[0] or f"still running {DURATION + EXIT_CAP:g} s after it began"
            child.kill()
            pid, status, usage = os.wait4(child.pid, 0)
            break
        time.sleep(0.02)
    child.returncode = os.waitstatus_to_exitcode(status)
    for reader in readers:
        reader.join(10)
    return {
        "status": child.returncode,
        "peak": usage.ru_maxrss * 1024,
        "written": written[0],
        "stderr": errors[0].decode("utf-8", "replace"),
        "seconds": time.monotonic() - began,
        "killed": killed[0],
    }


def _check(run: Run, result: dict, baseline: int) -> None:
    if result["killed"]:
        raise CapExceeded(f"time or output cap exceeded: the replay {result['killed']}")
    run.check_memory("the replay", result["peak"], baseline, lambda b: b + GROWTH_CAP)
    stderr = result["stderr"]
    if "Traceback" in stderr or "internal error" in stderr:
        raise PathFailure(f"the replay failed inside: {stderr.strip()[-400:]}")
    if stderr.count("\n") > STDERR_LINES:
        raise PathFailure(f"{stderr.count(chr(10))} lines on stderr (at most {STDERR_LINES})")
    if result["status"] not in (0, 1, 2):
        raise PathFailure(f"the replay exited with status {result['status']}")


@path_target(
    "replay.recording",
    caps=(
        f"memory: a replay's peak within {GROWTH_CAP // MB} MB of a well-behaved recording's; "
        f"time: each replay ends within {EXIT_CAP:g} s of its {DURATION:g} s; output: at most "
        f"{OUTPUT_CAP // MB} MB"
    ),
    overrun=DURATION + EXIT_CAP + 30.0,
)
def _recordings(run: Run) -> None:
    with tempfile.TemporaryDirectory(prefix="gadgetctl-fuzz-replay-") as scratch:
        calm = Path(scratch, "calm.ndjson")
        calm.write_bytes(_well_behaved())
        first = _replay(calm)
        if first["status"] != 0 or first["killed"]:
            raise PathFailure(f"a well-behaved recording does not replay: {first['stderr'][-400:]}")
        baseline = first["peak"]
        run.memory("baseline_mb", baseline)
        peak = baseline
        for replays, (data, suffix) in enumerate(_inputs(run)):
            if replays >= MIN_INPUTS and run.left() < DURATION + 2:
                break
            path = Path(scratch, f"input{suffix}")
            path.write_bytes(run.sent(data))
            result = _replay(path)
            peak = max(peak, result["peak"])
            run.memory("peak_mb", peak)
            run.count("replays")
            _check(run, result, baseline)
