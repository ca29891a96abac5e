"""Hypothesis profiles: ``ci`` (small, derandomized, no database: ``make test`` is
deterministic) and ``fuzz`` (random, for long runs), chosen by ``GADGETCTL_FUZZ_PROFILE``."""

from __future__ import annotations

import os

from hypothesis import HealthCheck, settings

_QUIET = [
    HealthCheck.too_slow,
    HealthCheck.data_too_large,
    HealthCheck.filter_too_much,
    HealthCheck.large_base_example,
]

settings.register_profile(
    "ci",
    derandomize=True,
    database=None,
    deadline=None,
    print_blob=False,
    suppress_health_check=_QUIET,
)
settings.register_profile(
    "fuzz",
    derandomize=False,
    database=None,
    deadline=None,
    print_blob=True,
    suppress_health_check=_QUIET,
)


def load_profile() -> str:
    name = os.environ.get("GADGETCTL_FUZZ_PROFILE", "ci")
    settings.load_profile(name)
    return name
