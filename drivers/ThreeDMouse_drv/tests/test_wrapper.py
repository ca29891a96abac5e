"""The 3D mouse device in an input manager, against the emulator over a real pty pair."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from ThreeDMouse_drv.emulator import ThreeDMouseEmulator

from gadgetctl.input.devicetypes import DigitalState
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.testing import reads_past_garbage, serial_line_lost_then_resumes, wait_until
from gadgetctl.input.testing.configs import pending_reasons, rewritten
from gadgetctl.input.testing.fixtures import emulator_fixture, managers_fixture

pytestmark = pytest.mark.timeout(30)
EXAMPLE = Path(__file__).resolve().parents[1] / "example.jconf"
FAST = {
    "demand_wait": 0.0,
    "reset_wait": 0.0,
    "diagnostic_wait": 0.0,
    "read_timeout": 1.0,
    "poll_timeout": 0.05,
    "poll_interval": 0.005,
}
INCH = 0.0254


def element(name: str, port: str, baud: int = 19200) -> str:
    return (
        f'<three_d_mouse name="{name}" version="1"><port>{port}</port><baud>{baud}</baud></three_d_mouse>\n'
        f'<position_proxy name="{name} Pos" version="1"><device>{name}</device><unit>0</unit></position_proxy>\n'
        + "".join(
            f'<digital_proxy name="{name} B{u}" version="1"><device>{name}</device><unit>{u}</unit></digital_proxy>\n'
            for u in range(3)
        )
    )


emulator = emulator_fixture(ThreeDMouseEmulator, rate=200.0)
managers = managers_fixture("ThreeDMouse_drv", tune={"three_d_mouse": FAST})


def test_translation_rotation_and_buttons_reach_the_proxies(tmp_path, emulator, managers) -> None:
    emu = emulator("buttons")
    manager = managers(element("M", emu.address, baud=12900))
    assert not manager.pending()
    device = manager.device("M")
    assert device.baud == 19200  # the definition's "19200" label has the value 12900
    seen: set[tuple] = set()

    def frame() -> None:
        manager.update()
        seen.update(s.values for s in device.store.frame(DeviceKind.DIGITAL))

    assert wait_until(lambda: {(1, 0, 0), (0, 1, 0), (0, 0, 1)} <= seen, timeout=5, step=frame)
    emu.pause()  # the last report sent is final: wait for the proxies to show it
    position, _, flags = emu.sent[-1]

    def shown() -> bool:
        matrix = manager.proxy("M Pos").matrix
        states = [
            manager.proxy(f"M B{u}").data in (DigitalState.ON, DigitalState.TOGGLE_ON)
            for u in range(3)
        ]
        return bool(
            np.allclose(matrix[:3, 3], np.asarray(position) / 1000 * INCH, atol=1e-9)
        ) and states == [
            bool(flags & 4),
            bool(flags & 2),
            bool(flags & 1),
        ]

    assert wait_until(shown, timeout=5, step=frame)
    matrix = manager.proxy("M Pos").matrix
    assert not np.allclose(matrix[:3, :3], np.eye(3))  # the angles rotate
    np.testing.assert_allclose(matrix[:3, :3] @ matrix[:3, :3].T, np.eye(3), atol=1e-9)


def test_garbage_is_counted_without_a_fault(tmp_path, emulator, managers) -> None:
    emu = emulator("garbage")
    manager = managers(element("M", emu.address))
    device = reads_past_garbage(manager, "M", 30)
    assert device.bad_records >= 20 and device.counters["skipped_bytes"] > 0


def test_lost_line_faults_then_resumes_within_two_seconds(tmp_path, emulator, managers) -> None:
    link = tmp_path / "mouse"
    emu = emulator("disconnect", disconnect_after=15, link=link)
    manager = managers(element("M", str(link)))
    serial_line_lost_then_resumes(manager, "M", emu, lambda: emulator("motion", link=link), 15)


def test_configuration_errors_leave_the_element_pending(tmp_path, managers) -> None:
    body = (
        '<three_d_mouse name="No Port" version="1"><port></port></three_d_mouse>\n'
        '<three_d_mouse name="No Mouse" version="1"><port>/nonexistent/tty</port></three_d_mouse>\n'
    )
    pending = pending_reasons(managers(body))
    assert pending["No Port"].startswith("port is empty")
    assert "/nonexistent/tty" in pending["No Mouse"]


def test_example_delivers_through_its_aliases(tmp_path, emulator, managers) -> None:
    emu = emulator("motion")
    path = rewritten(
        EXAMPLE, tmp_path, ("<port>/tmp/gadgetctl-3dmouse</port>", f"<port>{emu.address}</port>")
    )
    manager = managers(path)
    device = manager.device("3D Mouse")
    assert wait_until(lambda: device.records >= 10, timeout=5, step=manager.update)
    emu.pause()
    distance = np.linalg.norm(emu.sent[-1][0]) / 1000 * INCH
    assert wait_until(
        lambda: abs(np.linalg.norm(manager.proxy("VJHead").matrix[:3, 3]) - distance) < 1e-9,
        timeout=5,
        step=manager.update,
    )
    assert not manager.proxy("VJButton0").stupefied
