"""The IS-900 device in an input manager, against the emulator over a real pty pair."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from IS900_drv.emulator import IS900Emulator
from IS900_drv.standalone import pose_matrix

from gadgetctl.input.devicetypes import DigitalState
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.testing import reads_past_garbage, serial_line_lost_then_resumes, wait_until
from gadgetctl.input.testing.commands import monitor_ndjson, run_gadgetctl, samples_of
from gadgetctl.input.testing.configs import corpus_copy, pending_reasons, proxy
from gadgetctl.input.testing.fixtures import emulator_fixture, managers_fixture

pytestmark = pytest.mark.timeout(30)

FAST = {"settle": 0.0, "read_timeout": 1.0, "poll_timeout": 0.05, "poll_interval": 0.005}
INCH = 0.0254


def tracker_element(name: str, port: str) -> str:
    return (
        f'<intersense name="{name}" version="1"><port>{port}</port><min>0</min><max>255</max>'
        '<stations><intersense_station name="Wand" version="1"><enabled>true</enabled>'
        "<station_index>0</station_index><digital_first>2</digital_first><digital_count>4</digital_count>"
        "<analog_first>1</analog_first><analog_count>2</analog_count></intersense_station></stations>"
        '<stations><intersense_station name="Head" version="1"><enabled>true</enabled>'
        "<station_index>1</station_index><use_digital>false</use_digital><use_analog>false</use_analog>"
        "</intersense_station></stations></intersense>\n"
    )


emulator = emulator_fixture(IS900Emulator, rate=200.0)
managers = managers_fixture("IS900_drv", tune={"intersense": FAST})


def test_station_units_buttons_and_joystick_reach_proxies(tmp_path, emulator, managers) -> None:
    emu = emulator("buttons")
    manager = managers(
        tracker_element("IS", emu.address)
        + "".join(proxy("digital", f"B{u}", "IS", u) for u in range(6))
        + proxy("analog", "A1", "IS", 1)
    )
    assert not manager.pending()
    device = manager.device("IS")
    seen: list[tuple] = []

    def frame() -> None:
        manager.update()
        seen.extend(s.values for s in device.store.frame(DeviceKind.DIGITAL))

    assert wait_until(lambda: device.records >= 60, timeout=5, step=frame)
    # digital units 2..5 are the wand's buttons 0..3 (0/1), units 0 and 1 stay 0
    assert any(values[2:6] != (0, 0, 0, 0) for values in seen)
    for values in seen:
        assert len(values) == 6 and values[:2] == (0, 0) and sum(values[2:]) <= 1
    emu.pause()  # the last records sent are final: wait for the proxies to show them
    wand = next(s for s in reversed(emu.sent) if s[0] == 0)
    head = next(s for s in reversed(emu.sent) if s[0] == 1)
    expected_wand = pose_matrix(tuple(v * INCH for v in wand[1]), wand[2])
    expected_head = pose_matrix(tuple(v * INCH for v in head[1]), head[2])

    def shown() -> bool:
        positions = device.store.latest(DeviceKind.POSITION).values
        return bool(
            np.allclose(positions[0], expected_wand, atol=1e-6)
            and np.allclose(positions[1], expected_head, atol=1e-6)
            and device.store.latest(DeviceKind.ANALOG).values == (0.0, *map(float, wand[4]))
        )

    assert wait_until(shown, timeout=5, step=frame)
    assert manager.proxy("A1").data == pytest.approx(wand[4][0] / 255.0)  # raw byte at unit 1
    buttons = [manager.proxy(f"B{u}").data for u in range(2, 6)]
    expected = [bool(wand[3] >> k & 1) for k in range(4)]
    assert [b in (DigitalState.ON, DigitalState.TOGGLE_ON) for b in buttons] == expected


def test_garbage_is_counted_without_a_fault(tmp_path, emulator, managers) -> None:
    emu = emulator("garbage")
    manager = managers(tracker_element("IS", emu.address))
    device = reads_past_garbage(manager, "IS", 40)
    manager.shutdown()  # the two reads below agree only once no record arrives between them
    assert device.bad_records >= 20 and device.skipped_bytes > 0
    assert device.counters["records"] == device.records


def test_lost_line_faults_then_resumes_within_two_seconds(tmp_path, emulator, managers) -> None:
    link = tmp_path / "is900"
    emu = emulator("disconnect", disconnect_after=10, link=link)
    manager = managers(tracker_element("IS", str(link)))
    # 10 polls answered by 2 stations, none lost; then the tracker is back behind the link
    serial_line_lost_then_resumes(manager, "IS", emu, lambda: emulator("motion", link=link), 20)


def test_configuration_errors_leave_the_element_pending(tmp_path, managers) -> None:
    body = (
        '<intersense name="No Stations" version="1"><port>/dev/null</port></intersense>\n'
        '<intersense name="Bad Station" version="1"><port>/dev/null</port><stations>'
        '<intersense_station name="S" version="1"><station_index>99</station_index>'
        "</intersense_station></stations></intersense>\n"
    )
    pending = pending_reasons(managers(body))
    assert "no stations" in pending["No Stations"]
    assert "station_index 99" in pending["Bad Station"]


def corpus_example(tmp_path: Path, port: str) -> Path:
    return corpus_copy(
        "example.intersense.jconf",
        tmp_path,
        ("<port>/dev/ttyd11</port>", f"<port>{port}</port>"),
    )


def test_corpus_example_delivers_through_its_proxies_and_aliases(
    tmp_path, emulator, managers
) -> None:
    emu = emulator("motion")
    manager = managers(corpus_example(tmp_path, emu.address))
    assert not manager.pending()
    assert not [d for d in manager.diagnostics if d.code == "CFG034"]
    device = manager.device("Isense1")
    assert wait_until(lambda: device.records >= 20, timeout=5, step=manager.update)
    emu.pause()  # the last records sent are final: wait for the aliases to show them
    distances = {
        station: np.linalg.norm(
            np.asarray(next(s for s in reversed(emu.sent) if s[0] == station)[1]) * INCH
        )
        for station in (0, 1)
    }

    def shown() -> bool:
        # the filters rotate; the distance from the tracker's origin stays
        return all(
            abs(np.linalg.norm(manager.proxy(alias).matrix[:3, 3]) - distances[station]) < 1e-6
            for alias, station in (("VJWand", 0), ("VJHead", 1))
        )

    assert wait_until(shown, timeout=5, step=manager.update)
    assert not manager.proxy("VJWand").stupefied and not manager.proxy("VJHead").stupefied
    # the example reads neither buttons nor joystick (use_digital/use_analog false): units exist, 0
    for alias in ("VJButton0", "VJButton1", "VJButton2", "VJButton3"):
        assert manager.proxy(alias).data == DigitalState.OFF
    assert not manager.proxy("Analog 0 Proxy").stupefied


def test_gadgetctl_monitor_reads_the_corpus_example(tmp_path, emulator) -> None:
    emu = emulator("motion")
    config = corpus_example(tmp_path, emu.address)
    done, records = monitor_ndjson(config, duration=1, timeout=30)
    samples = samples_of(records, "Isense1")
    assert {r["kind"] for r in samples} == {"position", "digital", "analog"}, done.stderr[-2000:]
    assert {r["unit"] for r in samples if r["kind"] == "position"} == {0, 1}
    assert {r["unit"] for r in samples if r["kind"] == "digital"} == set(range(4))
    for command in (["validate"], ["doctor"], ["config", "pending"]):
        out = run_gadgetctl(*command, str(config), timeout=30)
        text = out.stdout + out.stderr
        assert "DRV001" not in text and "PENDING" not in text and "stays pending" not in text, text
        if command == ["config", "pending"]:
            assert "0 pending" in text
