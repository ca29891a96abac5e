"""The Ether I/O 24 driver against its loopback board: the 24 lines as 0/1 (upstream stored
raw bit values), inversion, the pin set-up written in upstream's order, garbage replies,
the board going silent and coming back, find_mac discovery (sent to loopback, never broadcast)."""

from __future__ import annotations

import socket
from pathlib import Path

import pytest
from ElexolEther24_drv.emulator import IDLE_PATTERN, MAC, Ether24Emulator
from ElexolEther24_drv.standalone import (
    DiscoveryCounts,
    find_board,
    format_mac,
    lines,
    parse_address,
    parse_mac,
)

from gadgetctl.input import DeviceKind, DigitalState
from gadgetctl.input.testing import frames_until
from gadgetctl.input.testing.commands import run_gadgetctl
from gadgetctl.input.testing.configs import configuration, pending_reasons, proxy
from gadgetctl.input.testing.fixtures import managers_fixture
from gadgetctl.input.testing.floods import bad_one_for_one

pytestmark = pytest.mark.timeout(30)

PRESSED = (DigitalState.ON, DigitalState.TOGGLE_ON)


def board(name: str, address: str, port_a: str = "", method: str = "static_ip") -> str:
    a = f'<port_a><elexol_ether24_port name="{name} A" version="1">{port_a}</elexol_ether24_port></port_a>'
    return (
        f'<elexol_ether24 name="{name}" version="1"><ip_address>{address}</ip_address>'
        f"<config_method>{method}</config_method>{a if port_a else ''}</elexol_ether24>\n"
    )


build = managers_fixture("ElexolEther24_drv", name="build", ready=True)


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
        body += "".join(proxy("digital", f"L{u}", "IO", u) for u in range(24))
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
            board("IO", emu.address)
            + "".join(proxy("digital", f"L{u}", "IO", u) for u in range(24))
        )
        seen: set[int] = set()

        def all_lines() -> bool:
            seen.update(u for u in range(24) if manager.proxy(f"L{u}").data in PRESSED)
            return len(seen) == 24

        frames_until(manager, all_lines, timeout=10.0)


def test_garbage_replies_are_counted_without_a_fault(build) -> None:
    with Ether24Emulator(0, scenario="garbage", rate=50.0) as emu:
        manager = build(board("IO", emu.address) + proxy("digital", "L0", "IO", 0))
        dev = manager.device("IO")
        frames_until(manager, lambda: dev.counters.get("bad_replies", 0) >= 30)
        frames_until(manager, lambda: dev.store.total(DeviceKind.DIGITAL) >= 10)
        assert manager.status("IO").state == "running" and dev.faults == 0
        assert dev.counters["replies"] >= 30


def test_a_silent_board_faults_and_data_returns_within_two_seconds(build) -> None:
    emu = Ether24Emulator(0, scenario="disconnect", rate=50.0, disconnect_after=20).start()
    port = emu.port
    try:
        manager = build(
            board("IO", emu.address) + proxy("digital", "L0", "IO", 0), peer_timeout=0.3
        )
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


def mac_board(name: str, mac: str) -> str:
    return (
        f'<elexol_ether24 name="{name}" version="1"><mac_address>{mac}</mac_address>'
        "<config_method>find_mac</config_method></elexol_ether24>\n"
    )


def test_find_mac_finds_the_board_by_its_mac_and_reads_its_lines(build, monkeypatch) -> None:
    # the discovery goes to the emulator's loopback address, never to a broadcast address
    with Ether24Emulator(0, scenario="idle") as emu:
        monkeypatch.setenv("GADGETCTL_ETHER24_DISCOVERY", emu.address)
        manager = build(
            mac_board("IO", format_mac(MAC).lower().replace(":", "-"))
            + proxy("digital", "L3", "IO", 3)
        )
        dev = manager.device("IO")
        frames_until(manager, lambda: dev.store.total(DeviceKind.DIGITAL) > 2)
        assert (dev.host, dev.board_port) == parse_address(emu.address)
        assert dev.counters["discovery_replies"] == 1
        expected = lines(list(IDLE_PATTERN), [0, 0, 0])[3]
        assert (manager.proxy("L3").data in PRESSED) == bool(expected)


def test_find_mac_with_no_such_board_is_pending_with_the_reason(build, monkeypatch) -> None:
    with Ether24Emulator(0, scenario="idle") as emu:
        monkeypatch.setenv("GADGETCTL_ETHER24_DISCOVERY", emu.address)
        manager = build(
            mac_board("Other", "00:00:00:00:00:01") + mac_board("Typo", "00:0A:BC:12:34"),
            ready=False,
        )
        reasons = pending_reasons(manager)
    assert "no Ether I/O 24 with MAC 00:00:00:00:00:01 answered" in reasons["Other"]
    assert emu.address in reasons["Other"]
    assert "mac_address" in reasons["Typo"] and "not a MAC address" in reasons["Typo"]


def test_a_bad_discovery_variable_is_a_config_error(build, monkeypatch) -> None:
    monkeypatch.setenv("GADGETCTL_ETHER24_DISCOVERY", "127.0.0.1:99999")
    manager = build(mac_board("IO", format_mac(MAC)), ready=False)
    (entry,) = manager.pending()
    assert "GADGETCTL_ETHER24_DISCOVERY" in entry.message


def test_find_board_passes_over_other_boards_and_counts_odd_replies() -> None:
    import socket
    import threading

    wanted = bytes.fromhex("0011223344ff")
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as responder:
        responder.bind(("127.0.0.1", 0))
        where = responder.getsockname()

        def answer() -> None:
            data, peer = responder.recvfrom(64)
            assert data == b"IO24"
            responder.sendto(b"IO24" + b"\x00" * 6 + b"\x01\x00", peer)  # another board
            responder.sendto(b"IO2", peer)  # too short
            responder.sendto(b"XX24" + wanted + b"\x01\x00", peer)  # wrong head
            responder.sendto(b"IO24" + wanted + b"\x02\x07", peer)

        thread = threading.Thread(target=answer)
        thread.start()
        counts = DiscoveryCounts()
        found = find_board(wanted, where, listen=5.0, counts=counts)
        thread.join(5.0)
    assert found is not None and found.mac == wanted and found.firmware == 0x0207
    assert (found.host, found.port) == where
    assert (counts.replies, counts.bad_replies) == (2, 2)


def test_mac_addresses_in_the_usual_spellings() -> None:
    raw = bytes.fromhex("000abc123456")
    assert (
        parse_mac("00:0A:BC:12:34:56")
        == parse_mac("00-0a-bc-12-34-56")
        == parse_mac("000ABC123456")
        == raw
    )
    assert format_mac(raw) == "00:0A:BC:12:34:56"
    for bad in ("", "00:0A:BC:12:34", "00:0A:BC:12:34:ZZ"):
        with pytest.raises(ValueError):
            parse_mac(bad)


def test_validate_knows_the_24_lines_and_doctor_the_board(tmp_path: Path) -> None:
    import json

    path = tmp_path / "units.jconf"
    path.write_text(
        configuration(
            "ElexolEther24_drv",
            board("IO", "127.0.0.1:2500")
            + proxy("digital", "Last", "IO", 23)
            + proxy("digital", "Beyond", "IO", 24),
        )
    )

    result = run_gadgetctl("validate", str(path), timeout=60)
    assert result.returncode == 1 and result.stdout.count("CFG034") == 1
    assert "'Beyond'" in result.stdout
    report = json.loads(run_gadgetctl("doctor", str(path), "--format", "json", timeout=60).stdout)
    (dev,) = report["devices"]
    assert dev["checks"][0]["target"] == "127.0.0.1:2500"
    assert dev["checks"][0]["status"] == "unchecked"


def test_doctor_names_the_mac_a_find_mac_board_is_found_by(tmp_path: Path) -> None:
    import json
    import subprocess
    import sys

    path = tmp_path / "mac.jconf"
    path.write_text(configuration("ElexolEther24_drv", mac_board("IO", "00:0A:BC:12:34:56")))
    command = [sys.executable, "-m", "gadgetctl", "doctor", str(path), "--format", "json"]
    report = json.loads(subprocess.run(command, capture_output=True, text=True, timeout=60).stdout)
    ((check,),) = [dev["checks"] for dev in report["devices"]]
    assert check["target"] == "MAC 00:0A:BC:12:34:56" and check["status"] == "unchecked"
    assert check["property"] == "mac_address"


def test_a_flood_of_malformed_replies_is_counted_bad_one_for_one(build) -> None:
    """Issue 23 item 4: every datagram from the board is a reply or a counted bad one."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as fake:
        fake.bind(("127.0.0.1", 0))
        fake.settimeout(10.0)
        host, port = fake.getsockname()
        manager = build(board("IO", f"{host}:{port}"), peer_timeout=60.0)
        _request, device_address = fake.recvfrom(64)  # the driver's first write

        def from_the_board(payloads) -> None:
            for payload in payloads:
                fake.sendto(payload, device_address)

        junk = [b"", b"Z\x01", b"A", b"A\x01\x02", b"\xff" * 40]
        counters = bad_one_for_one(
            manager, "IO", port, [junk[n % 5] for n in range(2000)], send=from_the_board
        )
    assert counters["bad_datagrams"] > 0 and counters["decoded"] == 0
    status = manager.status("IO")
    assert status.state == "undecodable" and "first: not a port reply" in status.reason
