"""Every bundled driver's example.jconf validates clean and configures with nothing pending."""

from __future__ import annotations

import pytest

from conftest import REPO

EXAMPLES = sorted((REPO / "drivers").glob("*/example.jconf"))


def test_every_bundled_driver_has_an_example():
    assert {p.parent.name for p in EXAMPLES} >= {
        "LinuxJoydev_drv",
        "DTrack_drv",
        "PinchGlove_drv",
        "MotionStar_drv",
    }


@pytest.mark.parametrize("example", EXAMPLES, ids=[p.parent.name for p in EXAMPLES])
def test_example_is_valid_and_nothing_is_pending(cli, example):
    validated = cli("validate", example)
    assert validated.exit_code == 0, validated.stdout + validated.stderr
    pending = cli("config", "pending", example)
    assert pending.exit_code == 0, pending.stdout + pending.stderr
    assert "0 pending, 0 stupefied" in pending.stdout
