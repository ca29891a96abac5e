"""Issue 13 item 7 benchmark: validation and `config graph` stay linear in the input.

In-process times, each against a baseline of the same shape with 1,000 elements measured in
the same run (ratio of the time per element; linear means about 1x):

- a chain of aliases, each pointing at the previous one, the first at a missing name
  (every alias pending): 8,000 and 50,000 aliases (target: 50,000 in under 2 s);
- proxies pointing at devices with one letter dropped ("did you mean" for each): 8,000;
- the same file written on one line (columns): 8,000;
- `config graph` of devices with 70 values each: 700,000 values, against 70,000;
- dangling pointers at doubling sizes (8,000, 16,000, 32,000, also on one line): the ratio
  of the time per element to the previous size's (linear: about 1x per doubling);
- end to end, `gadgetctl validate FILE` of the 50,000-alias chain (target: under 2 s of
  CPU time, user + system, which a loaded machine inflates less than the wall clock),
  against the same command on a 1,000-alias chain (the baseline: mostly start-up).

    python bench/bench_validate_scale.py
"""

from __future__ import annotations

import random
import tempfile
from pathlib import Path

from common import GADGETCTL, Report, command_cpu, timed_call

from gadgetctl.jccl.configcheck import open_configuration
from gadgetctl.jccl.graph import build_graph, render_text
from gadgetctl.validate import ValidateOptions, validate_paths

HEAD = (
    '<?xml version="1.0" encoding="UTF-8"?>\n<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
    '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="scale">\n<elements>\n'
)
TAIL = "</elements>\n</configuration>\n"
TARGET_RATIO = 1.5
FINDINGS = (0, 1)  # validate exits 1 on the chain's findings


def chain(count: int) -> str:
    return "".join(
        f'<alias name="A{i}" version="1"><proxy>{"Nowhere" if i == 0 else f"A{i - 1}"}</proxy></alias>\n'
        for i in range(count)
    )


def dangling(count: int) -> str:
    """count / 2 devices and count / 2 proxies naming them with one letter dropped."""
    rng = random.Random(1)
    parts = []
    for i in range(count // 2):
        name = f"Tracker {i:05d}"
        cut = rng.randrange(len(name))
        parts.append(
            f'<waveform_device name="{name}" version="1"><rate>60.0</rate></waveform_device>\n'
            f'<analog_proxy name="P{i}" version="1"><device>{name[:cut] + name[cut + 1 :]}</device>'
            "<unit>0</unit></analog_proxy>\n"
        )
    return "".join(parts)


def valued(count: int, per: int = 70) -> str:
    """count / 2 devices with ``per`` values each and a proxy each."""
    return "".join(
        f'<waveform_device name="W{i}" version="1"><rate>60.0</rate>{"<min>0</min>" * per}'
        f'</waveform_device>\n<analog_proxy name="P{i}" version="1"><device>W{i}</device>'
        "<unit>0</unit></analog_proxy>\n"
        for i in range(count // 2)
    )


def timed(fn) -> float:
    return timed_call(fn)


def validate_time(path: Path) -> float:
    return timed(lambda: validate_paths([path], ValidateOptions()))


def graph_time(path: Path) -> float:
    def run() -> None:
        opened = open_configuration([path])
        render_text(build_graph(opened.configuration, opened.index))

    return timed(run)


def main() -> None:
    report = Report()
    cases = [
        ("alias chain", chain, (8_000, 50_000), validate_time, False),
        ("dangling pointers with suggestions", dangling, (8_000,), validate_time, False),
        ("dangling pointers, one line", dangling, (8_000,), validate_time, True),
        ("config graph, 70 values per device", valued, (20_000,), graph_time, False),
    ]
    with tempfile.TemporaryDirectory(prefix="gadgetctl-bench-") as tmp:

        def write(name: str, body: str, one_line: bool) -> Path:
            path = Path(tmp) / f"{name}.jconf"
            text = HEAD + body + TAIL
            path.write_text(text.replace("\n", " ") if one_line else text)
            return path

        validate_paths([write("warm", chain(10), False)], ValidateOptions())  # warm caches
        for label, make, sizes, measure, one_line in cases:
            base_size = 1_000
            base = measure(write(f"{label}-base", make(base_size), one_line)) / base_size
            print(f"{label}: baseline {base_size} elements, {base * 1e6:.1f} us per element")
            for size in sizes:
                took = measure(write(f"{label}-{size}", make(size), one_line))
                report.figure(
                    f"{label}, {size} elements",
                    took,
                    "s",
                    target=2.0 if (label == "alias chain" and size == 50_000) else None,
                )
                report.figure(
                    f"  per element vs {base_size} elements",
                    took / size / base,
                    "x",
                    target=TARGET_RATIO,
                )
        for label, one_line in (
            ("dangling pointers", False),
            ("dangling pointers, one line", True),
        ):
            previous = None
            for size in (8_000, 16_000, 32_000):
                took = min(
                    validate_time(write(f"{label}-d{size}", dangling(size), one_line))
                    for _ in range(2)
                )
                report.figure(f"{label}, {size} elements", took, "s")
                if previous is not None:
                    report.figure(
                        "  per element vs half the size",
                        (took / size) / (previous[0] / previous[1]),
                        "x",
                        target=TARGET_RATIO,
                    )
                previous = (took, size)
        big = write("e2e-chain-50000", chain(50_000), False)
        small = write("e2e-chain-1000", chain(1_000), False)
        command_cpu([*GADGETCTL, "validate", str(small)], FINDINGS)  # warm the file cache
        runs = [command_cpu([*GADGETCTL, "validate", str(big)], FINDINGS) for _ in range(3)]
        base = [command_cpu([*GADGETCTL, "validate", str(small)], FINDINGS) for _ in range(3)]
        print("end to end: gadgetctl validate FILE (best of 3)")
        report.figure("50,000-alias chain (wall clock)", min(r[0] for r in runs), "s")
        report.figure(
            "50,000-alias chain (CPU time, user + system)", min(r[1] for r in runs), "s", target=2.0
        )
        report.figure("1,000-alias chain, the baseline (wall clock)", min(r[0] for r in base), "s")
        report.figure("1,000-alias chain, the baseline (CPU time)", min(r[1] for r in base), "s")
        report.ratio(
            "50,000 / 1,000 aliases (CPU time)", min(r[1] for r in runs), min(r[1] for r in base)
        )
    report.exit()


if __name__ == "__main__":
    main()
