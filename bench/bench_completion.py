"""Issue 16 benchmark: a dynamic completion answers within 150 ms.

Every Tab on a word the scripts cannot know (driver, emulator, code, definition and element
names) starts a fresh `gadgetctl __complete KIND WORDS...` process. Measured here, each in a
fresh process, median of several rounds (round robin, so that the load of a shared machine
falls alike on all): the baselines `python -c pass` and
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
import statistics
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
    commands: dict[str, list[str]] = {
        "baseline: python -c pass": [sys.executable, "-c", "pass"],
        "baseline: gadgetctl --version": [*COMMAND, "--version"],
    }
    commands.update({label: [*COMMAND, "__complete", *case] for label, case in CASES.items()})
    bash = shutil.which("bash")
    if bash and len(COMMAND) == 1:
        script = REPO / "completions" / "gadgetctl.bash"
        words = " ".join(shlex.quote(w) for w in (COMMAND[0], "monitor", *SIM, "Wand"))
        line = (
            f"source {shlex.quote(str(script))}; COMP_WORDS=({words}); COMP_CWORD={len(SIM) + 2}; "
            "_gadgetctl; [[ ${#COMPREPLY[@]} -gt 0 ]]"
        )
        run([bash, "-c", line + " && echo ok"])
        commands["bash Tab end to end (monitor CONFIG... Wand)"] = [bash, "-c", line]
    # Round robin, so that the machine's load falls alike on the baselines and the completions.
    times: dict[str, list[float]] = {label: [] for label in commands}
    for _ in range(repeat):
        for label, argv in commands.items():
            times[label].append(command_time(argv, 1))
    ms = {label: statistics.median(values) * 1000 for label, values in times.items()}
    print(
        f"fresh process per call, median of {repeat} (round robin); command: {shlex.join(COMMAND)}"
    )
    python = ms["baseline: python -c pass"]
    for label, value in ms.items():
        baseline = label.startswith("baseline")
        report.figure(label, value, "ms", target=None if baseline else TARGET_MS)
        if label != "baseline: python -c pass":
            report.ratio("  ratio to python -c pass", value, python)
    report.exit()
    return 0


if __name__ == "__main__":
    sys.exit(main())
