"""The system status's measurement rate is six ASCII digits; anything else is no rate (found
by make fuzz: a signed field gave a negative rate)."""

from __future__ import annotations

import pytest
from MotionStar_drv.standalone import SystemStatus


def status(rate: bytes) -> SystemStatus:
    return SystemStatus.parse(bytes([0, 0, 1, 1, 1]) + rate + bytes([1, 1, 1, 3, 0]) + b"\xe0")


@pytest.mark.parametrize(
    ("rate", "hz"),
    [(b"086100", 86.1), (b"144000", 144.0), (b"-92233", 0.0), (b" 86100", 0.0), (b"+86100", 0.0),
     (b"8_6100", 0.0), (b"\xd9\xa386100"[:6], 0.0), (b"abcdef", 0.0)],
)  # fmt: skip
def test_measurement_rate_is_six_digits_or_none(rate: bytes, hz: float) -> None:
    assert status(rate).measurement_rate == pytest.approx(hz)
