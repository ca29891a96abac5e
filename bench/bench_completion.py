"""Issue 16 benchmark: a dynamic completion answers within 150 ms.

Every Tab on a word the scripts cannot know (driver, emulator, code, definition and element
names) starts a fresh `gadgetctl __complete KIND WORDS...` process. Measured here, each in a
fresh process, median of several runs: the baselines `python -c pass` and
`gadgetctl --version` (the cheapest gadgetctl start), each kind of completion, and bash
running its completion function end to end (sourcing the script included) for an element
name of the corpus's simulator configurations. Prints milliseconds and the ratio to
`python -c pass` of the same run; the target is 150 ms for each completion.

    python bench/bench_completion.py [--repeat N]
"""

from __future__ import annotations

import argparse
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

from common import CORPUS, GADGETCTL, REPO, Report, command_time

# The console script a shell runs (beside this Python), else `python -m gadgetctl`.
SCRIPT = Path(sys.executable).parent / "gadgetctl"
COMMAND = [str(SCRIPT)] if SCRIPT.is_file() else GADGETCTL

TARGET_MS = 150.0
CONFIGS = CORPUS / "modules" / "vrjuggler" / "data" / "configFiles"
SIM = [str(CONFIGS / "sim.base.jconf"), str(CONFIGS / "sim.wand.mixin.jconf")]

CASES = {
    "explain CODE (diagnostic codes)": ["codes", "explain"],
    "emulate DRIVER (emulators)": ["emulators", "emulate"],
    "drivers load NAME (driver plug-ins)": ["drivers", "drivers", "load"],
    "defs show TYPE (definition names)": ["definitions", "defs", "show"],
    "monitor CONFIG... NAME (sim.base + sim.wand.mixin)": ["inputs", "monitor", *SIM],
    "monitor --keyboard NAME (sim.base + sim.wand.mixin)": [
        "keyboards",
        "monitor",
        *SIM,
        "--keyboard",
    ],
}


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeat", type=int, default=11)
    args = parser.parse_args()
    report = Report()
    repeat = args.repeat

    def run(argv: list[str]) -> None:
        done = subprocess.run(argv, capture_output=True, text=True)
        if done.returncode != 0 or not done.stdout.strip():
            raise SystemExit(f"{shlex.join(argv)} failed or printed nothing: {done.stderr.strip()}")

    for case in CASES.values():  # each answers something (and warms the file cache)
        run([*COMMAND, "__complete", *case])
    python = command_time([sys.executable, "-c", "pass"], repeat) * 1000
    version = command_time([*COMMAND, "--version"], repeat) * 1000
    print(f"fresh process per call, median of {repeat}; command: {shlex.join(COMMAND)}")
    report.figure("baseline: python -c pass", python, "ms")
    report.figure("baseline: gadgetctl --version", version, "ms")
    report.ratio("gadgetctl --version / python -c pass", version, python)
    for label, case in CASES.items():
        ms = command_time([*COMMAND, "__complete", *case], repeat) * 1000
        report.figure(label, ms, "ms", target=TARGET_MS)
        report.ratio("  ratio to python -c pass", ms, python)
    bash = shutil.which("bash")
    if bash and len(COMMAND) == 1:
        script = REPO / "completions" / "gadgetctl.bash"
        words = " ".join(shlex.quote(w) for w in (COMMAND[0], "monitor", *SIM, "Wand"))
        line = (
            f"source {shlex.quote(str(script))}; COMP_WORDS=({words}); COMP_CWORD={len(SIM) + 2}; _gadgetctl; "
            "[[ ${#COMPREPLY[@]} -gt 0 ]]"
        )
        run([bash, "-c", line + " && echo ok"])
        ms = command_time([bash, "-c", line], repeat) * 1000
        report.figure("bash Tab end to end (monitor CONFIG... Wand)", ms, "ms", target=TARGET_MS)
        report.ratio("  ratio to python -c pass", ms, python)
    report.exit()
    return 0


if __name__ == "__main__":
    sys.exit(main())
