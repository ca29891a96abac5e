"""The VRPN device in the input manager against the emulator (gadgetctl's VRPN server) and
raw-socket servers, over loopback: units through proxies and aliases, normalised analogs,
button toggles, several elements and servers, a server down, gone and back, a wrong device
name, a hostile server, and the corpus example."""

from __future__ import annotations

import re
import socket
import struct
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from VRPN_drv.emulator import VrpnEmulator, analog_values, sensor_pose
from VRPN_drv.standalone import pose_matrix

from gadgetctl.input import DeviceKind, DigitalState, InputManager, ManagerOptions, RestartPolicy
from gadgetctl.input.testing import frames_until
from gadgetctl.input.testing.configs import alias, corpus_file, proxy
from gadgetctl.input.testing.fixtures import managers_fixture

pytestmark = pytest.mark.timeout(60)

COOKIE = bytes.fromhex("7672706e3a207665722e2030372e33382020300000000000")


def vrpn(
    name: str,
    address: str,
    sensors: int = 2,
    buttons: int = 4,
    channels: int = 2,
    *,
    tracker: str = "Tracker0",
    extra: str = "",
) -> str:
    return (
        f'<vrpn name="{name}" version="3">'
        f"<tracker_server>{tracker}@{address}</tracker_server><button_server>Button0@{address}</button_server>"
        f"<analog_server>Analog0@{address}</analog_server><tracker_count>{sensors}</tracker_count>"
        f"<button_count>{buttons}</button_count><analog_count>{channels}</analog_count>"
        f"<min>-1.0</min><max>1.0</max>{extra}</vrpn>\n"
    )


build = managers_fixture(
    "VRPN_drv",
    name="build",
    ready=True,
    options=ManagerOptions(
        retry_interval=None,
        entry_points=False,
        restart=RestartPolicy(initial_delay=0.05, max_delay=0.5),
    ),
)


def reserved_port() -> socket.socket:
    """A UDP socket holding a port nobody serves VRPN on (lobs to it go unanswered)."""
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    return s


def total(manager: InputManager, device: str, kind: DeviceKind) -> int:
    return manager.device(device).store.total(kind)


@pytest.mark.parametrize("scheme", ["", "tcp://"])
def test_units_through_proxies_and_aliases(build, scheme) -> None:
    with VrpnEmulator(0, scenario="idle", rate=200, sensors=3, buttons=4, channels=3) as emu:
        body = vrpn("V", f"{scheme}{emu.address}", sensors=3, buttons=4, channels=3)
        for unit in range(3):
            body += proxy("position", f"P{unit}", "V", unit) + alias(f"VJP{unit}", f"P{unit}")
        body += proxy("analog", "A2", "V", 2) + proxy("digital", "B3", "V", 3)
        manager = build(body)
        frames_until(
            manager,
            lambda: (
                total(manager, "V", DeviceKind.POSITION) > 5
                and total(manager, "V", DeviceKind.ANALOG) > 5
            ),
            timeout=10,
        )
        assert manager.status("V").state == "running"
    for unit in range(3):
        position, quat = sensor_pose(0, unit, False)
        np.testing.assert_allclose(
            manager.proxy(f"VJP{unit}").matrix, pose_matrix(position, quat), atol=1e-9
        )
    expected = (analog_values(0, 3, False)[2] + 1.0) / 2.0  # normalised from [-1, 1]
    assert manager.proxy("A2").data == pytest.approx(expected, abs=1e-12)
    assert manager.proxy("B3").data == DigitalState.OFF


def test_quaternion_and_device_filters() -> None:
    # A quarter turn about z turns x onto y; position passes through.
    s = np.sin(np.pi / 4)
    m = pose_matrix((1.0, 2.0, 3.0), (0.0, 0.0, s, s))
    np.testing.assert_allclose(m[:3, :3] @ [1, 0, 0], [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(m[:3, 3], [1, 2, 3])
    # A quaternion that is not of unit length is normalised; a zero one is no rotation.
    np.testing.assert_allclose(pose_matrix((1.0, 2.0, 3.0), (0.0, 0.0, 2.0, 2.0)), m, atol=1e-12)
    np.testing.assert_allclose(pose_matrix((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0)), np.eye(4))


def test_buttons_toggle_and_positions_move(build) -> None:
    with VrpnEmulator(0, scenario="buttons", rate=200, sensors=1, buttons=2, channels=0) as emu:
        manager = build(
            vrpn("V", emu.address, sensors=1, buttons=2, channels=0)
            + proxy("digital", "B0", "V", 0)
            + proxy("digital", "B1", "V", 1)
            + proxy("position", "P0", "V", 0)
        )
        seen: set = set()

        def pressed_both() -> bool:
            seen.update((n, manager.proxy(n).data) for n in ("B0", "B1"))
            return {
                ("B0", DigitalState.TOGGLE_ON),
                ("B1", DigitalState.TOGGLE_ON),
                ("B0", DigitalState.TOGGLE_OFF),
            } <= seen

        frames_until(manager, pressed_both, timeout=15)
        xs = {round(float(manager.proxy("P0").matrix[0, 3]), 9)}
        frames_until(
            manager,
            lambda: xs.add(round(float(manager.proxy("P0").matrix[0, 3]), 9)) or len(xs) > 3,
        )


def test_device_level_filters_apply(build) -> None:
    filters = (
        '<position_filters><position_transform_filter name="F" version="1">'
        "<pre_translate>0.0</pre_translate><pre_translate>0.5</pre_translate><pre_translate>0.0</pre_translate>"
        "<custom_scale>1.0</custom_scale><device_units>1.0</device_units>"
        "</position_transform_filter></position_filters>"
    )
    with VrpnEmulator(0, scenario="idle", rate=200, sensors=1, buttons=0, channels=0) as emu:
        manager = build(
            vrpn("V", emu.address, 1, 0, 0, extra=filters) + proxy("position", "P", "V", 0)
        )
        frames_until(manager, lambda: total(manager, "V", DeviceKind.POSITION) > 2, timeout=10)
    position, _quat = sensor_pose(0, 0, False)
    assert manager.proxy("P").matrix[1, 3] == pytest.approx(position[1] + 0.5, abs=1e-9)


def test_several_elements_against_several_servers(build) -> None:
    with (
        VrpnEmulator(0, scenario="motion", rate=100, sensors=1, buttons=1, channels=1) as a,
        VrpnEmulator(0, scenario="motion", rate=100, sensors=2, buttons=2, channels=2) as b,
    ):
        manager = build(
            vrpn("VA", a.address, 1, 1, 1)
            + vrpn("VB", b.address, 2, 2, 2)
            + vrpn("VB2", f"tcp://{b.address}", 2, 0, 0)
        )
        frames_until(
            manager,
            lambda: all(total(manager, n, DeviceKind.POSITION) > 10 for n in ("VA", "VB", "VB2")),
            timeout=15,
        )
        assert {c.mode for c in b.server.clients} == {"lob", "tcp"}
    assert manager.device("VB").remote_clock.count > 0
    clock = manager.device("VB").remote_clock.to_dict()
    assert abs(clock["offset"]) < 5 and clock["latency"] >= 0  # same machine: small offset


def test_server_down_then_up_then_gone_then_back(build) -> None:
    holder = reserved_port()
    port = holder.getsockname()[1]
    manager = build(vrpn("V", f"127.0.0.1:{port}", 1, 1, 0) + proxy("position", "P", "V", 0))
    frames_until(
        manager, lambda: manager.status("V").state in ("faulted", "reconnecting"), timeout=10
    )
    assert "no VRPN server" in manager.status("V").reason
    holder.close()
    for _ in range(2):
        with VrpnEmulator(port, scenario="motion", rate=100, sensors=1, buttons=1, channels=0):
            before = total(manager, "V", DeviceKind.POSITION)
            frames_until(
                manager,
                lambda b=before: total(manager, "V", DeviceKind.POSITION) > b + 5,
                timeout=10,
            )
            assert manager.status("V").state == "running"
        frames_until(
            manager, lambda: manager.status("V").state in ("faulted", "reconnecting"), timeout=10
        )
    assert manager.device("V").stats.faults >= 2


def test_a_wrong_device_name_names_the_announced_ones(build) -> None:
    with VrpnEmulator(0, scenario="idle", rate=50, sensors=1, buttons=0, channels=0) as emu:
        manager = build(vrpn("V", emu.address, 1, 0, 0, tracker="Trakcer0"))
        frames_until(
            manager,
            lambda: (
                manager.status("V").state in ("faulted", "reconnecting")
                and "Trakcer0" in (manager.status("V").reason or "")
            ),
            timeout=10,
        )
    reason = manager.status("V").reason
    assert "has no device 'Trakcer0'" in reason and "Tracker0" in reason


def _hostile(conn: socket.socket, n: int) -> None:
    """Garbage, a wrong cookie, an oversized message, a short tracker report, in turn."""
    kind = n % 4
    if kind == 0:
        conn.sendall(b"\x00garbage" * 100)
    elif kind == 1:
        conn.sendall(b"vrpn: ver. 08.00  0" + b"\0" * 5)
    else:
        conn.sendall(COOKIE)

        def desc(k, i, s):
            return (
                struct.pack(">IiiiiI", 24 + 5 + len(s), 0, 0, i, k, 0)
                + struct.pack(">I", len(s) + 1)
                + s
                + b"\0"
                + b"\0" * (-(5 + len(s)) % 8)
            )

        conn.sendall(desc(-1, 0, b"Tracker0") + desc(-2, 0, b"vrpn_Tracker Pos_Quat"))
        if kind == 2:
            conn.sendall(struct.pack(">IiiiiI", 9_000_000, 0, 0, 0, 0, 0))
        else:
            conn.sendall(struct.pack(">IiiiiI", 24 + 40, 0, 0, 0, 0, 0) + b"\0" * 40)
    time.sleep(0.1)


def test_a_hostile_server_is_counted_and_survived(build) -> None:
    listener = socket.socket()
    listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    listener.bind(("127.0.0.1", 0))
    listener.listen(8)
    listener.settimeout(0.1)
    port = listener.getsockname()[1]
    served = [0]
    stop = threading.Event()

    def run() -> None:
        while not stop.is_set():
            try:
                conn, _ = listener.accept()
            except OSError:
                continue
            served[0] += 1
            with conn:
                try:
                    _hostile(conn, served[0])
                except OSError:
                    pass

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    manager = build(vrpn("V", f"tcp://127.0.0.1:{port}", 1, 0, 0))
    try:
        frames_until(manager, lambda: served[0] >= 6, timeout=20)
    finally:
        stop.set()
        thread.join(5)
        listener.close()
    counters = manager.device("V").counters
    assert (
        counters["bad_cookies"] >= 2 and counters["oversized"] >= 1 and counters["bad_reports"] >= 1
    ), counters
    # (the last hostile connection may still be ending: wait for the fault)
    frames_until(
        manager, lambda: manager.status("V").state in ("faulted", "reconnecting"), timeout=10
    )
    assert re.search(r"VRPN server", manager.status("V").reason or "")
    # The same port serves properly now: the device recovers.
    with VrpnEmulator(port, scenario="motion", rate=100, sensors=1, buttons=0, channels=0):
        frames_until(
            manager,
            lambda: (
                manager.status("V").state == "running"
                and total(manager, "V", DeviceKind.POSITION) > 5
            ),
            timeout=15,
        )


def test_corpus_example_with_only_the_server_names_changed(build, tmp_path: Path) -> None:
    text = corpus_file("example.vrpn.jconf").read_text()
    with VrpnEmulator(0, scenario="buttons", rate=100, sensors=2, buttons=4, channels=0) as emu:
        changed = text.replace("alpha.cs.ucl.ac.uk", emu.address)
        assert changed.count(emu.address) == 3
        path = tmp_path / "example.vrpn.jconf"
        path.write_text(changed)
        manager = build(path)
        frames_until(
            manager,
            lambda: (
                total(manager, "Vrpn", DeviceKind.POSITION) > 5
                and total(manager, "Vrpn", DeviceKind.DIGITAL) > 3
            ),
            timeout=15,
        )
        for name in (
            "VJHead",
            "VJWand",
            "VJButton0",
            "VJButton1",
            "VJButton2",
            "VJButton3",
            "HeadProxy",
            "WandProxy",
            "Button3Proxy",
        ):
            assert manager.status(name).state == "active", (name, manager.status(name))
        assert manager.proxy("VJHead").matrix[3, 3] == 1.0
