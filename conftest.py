"""Test-wide set-up: driver plug-in packages under drivers/ are importable by name, and
gadgetctl keeps its cache (the bundled definitions as read) in a folder of the test run's
own, not the user's."""

import os
import shutil
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent
DRIVERS = ROOT / "drivers"
if str(DRIVERS) not in sys.path:
    sys.path.insert(0, str(DRIVERS))

_CACHE_VAR = "GADGETCTL_CACHE_DIR"
_own_cache: list[str] = []


def pytest_configure(config) -> None:
    if _CACHE_VAR not in os.environ:  # (processes the tests start inherit it)
        _own_cache.append(tempfile.mkdtemp(prefix="gadgetctl-test-cache-"))
        os.environ[_CACHE_VAR] = os.path.join(_own_cache[0], "cache")


def pytest_unconfigure(config) -> None:
    if _own_cache:
        shutil.rmtree(_own_cache.pop(), ignore_errors=True)
        os.environ.pop(_CACHE_VAR, None)
