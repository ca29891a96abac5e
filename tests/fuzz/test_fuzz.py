"""Every fuzz target with a small, fixed budget of generated and mutated inputs.

The ``ci`` profile (the default) is derandomized and keeps no database, so ``make test`` runs
the same inputs every time; ``GADGETCTL_FUZZ_PROFILE=fuzz`` makes the inputs random. ``make
fuzz`` (:mod:`fuzz.campaign`) runs the same targets and inputs for a set time.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import given, settings

from fuzz.inputs import strategy
from fuzz.settings import load_profile
from fuzz.targets import TARGETS, feed

load_profile()
DRIVERS = Path(__file__).resolve().parents[2] / "drivers"


@pytest.mark.timeout(300)
@pytest.mark.parametrize("name", sorted(TARGETS))
def test_parser_takes_hostile_input(name: str) -> None:
    target = TARGETS[name]

    @settings(max_examples=target.examples)
    @given(strategy(target.seeds(), target.grammar))
    def run(data: bytes) -> None:
        feed(target, data)

    run()


def test_every_bundled_driver_has_a_target() -> None:
    drivers = {p.name for p in DRIVERS.iterdir() if (p / "standalone.py").is_file()}
    covered = {TARGETS[name].driver for name in TARGETS} - {None}
    assert drivers <= covered, (
        f"drivers without a fuzz target: {sorted(drivers - covered)}; add a "
        "@target(..., driver=NAME) entry for each decoder in tests/fuzz/targets.py"
    )
