"""The Ether I/O 24 driver against its loopback board: the 24 lines as 0/1 (upstream stored
raw bit values), inversion, the pin set-up written in upstream's order, garbage replies,
the board going silent and coming back, find_mac refused without broadcasting."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from ElexolEther24_drv.emulator import IDLE_PATTERN, Ether24Emulator
from ElexolEther24_drv.standalone import lines, parse_address

from gadgetctl.input import DeviceKind, DigitalState, InputManager, ManagerOptions
from gadgetctl.input.testing import frames_until

pytestmark = pytest.mark.timeout(30)

HEAD = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="test">
<elements>
<input_manager name="IM" version="2"><driver>ElexolEther24_drv</driver></input_manager>
"""
PRESSED = (DigitalState.ON, DigitalState.TOGGLE_ON)


def board(name: str, address: str, port_a: str = "", method: str = "static_ip") -> str:
    a = f'<port_a><elexol_ether24_port name="{name} A" version="1">{port_a}</elexol_ether24_port></port_a>'
    return (
        f'<elexol_ether24 name="{name}" version="1"><ip_address>{address}</ip_address>'
        f"<config_method>{method}</config_method>{a if port_a else ''}</elexol_ether24>\n"
    )


def proxy(name: str, dev: str, unit: int) -> str:
    return f'<digital_proxy name="{name}" version="1"><device>{dev}</device><unit>{unit}</unit></digital_proxy>\n'


@pytest.fixture
def build(tmp_path: Path) -> Iterator[Callable[..., InputManager]]:
    made: list[InputManager] = []

    def make(
        body: str, peer_timeout: float | None = None, pending_ok: bool = False
    ) -> InputManager:
        path = tmp_path / f"t{len(made)}.jconf"
        path.write_text(HEAD + body + "</elements>\n</configuration>\n")
        manager, configuration = InputManager.from_files(
            [path], options=ManagerOptions(retry_interval=None, entry_points=False)
        )
        made.append(manager)
        manager.configure(configuration)
        if not pending_ok:
            assert not manager.pending(), [(p.name, p.message) for p in manager.pending()]
        if peer_timeout is not None:
            for dev in manager.devices.values():
                dev.peer_timeout = peer_timeout
        return manager

    yield make
    for manager in made:
        manager.shutdown()


def test_lines_are_zero_or_one_after_inversion() -> None:
    assert lines([0x08, 0x00, 0x80], [0, 0, 0])[3] == 1  # upstream stored 8
    values = lines([0xA5, 0x0F, 0x81], [0xFF, 0, 0])
    assert set(values) == {0, 1} and len(values) == 24
    assert values[:8] == [0, 1, 0, 1, 1, 0, 1, 0]  # 0xA5 inverted is 0x5A
    assert values[16] == 1 and values[23] == 1 and values[20] == 0


def test_addresses_with_and_without_a_port() -> None:
    assert parse_address("10.0.0.5") == ("10.0.0.5", 2424)
    assert parse_address("127.0.0.1:5000") == ("127.0.0.1", 5000)
    with pytest.raises(ValueError):
        parse_address("127.0.0.1:70000")


def test_24_lines_through_proxies_and_the_setup_written(build) -> None:
    with Ether24Emulator(0, scenario="idle") as emu:
        body = board("IO", emu.address, "<invert0>1</invert0><pullup1>0</pullup1>")
        body += "".join(proxy(f"L{u}", "IO", u) for u in range(24))
        manager = build(body)
        frames_until(manager, lambda: manager.device("IO").store.total(DeviceKind.DIGITAL) > 2)
        expected = lines(list(IDLE_PATTERN), [0x01, 0, 0])
        got = [1 if manager.proxy(f"L{u}").data in PRESSED else 0 for u in range(24)]
        assert got == expected
        assert set(manager.device("IO").store.latest(DeviceKind.DIGITAL).values) <= {0, 1}
        # port A: start level, then direction, pull-up, threshold, Schmitt (upstream's order)
        assert emu.writes[:5] == [b"A\x00", b"!A\xff", b"@A\xfd", b"#A\xff", b"$A\xff"]
        assert len(emu.writes) == 15


def test_each_line_goes_high_in_turn(build) -> None:
    with Ether24Emulator(0, scenario="buttons", rate=100.0) as emu:
        manager = build(
            board("IO", emu.address) + "".join(proxy(f"L{u}", "IO", u) for u in range(24))
        )
        seen: set[int] = set()

        def all_lines() -> bool:
            seen.update(u for u in range(24) if manager.proxy(f"L{u}").data in PRESSED)
            return len(seen) == 24

        frames_until(manager, all_lines, timeout=10.0)


def test_garbage_replies_are_counted_without_a_fault(build) -> None:
    with Ether24Emulator(0, scenario="garbage", rate=50.0) as emu:
        manager = build(board("IO", emu.address) + proxy("L0", "IO", 0))
        dev = manager.device("IO")
        frames_until(manager, lambda: dev.counters.get("bad_replies", 0) >= 30)
        frames_until(manager, lambda: dev.store.total(DeviceKind.DIGITAL) >= 10)
        assert manager.status("IO").state == "running" and dev.faults == 0
        assert dev.counters["replies"] >= 30


def test_a_silent_board_faults_and_data_returns_within_two_seconds(build) -> None:
    emu = Ether24Emulator(0, scenario="disconnect", rate=50.0, disconnect_after=20).start()
    port = emu.port
    try:
        manager = build(board("IO", emu.address) + proxy("L0", "IO", 0), peer_timeout=0.3)
        dev = manager.device("IO")
        frames_until(manager, lambda: emu.finished.is_set() and dev.store.total() > 3)
        frames_until(manager, lambda: manager.status("IO").state == "faulted")
        assert "Ether I/O 24" in manager.status("IO").reason
    finally:
        emu.stop()
    with Ether24Emulator(port, scenario="motion", rate=50.0):
        count = dev.store.total()
        resumed = frames_until(manager, lambda: dev.store.total() > count, timeout=4.0)
        assert resumed < 2.0
        frames_until(manager, lambda: manager.status("IO").state == "running")
    assert dev.restarts >= 1


def test_find_mac_stays_pending_without_broadcasting(build) -> None:
    manager = build(board("IO", "", method="find_mac"), pending_ok=True)
    reasons = {p.name: p.message for p in manager.pending()}
    assert "broadcasting" in reasons["IO"] and "static_ip" in reasons["IO"]


def test_validate_knows_the_24_lines_and_doctor_the_board(tmp_path: Path) -> None:
    import json
    import subprocess
    import sys

    path = tmp_path / "units.jconf"
    path.write_text(
        HEAD
        + board("IO", "127.0.0.1:2500")
        + proxy("Last", "IO", 23)
        + proxy("Beyond", "IO", 24)
        + "</elements>\n</configuration>\n"
    )

    def gadgetctl(*args: str) -> subprocess.CompletedProcess:
        command = [sys.executable, "-m", "gadgetctl", *args]
        return subprocess.run(command, capture_output=True, text=True, timeout=60)

    result = gadgetctl("validate", str(path))
    assert result.returncode == 1 and result.stdout.count("CFG034") == 1
    assert "'Beyond'" in result.stdout
    report = json.loads(gadgetctl("doctor", str(path), "--format", "json").stdout)
    (dev,) = report["devices"]
    assert dev["checks"][0]["target"] == "127.0.0.1:2500"
    assert dev["checks"][0]["status"] == "unchecked"
