"""What every emulator's command line shares: the common options and the run loop.

:func:`emulator_parser` gives an :class:`argparse.ArgumentParser` with ``--scenario``,
``--rate`` and ``--duration`` (seconds of wall clock; a negative or non-finite value is a
usage error, exit status 2). :func:`run` starts the emulator, announces it, and runs until
``--duration`` seconds have passed, the emulator reports an end, or a stop request comes:
Ctrl-C, SIGTERM or SIGHUP. However it ends, the emulator is stopped, so every pty link,
FIFO and socket it made is removed.
"""

from __future__ import annotations

import argparse
import math
import sys
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from typing import NoReturn, Protocol

from gadgetctl.emulation.console import attach
from gadgetctl.emulation.signals import StopRequested, stop_on_signals


class Emulator(Protocol):
    def start(self) -> object: ...

    def stop(self) -> None: ...


#: The scenarios every bundled emulator offers.
STANDARD_SCENARIOS: tuple[str, ...] = ("idle", "motion", "buttons", "garbage", "disconnect")


def check_settings(scenario: str, scenarios: Sequence[str], rate: float) -> None:
    """Refuse (ValueError) a scenario the emulator does not have, or a rate not above 0."""
    if scenario not in scenarios:
        raise ValueError(f"unknown scenario {scenario!r}; choose from {', '.join(scenarios)}")
    if rate <= 0:
        raise ValueError("rate must be positive")


def duration_seconds(text: str) -> float:
    """An argparse type: a finite number of seconds, 0 or more."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number of seconds: {text!r}") from None
    if not math.isfinite(value) or value < 0:
        raise argparse.ArgumentTypeError(f"must be 0 or more seconds, not {text!r}")
    return value


def rate_per_second(text: str) -> float:
    """An argparse type: a finite rate above 0 per second."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number per second: {text!r}") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"must be more than 0 per second, not {text!r}")
    return value


# What the standard scenarios send; an emulator describes its own others (or differences).
SCENARIO_MEANINGS = {
    "idle": "the device is there, at rest",
    "motion": "values and poses move",
    "buttons": "buttons pressed and released in turn",
    "garbage": "motion with junk and broken records between, which a driver must skip and count",
    "disconnect": "motion, then the device goes away",
    "touches": "contacts made and broken in a fixed sequence",
    "hats": "each hat steps through its directions",
}


class EmulatorArgumentParser(argparse.ArgumentParser):
    """Usage errors in one line in gadgetctl's style (``gadgetctl: error: emulate X: ...``),
    exit status 2."""

    def error(self, message: str) -> NoReturn:
        command = self.prog.removeprefix("gadgetctl ")
        head = f"gadgetctl: error: {command}: " if command != self.prog else f"{self.prog}: error: "
        self.exit(2, f"{head}{message} (see '{self.prog} --help')\n")


def command_name(prog: str) -> str:
    """The command a user types for the emulator ``prog`` names: ``DTrack_drv.emulator`` (the
    module) is run as ``gadgetctl emulate DTrack_drv``."""
    plugin, _, rest = prog.partition(".")
    return f"gadgetctl emulate {plugin}" if rest == "emulator" else prog


def emulator_parser(
    prog: str,
    description: str,
    *,
    scenarios: Sequence[str],
    default_scenario: str,
    rate: float,
    rate_help: str,
    scenario_meanings: Mapping[str, str] | None = None,
) -> argparse.ArgumentParser:
    """A parser with the options every emulator has; add the emulator's own to it. ``prog``
    is the emulator's module (``DTrack_drv.emulator``); usage names the command typed."""
    parser = EmulatorArgumentParser(prog=command_name(prog), description=description)
    meanings = {**SCENARIO_MEANINGS, **(scenario_meanings or {})}
    described = "; ".join(
        f"{name}: {meanings[name]}" if name in meanings else name for name in scenarios
    )
    parser.add_argument(
        "--scenario",
        choices=list(scenarios),
        default=default_scenario,
        metavar="NAME",
        help=f"what to send (default {default_scenario}): {described}",
    )
    parser.add_argument("--rate", type=rate_per_second, default=rate, metavar="HZ", help=rate_help)
    parser.add_argument(
        "--duration",
        type=duration_seconds,
        default=None,
        metavar="SECONDS",
        help="stop after this many seconds of wall clock (default: until Ctrl-C, SIGTERM or SIGHUP)",
    )
    return parser


class Ending(Protocol):
    error: BaseException | None


def ended(emulator: Ending) -> Callable[[], int | None]:
    """A ``check`` for :func:`run`: exit status 1 (the reason on standard error, one line)
    once the emulator failed, 0 once it has finished (when it has a ``finished`` event)."""
    finished: threading.Event | None = getattr(emulator, "finished", None)

    def check() -> int | None:
        if emulator.error is not None:
            print(f"emulator failed: {emulator.error}", file=sys.stderr)
            return 1
        return 0 if finished is not None and finished.is_set() else None

    return check


def run(
    emulator: Emulator,
    *,
    duration: float | None = None,
    announce: Callable[[], None] | None = None,
    check: Callable[[], int | None] | None = None,
    interval: float = 0.1,
) -> int:
    """Run ``emulator`` until ``duration`` seconds, Ctrl-C, SIGTERM or SIGHUP (exit status
    0), or until ``check`` (called every ``interval`` seconds) returns an exit status.
    ``announce`` runs once the emulator has started (to print where it is). The emulator's
    console lines (clients coming and going, the scenario's end) go to standard output."""
    attach(emulator)
    with stop_on_signals():
        try:
            try:
                emulator.start()
                if announce is not None:
                    announce()
                end = None if duration is None else time.monotonic() + duration
                while True:
                    if check is not None:
                        code = check()
                        if code is not None:
                            return code
                    if end is None:
                        time.sleep(interval)
                        continue
                    remaining = end - time.monotonic()
                    if remaining <= 0:
                        return 0
                    time.sleep(min(interval, remaining))
            finally:
                emulator.stop()
        except (KeyboardInterrupt, StopRequested):
            return 0
