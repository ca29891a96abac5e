"""Issue 2 benchmarks: start-up, schema-level validation of the corpus, throughput vs xmllint."""

from __future__ import annotations

import shutil
import subprocess
import tempfile
import time
from pathlib import Path

from common import CORPUS, GADGETCTL, REPO, Report, command_time, median_time, replicate_corpus

from gadgetctl.validate import ValidateOptions, validate_paths

report = Report()
print("start-up (median of 7 runs, wall time):")
report.figure("gadgetctl --version", command_time([*GADGETCTL, "--version"]), "s", target=0.150)
report.figure("gadgetctl --help", command_time([*GADGETCTL, "--help"]), "s", target=0.100)
script = REPO / "completions" / "gadgetctl.bash"
complete = [
    "bash",
    "-c",
    f"source {script}; COMP_WORDS=(gadgetctl validate --f); COMP_CWORD=2; _gadgetctl",
]
report.figure(
    "bash completion request (static script, incl. bash start)",
    command_time(complete),
    "s",
    target=0.150,
)
report.figure(
    "python -c pass (interpreter start-up, for reference)",
    command_time([GADGETCTL[0] if GADGETCTL[0].endswith("python") else "python3", "-c", "pass"]),
    "s",
)

print("schema-level validation of the whole corpus in one process (wall time incl. start-up):")
report.figure(
    "gadgetctl validate CORPUS --level schema",
    command_time(
        [*GADGETCTL, "validate", str(CORPUS), "--level", "schema", "-f", "json"], repeat=5
    ),
    "s",
    target=0.300,
)

with tempfile.TemporaryDirectory() as tmp:
    files = replicate_corpus(Path(tmp), 9)
    options = ValidateOptions(level="schema")
    validate_paths([Path(tmp) / "copy0"], options)  # warm caches (compiled schemas)
    elapsed = median_time(lambda: validate_paths([Path(tmp)], options), repeat=3)
    rate = len(files) / elapsed
    print(f"in-process throughput on {len(files)} files (corpus x9):")
    report.figure(
        "gadgetctl files/s (schema level)", rate, "files/s", target=2000, higher_is_better=True
    )
    xmllint = shutil.which("xmllint")
    if xmllint:
        jdefs = [str(f) for f in files if f.suffix == ".jdef"]
        jconfs = [str(f) for f in files if f.suffix == ".jconf"]

        def run_xmllint() -> None:
            for schema, group in (
                (REPO / "schemas/definition-3.1.xsd", jdefs),
                (REPO / "schemas/configuration-3.0.xsd", jconfs),
            ):
                subprocess.run(
                    [xmllint, "--noout", "--nonet", "--schema", str(schema), *group],
                    capture_output=True,
                )

        start = time.perf_counter()
        run_xmllint()
        baseline = len(files) / (time.perf_counter() - start)
        report.figure("xmllint --noout --nonet --schema files/s (baseline)", baseline, "files/s")
        report.ratio(
            "gadgetctl / xmllint throughput", rate, baseline, "(above 1: faster than xmllint)"
        )
    else:
        print("  xmllint not installed: no baseline (apt-get install libxml2-utils)")
report.exit()
