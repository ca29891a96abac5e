"""SDL joystick: poll rate, share of a core and time back after a disconnect.

SDL virtual joysticks exist only in the process that attaches them, so the emulator (10 axes,
16 buttons, 1 hat, the motion scenario at 100 Hz) runs in this process beside an input
manager whose sdl_joystick device is polled at Gadgeteer's 100 Hz, then at 1 kHz. Printed:
the polls a second reached, this process's share of one core (emulator included: it cannot
be elsewhere), the cost of one poll through the SDL thread and the device against a baseline
measured in the same run (the 27 SDL calls that read the same state, made directly), and
the time from a joystick's return (detached, attached again) to its first new sample, the
worst of several (issue 15: data within 2 s of the device's return).
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

from common import REPO, Report

sys.path.insert(0, str(REPO / "drivers"))

from SdlJoystick_drv.emulator import SdlJoystickEmulator

from gadgetctl.input import InputManager, ManagerOptions
from gadgetctl.transport.sdl import hub

SECONDS = float(os.environ.get("BENCH_SECONDS", "4"))
RETURNS = 5
CONFIG = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="bench">
<elements>
<input_manager name="IM" version="2"><driver>SdlJoystick_drv</driver></input_manager>
<sdl_joystick name="Bench" version="2"><device>{index}</device></sdl_joystick>
</elements>
</configuration>
"""


def manager_for(index: int, tmp: Path, poll_rate: float) -> InputManager:
    path = tmp / f"bench{poll_rate:g}.jconf"
    path.write_text(CONFIG.format(index=index))
    options = ManagerOptions(retry_interval=0.2, entry_points=False)
    manager, configuration = InputManager.from_files([path], options=options)
    manager.configure(configuration)
    assert not manager.pending(), [p.message for p in manager.pending()]
    device = manager.device("Bench")
    if device.poll_rate != poll_rate:  # the class's rate: set, then configure anew
        manager.shutdown()
        type(device).poll_rate = poll_rate
        manager, configuration = InputManager.from_files([path], options=options)
        manager.configure(configuration)
        device = manager.device("Bench")
    assert device.poll_rate == poll_rate
    return manager


def measure(manager: InputManager) -> tuple[float, float, int]:
    device = manager.device("Bench")
    manager.run(60.0, frames=6)
    polls0, cpu0, wall0 = device.counters["polls"], time.process_time(), time.perf_counter()
    manager.run(60.0, frames=int(SECONDS * 60))
    cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
    return (device.counters["polls"] - polls0) / wall, cpu / wall * 100, device.faults


def worst_return(manager: InputManager, emulator: SdlJoystickEmulator) -> float:
    device = manager.device("Bench")
    worst = 0.0
    for _ in range(RETURNS):
        emulator.detach()
        deadline = time.monotonic() + 10
        while manager.status("Bench").state == "running" and time.monotonic() < deadline:
            manager.update()
            time.sleep(0.005)
        count = device.store.total()
        emulator.attach()
        back = time.monotonic()
        while device.store.total() <= count and time.monotonic() < back + 10:
            manager.update()
            time.sleep(0.002)
        worst = max(worst, time.monotonic() - back)
    return worst


def direct_read_cost(emulator: SdlJoystickEmulator, n: int = 2000) -> float:
    """The baseline: reading 10 axes, 16 buttons and 1 hat with direct SDL calls."""
    sdl, handle = hub().sdl, emulator._handle

    def read() -> None:
        for i in range(10):
            sdl.SDL_JoystickGetAxis(handle, i)
        for i in range(16):
            sdl.SDL_JoystickGetButton(handle, i)
        sdl.SDL_JoystickGetHat(handle, 0)

    start = time.perf_counter()
    for _ in range(n):
        read()
    return (time.perf_counter() - start) / n


def main() -> int:
    report = Report()
    with (
        SdlJoystickEmulator(scenario="motion", rate=100.0, axes=10, buttons=16, hats=1) as emu,
        tempfile.TemporaryDirectory() as tmp,
    ):
        figures = {}
        for rate in (100.0, 1000.0):
            manager = manager_for(emu.index, Path(tmp), rate)
            figures[rate] = measure(manager)
            if rate == 100.0:
                returned = worst_return(manager, emu)
            manager.shutdown()
        baseline = direct_read_cost(emu)
    print(
        f"  10 axes, 16 buttons, 1 hat; virtual joystick moving at 100 Hz; {SECONDS:g} s per rate"
    )
    for rate, (polls, cpu, faults) in figures.items():
        report.figure(
            f"polls per second at poll_rate {rate:g}",
            polls,
            "/s",
            target=0.9 * rate,
            higher_is_better=True,
        )
        report.figure(f"process CPU at poll_rate {rate:g} (one core = 100 %)", cpu, "%")
        report.figure(f"faults at poll_rate {rate:g}", faults, "", target=0)
    polls, cpu, _ = figures[1000.0]
    per_poll = cpu / 100 / polls
    report.figure("CPU per poll at 1 kHz (SDL thread + device + frames)", per_poll * 1e6, "us")
    report.ratio("one poll vs 27 direct SDL reads (baseline)", per_poll, baseline)
    report.figure(
        f"worst time to data after the joystick returns ({RETURNS} returns)",
        returned,
        "s",
        target=2.0,
    )
    return 0 if report.ok else 1


if __name__ == "__main__":
    sys.exit(main())
