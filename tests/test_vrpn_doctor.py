"""`gadgetctl doctor` for vrpn elements and vrpn:Device@host names, against the VRPN
driver's emulator (gadgetctl's VRPN server) on loopback."""

from __future__ import annotations

import json
import socket
import sys
from pathlib import Path

import pytest

from conftest import REPO

sys.path.insert(0, str(REPO / "drivers"))
from VRPN_drv.emulator import VrpnEmulator

pytestmark = pytest.mark.timeout(60)


def config(
    tmp_path: Path, tracker: str, button: str, analog: str = "", analog_count: int = 0
) -> Path:
    path = tmp_path / "vrpn.jconf"
    path.write_text(f"""<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="t">
<elements>
<input_manager name="IM" version="2"><driver>VRPN_drv</driver></input_manager>
<vrpn name="Remote" version="3">
  <tracker_server>{tracker}</tracker_server>
  <button_server>{button}</button_server>
  <analog_server>{analog}</analog_server>
  <tracker_count>2</tracker_count><button_count>4</button_count><analog_count>{analog_count}</analog_count>
</vrpn>
</elements>
</configuration>
""")
    return path


def test_probe_names_the_announced_devices_when_a_name_is_wrong(cli, tmp_path: Path) -> None:
    with VrpnEmulator(0, scenario="idle", rate=50, sensors=2, buttons=4, channels=1) as emu:
        path = config(
            tmp_path,
            f"Tracker0@{emu.address}",
            f"Buton0@tcp://{emu.address}",
            f"Analog0@{emu.address}",
            analog_count=0,
        )  # count 0: not used, not checked
        result = cli("doctor", path, "--probe", "--format", "json")
    assert result.exit_code == 1, result.stderr
    report = json.loads(result.stdout)
    (device,) = report["devices"]
    checks = {c["property"]: c for c in device["checks"]}
    assert set(checks) == {"tracker_server", "button_server"}
    assert checks["tracker_server"]["status"] == "ok"
    assert "VRPN 07.38 server" in checks["tracker_server"]["detail"]
    assert "2 sensors" in checks["tracker_server"]["detail"]
    assert checks["button_server"]["code"] == "DRV112"
    assert checks["button_server"]["detail"].endswith(
        "has no device 'Buton0'; it announces: Analog0, Button0, Tracker0"
    )
    (finding,) = [d for d in report["diagnostics"] if d["code"] == "DRV112"]
    assert finding["severity"] == "error" and finding["line"] == 8  # the button_server line


def test_without_probe_the_server_is_not_contacted(cli, tmp_path: Path) -> None:
    with VrpnEmulator(0, scenario="idle", rate=50) as emu:
        path = config(tmp_path, f"Tracker0@localhost:{emu.port}", f"Button0@{emu.address}")
        result = cli("doctor", path, "--format", "json")
        contacted = emu.server.counters["accepted"] + emu.server.counters["lobs"]
    assert result.exit_code == 0, result.stdout
    checks = json.loads(result.stdout)["devices"][0]["checks"]
    assert [c["status"] for c in checks] == ["unchecked", "unchecked"]
    assert "localhost is 127.0.0.1" in checks[0]["detail"]
    assert contacted == 0


def test_vrpn_names_on_the_command_line(cli) -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as holder:  # a port nobody serves
        holder.bind(("127.0.0.1", 0))
        free = holder.getsockname()[1]
        with VrpnEmulator(0, scenario="idle", rate=50) as emu:
            result = cli(
                "doctor",
                f"vrpn:Tracker0@{emu.address}",
                f"vrpn:Wand@tcp://{emu.address}",
                f"vrpn:Tracker0@tcp://127.0.0.1:{free}",
                "vrpn:NoHost",
                "--probe",
                "--timeout",
                "1",
            )
    assert result.exit_code == 1
    text = result.stdout
    assert f"ok       Tracker0@{emu.address}: the VRPN 07.38 server" in text
    assert "has no device 'Wand'; it announces: Analog0, Button0, Tracker0" in text
    assert f"DRV111 vrpn:Tracker0@tcp://127.0.0.1:{free}: no VRPN server answers" in text
    assert "DRV110 vrpn:NoHost: 'NoHost' is not written as Device@host" in text
    assert "Traceback" not in result.stderr


def test_a_listed_but_silent_name_is_not_taken_for_a_device(cli) -> None:
    # A C++ vrpn_server announces, for good, every name any client once described to it;
    # such a name answers no ping. This raw server does the same for 'Ghost'.
    import time

    from vrpn_peers import COOKIE, RawServer, describe

    def script(conn: socket.socket, n: int) -> None:
        conn.sendall(COOKIE)
        conn.recv(24)
        conn.sendall(
            describe(-1, 0, "VRPN Control")
            + describe(-1, 1, "Ghost")
            + describe(-2, 0, "vrpn_Base ping_message")
        )
        end = time.monotonic() + 3
        while time.monotonic() < end:  # read and never answer
            try:
                if not conn.recv(4096):
                    return
            except TimeoutError:
                pass

    with RawServer(script) as raw:
        result = cli(
            "doctor", f"vrpn:Ghost@tcp://127.0.0.1:{raw.port}", "--probe", "--timeout", "1"
        )
    assert result.exit_code == 1
    assert "lists 'Ghost' but nothing answers for it" in result.stdout
