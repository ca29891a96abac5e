"""Issue 4 benchmark: full validation (XML, schema, definitions, configuration semantics).

Prints the in-process time for the corpus replicated 1x, 10x and 50x and the ratios
(targets: 10x within 11 times and 50x within 55 times the 1x time), the CPU time of validating
the corpus in-process against a bare lxml parse of the same files in the same process (issue 27
goal 4: within 3.5 times), and the wall time of one `gadgetctl validate` process on the
corpus, start-up included (target: under 0.5 s).

    python bench/bench_validate_full.py
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from common import CORPUS, GADGETCTL, Report, command_time, median_time, replicate_corpus
from lxml import etree

from gadgetctl.validate import ValidateOptions, validate_paths

MODULES = CORPUS / "modules"
EXTRA = [
    MODULES / "vrjuggler/samples/OGL/simple/ConfigApp",
    MODULES / "jackal/test/TestSuite/TestFiles/definitions",
]

PARSE_TARGET = 3.5


def bare_parse(files: list[Path]) -> None:
    parser = etree.XMLParser(resolve_entities=False, no_network=True)
    for path in files:
        try:
            etree.parse(str(path), parser)
        except (etree.LxmlError, OSError):  # the corpus holds broken files on purpose
            pass


report = Report()
options = ValidateOptions(definition_dirs=EXTRA)
times: dict[int, float] = {}
print("full validation in-process (median), corpus replicated:")
with tempfile.TemporaryDirectory(prefix="gadgetctl-bench-") as tmp:
    validate_paths([CORPUS], options)  # warm caches (compiled schemas)
    for copies in (1, 10, 50):
        root = Path(tmp) / f"x{copies}"
        files = replicate_corpus(root, copies)
        times[copies] = median_time(
            lambda root=root: validate_paths([root], options), repeat=5 if copies < 50 else 3
        )
        report.figure(f"corpus x{copies} ({len(files)} files)", times[copies] * 1000, "ms")
report.figure("ratio 10x / 1x", times[10] / times[1], "x", target=11)
report.figure("ratio 50x / 1x", times[50] / times[1], "x", target=55)

print("the corpus in-process against a bare lxml parse of its files (median CPU time):")
corpus_files = sorted(p for p in CORPUS.rglob("*") if p.suffix in (".jdef", ".jconf"))
validate_cpu = median_time(lambda: validate_paths([CORPUS], options), clock=time.process_time)
parse_cpu = median_time(lambda: bare_parse(corpus_files), clock=time.process_time)
report.figure(f"validate CORPUS ({len(corpus_files)} files), CPU", validate_cpu * 1000, "ms")
report.figure("bare lxml parse of the same files (baseline), CPU", parse_cpu * 1000, "ms")
report.figure("validate / bare parse", validate_cpu / parse_cpu, "x", target=PARSE_TARGET)

print("one process, start-up included (median of 5 runs, wall time):")
command = [*GADGETCTL, "validate", str(CORPUS), "-f", "json"]
for directory in EXTRA:
    command += ["--definitions", str(directory)]
report.figure(
    "gadgetctl validate CORPUS (full)", command_time(command, repeat=5), "s", target=0.500
)
report.exit()
