"""pytest fixtures a driver's tests declare in one line each (this module imports pytest).

::

    emulator = emulator_fixture(WandaEmulator, rate=100.0)
    managers = managers_fixture("Wanda_drv", tune={"wanda": FAST})

``emulator`` is then a fixture giving ``start(scenario, **options)`` (every emulator started is
stopped after the test); ``managers`` one giving an :class:`~gadgetctl.input.testing.configs.InputManagers`
on the test's ``tmp_path``, whose tuned class attributes go back through ``monkeypatch``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from typing import Any

import pytest

from gadgetctl.emulation.testing import emulators
from gadgetctl.input.testing.configs import InputManagers


def emulator_fixture(
    kind: Callable[..., Any],
    scenario: str = "motion",
    *,
    name: str = "emulator",
    **defaults: object,
) -> Any:
    """A fixture (called ``name``) that starts ``kind`` emulators, ``defaults`` under the
    options a test gives, and stops them after the test."""

    @pytest.fixture(name=name)
    def fixture() -> Iterator[Callable[..., Any]]:
        with emulators(kind, scenario, **defaults) as start:
            yield start

    return fixture


def managers_fixture(
    driver: str,
    *,
    name: str = "managers",
    tune: Mapping[str, Mapping[str, object]] | None = None,
    **settings: Any,
) -> Any:
    """A fixture (called ``name``) giving :class:`InputManagers` for ``driver`` (``settings``:
    its ``options`` and ``ready``), all shut down after the test."""

    @pytest.fixture(name=name)
    def fixture(tmp_path, monkeypatch) -> Iterator[InputManagers]:
        with InputManagers(
            tmp_path, driver, tune=tune, patch=monkeypatch.setattr, **settings
        ) as built:
            yield built

    return fixture
