"""The Fastrak device in an input manager, against the emulator over a real pty pair."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from Fastrak_drv.emulator import FastrakEmulator

from gadgetctl.input.devicetypes import DigitalState
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.testing import reads_past_garbage, serial_line_lost_then_resumes, wait_until
from gadgetctl.input.testing.configs import pending_reasons, rewritten
from gadgetctl.input.testing.fixtures import emulator_fixture, managers_fixture

pytestmark = pytest.mark.timeout(30)
EXAMPLE = Path(__file__).resolve().parents[1] / "example.jconf"
FAST = {"read_timeout": 1.0, "poll_interval": 0.005}
CM = 0.01


def element(name: str, port: str) -> str:
    return (
        f'<fastrak name="{name}" version="2"><port>{port}</port></fastrak>\n'
        + "".join(
            f'<position_proxy name="{name} S{s}" version="1"><device>{name}</device><unit>{s - 1}</unit>'
            "</position_proxy>\n"
            for s in range(1, 5)
        )
        + f'<digital_proxy name="{name} Stylus" version="1"><device>{name}</device><unit>0</unit></digital_proxy>\n'
    )


emulator = emulator_fixture(FastrakEmulator, rate=240.0)
managers = managers_fixture("Fastrak_drv", tune={"fastrak": FAST})


def test_station_four_is_unit_three_and_the_stylus_digital_zero(
    tmp_path, emulator, managers
) -> None:
    emu = emulator("buttons", active=(1, 4))
    manager = managers(element("F", emu.address))
    assert not manager.pending()
    device = manager.device("F")
    seen: list[tuple] = []

    def frame() -> None:
        manager.update()
        seen.extend(s.values for s in device.store.frame(DeviceKind.DIGITAL))

    assert wait_until(
        lambda: device.records >= 40 and {0, 1} <= {v[0] for v in seen}, timeout=5, step=frame
    )
    assert all(v in ((0,), (1,)) for v in seen)
    emu.pause()  # the last records sent are final: wait for the proxies to show them
    newest = {s[0]: s for s in emu.sent}

    def shown() -> bool:
        stylus = manager.proxy("F Stylus").data in (DigitalState.ON, DigitalState.TOGGLE_ON)
        return stylus == bool(newest[1][3]) and all(
            np.allclose(
                manager.proxy(f"F S{st}").matrix[:3, 3], np.asarray(newest[st][1]) * CM, atol=1e-7
            )
            for st in (1, 4)
        )

    assert wait_until(shown, timeout=5, step=manager.update)
    for station in (2, 3):  # not reported: identity
        np.testing.assert_array_equal(manager.proxy(f"F S{station}").matrix, np.eye(4))


def test_garbage_is_counted_without_a_fault(tmp_path, emulator, managers) -> None:
    emu = emulator("garbage")
    manager = managers(element("F", emu.address))
    device = reads_past_garbage(manager, "F", 40)
    assert device.bad_records >= 20 and device.counters["skipped_bytes"] > 0


def test_lost_line_faults_then_resumes_within_two_seconds(tmp_path, emulator, managers) -> None:
    link = tmp_path / "fastrak"
    emu = emulator("disconnect", disconnect_after=15, link=link)
    manager = managers(element("F", str(link)))
    serial_line_lost_then_resumes(manager, "F", emu, lambda: emulator("motion", link=link), 15)


def test_configuration_errors_leave_the_element_pending(tmp_path, managers) -> None:
    body = (
        '<fastrak name="No Port" version="2"><port></port></fastrak>\n'
        '<fastrak name="No Tracker" version="2"><port>/nonexistent/tty</port></fastrak>\n'
    )
    pending = pending_reasons(managers(body))
    assert pending["No Port"].startswith("port is empty")
    assert "/nonexistent/tty" in pending["No Tracker"]


def test_example_delivers_through_its_aliases(tmp_path, emulator, managers) -> None:
    emu = emulator("motion")
    path = rewritten(
        EXAMPLE, tmp_path, ("<port>/tmp/gadgetctl-fastrak</port>", f"<port>{emu.address}</port>")
    )
    manager = managers(path)
    device = manager.device("Fastrak")
    assert wait_until(lambda: device.records >= 10, timeout=5, step=manager.update)
    emu.pause()
    newest = {s[0]: s for s in emu.sent}

    def shown() -> bool:
        return all(
            np.allclose(
                manager.proxy(alias).matrix[:3, 3], np.asarray(newest[st][1]) * CM, atol=1e-7
            )
            for alias, st in (("VJWand", 1), ("VJHead", 2))
        )

    assert wait_until(shown, timeout=5, step=manager.update)
    assert not manager.proxy("VJButton0").stupefied
