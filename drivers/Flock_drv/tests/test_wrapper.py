"""The Flock device in an input manager, against the emulator over a real pty pair."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from Flock_drv.emulator import FlockEmulator
from Flock_drv.standalone import euler_matrix

from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.testing import (
    reads_past_garbage,
    serial_line_lost_then_resumes,
    wait_until,
)
from gadgetctl.input.testing.commands import monitor_ndjson, run_gadgetctl, samples_of
from gadgetctl.input.testing.configs import corpus_copy, pending_reasons
from gadgetctl.input.testing.fixtures import emulator_fixture, managers_fixture

pytestmark = pytest.mark.timeout(30)

FAST = {"reset_time": 0.0, "examine_delay": 0.0, "read_timeout": 1.0, "poll_interval": 0.005}
FOOT = 0.3048


def flock_element(name: str, port: str, extra: str = "") -> str:
    return (
        f'<flock name="{name}" version="2"><port>{port}</port><hemisphere>Upper</hemisphere>'
        f"{extra}</flock>\n"
        f'<position_proxy name="P0" version="1"><device>{name}</device><unit>0</unit></position_proxy>\n'
        f'<position_proxy name="P1" version="1"><device>{name}</device><unit>1</unit></position_proxy>\n'
    )


emulator = emulator_fixture(FlockEmulator, rate=144.0)
managers = managers_fixture("Flock_drv", tune={"flock": FAST})


def pose_matrix(position: tuple[float, ...], angles: tuple[float, ...]) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = euler_matrix(*angles)
    m[:3, 3] = position
    return m


def test_birds_reach_their_proxies_in_feet(tmp_path, emulator, managers) -> None:
    emu = emulator("motion", birds=2)
    manager = managers(flock_element("F", emu.address))
    assert not manager.pending()
    device = manager.device("F")
    assert wait_until(lambda: device.records >= 20, timeout=5, step=manager.update)
    assert set(emu.hemispheres.values()) == {b"\x0c\x01"}  # Upper
    manager.update()
    positions = device.store.latest(DeviceKind.POSITION).values
    assert len(positions) == 2
    sent = list(emu.sent)
    for unit in (0, 1):
        # the newest frame is one the emulator sent for that bird (the device may have read on)
        assert any(
            np.allclose(positions[unit], pose_matrix(position, angles), atol=2e-3)
            for bird, position, angles in sent
            if bird == unit
        ), unit
    assert device.faults == 0 and device.bad_records == 0


def test_garbage_is_counted_without_a_fault(tmp_path, emulator, managers) -> None:
    emu = emulator("garbage", birds=2)
    manager = managers(flock_element("F", emu.address))
    device = reads_past_garbage(manager, "F", 40)
    manager.shutdown()  # the two reads below agree only once no record arrives between them
    assert device.bad_records >= 20 and device.skipped_bytes > 0
    assert device.counters["records"] == device.records


def test_lost_line_faults_then_resumes_within_two_seconds(tmp_path, emulator, managers) -> None:
    link = tmp_path / "flock"
    emu = emulator("disconnect", birds=2, disconnect_after=10, link=link)
    manager = managers(flock_element("F", str(link)))
    # 10 frames of 2 birds, none lost; then the flock is back behind the link
    serial_line_lost_then_resumes(
        manager, "F", emu, lambda: emulator("motion", birds=2, link=link), 20, reopened=True
    )


def test_configuration_errors_leave_the_element_pending(tmp_path, managers) -> None:
    body = (
        '<flock name="Bad Hemisphere" version="2"><port>/dev/null</port>'
        "<hemisphere>9</hemisphere></flock>\n"
        '<flock name="No Port" version="2"><port></port></flock>\n'
    )
    pending = pending_reasons(managers(body))
    assert "hemisphere 9" in pending["Bad Hemisphere"]
    assert "port is empty" in pending["No Port"]


def corpus_example(tmp_path: Path, port: str) -> Path:
    return corpus_copy(
        "example.flock.jconf",
        tmp_path,
        ("<port>/dev/ttyd3</port>", f"<port>{port}</port>"),
    )


def test_corpus_example_delivers_through_its_proxies_and_aliases(
    tmp_path, emulator, managers
) -> None:
    emu = emulator("motion", birds=2)
    manager = managers(corpus_example(tmp_path, emu.address))
    assert not manager.pending()
    device = manager.device("Flock")
    assert wait_until(lambda: device.records >= 20, timeout=5, step=manager.update)
    manager.update()
    for alias in ("VJWand", "VJHead"):
        assert not manager.proxy(alias).stupefied
    # The device filter pre-translates by (0, 1.011936, 2.4384) m, rotates and turns the birds'
    # feet into metres; the wand proxy only post-rotates: its distance from the pre-translation
    # is the bird's distance from the transmitter, in metres.
    wand = np.asarray(manager.proxy("VJWand").matrix)
    offset = np.linalg.norm(wand[:3, 3] - np.array((0.0, 1.011936, 2.4384)))
    distances = [FOOT * np.linalg.norm(p) for bird, p, _a in list(emu.sent) if bird == 0]
    assert min(abs(offset - d) for d in distances) < 2e-3


def test_gadgetctl_monitor_reads_the_corpus_example(tmp_path, emulator) -> None:
    emu = emulator("motion", birds=2)
    config = corpus_example(tmp_path, emu.address)
    done, records = monitor_ndjson(config, duration=3, timeout=30)
    samples = samples_of(records, "Flock")
    assert {r["kind"] for r in samples} == {"position"}, done.stderr[-2000:]
    assert {r["unit"] for r in samples} == {0, 1}
    for command in (["validate"], ["doctor"], ["config", "pending"]):
        out = run_gadgetctl(*command, str(config), timeout=30)
        text = out.stdout + out.stderr
        assert "DRV001" not in text and "PENDING" not in text and "stays pending" not in text, text
        if command == ["config", "pending"]:
            assert "0 pending" in text
