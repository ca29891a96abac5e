"""The MotionStar wrapper in an input manager, against the emulator over loopback TCP."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from MotionStar_drv.emulator import MotionStarEmulator

from gadgetctl.input import InputManager, LengthUnit
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.pending import PendingKind
from gadgetctl.input.testing import resumes_within, wait_until
from gadgetctl.input.testing.commands import monitor_ndjson, samples_of
from gadgetctl.input.testing.configs import corpus_copy, corpus_file, rewritten
from gadgetctl.input.testing.fixtures import emulator_fixture, managers_fixture

pytestmark = pytest.mark.timeout(20)

EXAMPLE = Path(__file__).resolve().parents[1] / "example.jconf"

FAST = {"connect_timeout": 1.0, "read_timeout": 1.0, "sample_timeout": 0.05, "close_timeout": 0.2}
FULL_SCALE = 144  # the emulator's birds: inches at full scale


def units_filter(device_units: float, custom_scale: float = 1.0) -> str:
    zeros = "".join(
        f"<{p}>0.0</{p}>" * 3
        for p in ("pre_translate", "pre_rotation", "post_translate", "post_rotation")
    )
    return (
        f'<position_filters><position_transform_filter name="Units" version="1">{zeros}'
        f"<custom_scale>{custom_scale}</custom_scale><device_units>{device_units}</device_units>"
        "</position_transform_filter></position_filters>"
    )


def star(
    name: str, port: int, *, filters: str | None = None, version: int = 2, **props: object
) -> str:
    """A motion_star element (inches to meters unless ``filters`` says otherwise) and a proxy per unit."""
    values = {"address": "127.0.0.1", "server_port": port, **props}
    body = "".join(f"<{k}>{v}</{k}>" for k, v in values.items())
    body += units_filter(0.0254) if filters is None else filters
    proxies = "".join(
        f'<position_proxy name="{name} {unit}" version="1"><device>{name}</device>'
        f"<unit>{unit}</unit></position_proxy>\n"
        for unit in (0, 1)
    )
    return f'<motion_star name="{name}" version="{version}">{body}</motion_star>\n' + proxies


def rx(deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


def ry(deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, 0, s, 0], [0, 1, 0, 0], [-s, 0, c, 0], [0, 0, 0, 1.0]])


def rz(deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def move(x: float, y: float, z: float) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    return m


def sensor_pose(record: tuple, scale: float = 1.0) -> np.ndarray:
    """The pose a position/angles record describes, from the protocol description: position
    = full scale x word / 32767 inches (times ``scale``), rotation Rz·Ry·Rx of the Z, Y, X
    angles = 180 x word / 32767 degrees."""
    code, words, _buttons = record
    assert code == 4
    position = [FULL_SCALE * w / 32767 * scale for w in words[:3]]
    z, y, x = (180 * w / 32767 for w in words[3:6])
    return move(*position) @ rz(z) @ ry(y) @ rx(x)


def poses_sent(emu: MotionStarEmulator, sequence: int, scale: float = 0.0254) -> list[np.ndarray]:
    """Unit order = sensors in FBB address order."""
    records = emu.sent_data[sequence]
    return [sensor_pose(records[d.address], scale) for d in emu.sensors]


emulator = emulator_fixture(MotionStarEmulator, "idle", rate=200.0)
managers = managers_fixture("MotionStar_drv", tune={"motion_star": FAST})


def collect(manager: InputManager, device, into: list[np.ndarray]) -> Callable[[], None]:
    """A frame step that keeps every position sample of ``device``."""

    def frame() -> None:
        manager.update()
        into.extend(np.array(s.values) for s in device.store.frame(DeviceKind.POSITION))

    return frame


def sequence_of(emu: MotionStarEmulator, sample: np.ndarray, scale: float = 0.0254) -> int:
    for sequence in sorted(emu.sent_data):
        if np.allclose(sample, poses_sent(emu, sequence, scale), atol=1e-9):
            return sequence
    raise AssertionError("a sample matches no packet the emulator sent")


# -- units and values -------------------------------------------------------------------------


def test_example_positions_reach_proxies_in_meters_with_zyx_angles(
    tmp_path, emulator, managers
) -> None:
    emu = emulator("idle", birds=2, erc=True)  # an ERC at address 1: units are addresses 2 and 3
    manager = managers(
        rewritten(
            EXAMPLE,
            tmp_path,
            ("<server_port>6000</server_port>", f"<server_port>{emu.port}</server_port>"),
        )
    )
    assert not manager.pending()
    device = manager.device("MotionStar")
    assert wait_until(lambda: device.store.total(DeviceKind.POSITION) > 0)  # stored, not counted
    manager.update()
    expected = poses_sent(emu, device.sequence)
    for alias, unit in (("VJHead", 0), ("VJWand", 1)):
        proxy = manager.proxy(alias)
        assert not proxy.stupefied
        np.testing.assert_allclose(proxy.matrix, expected[unit], atol=1e-12)
        inches = proxy.matrix_in(LengthUnit.INCHES)[:3, 3]
        np.testing.assert_allclose(
            inches, sensor_pose(emu.sent_data[device.sequence][unit + 2])[:3, 3]
        )
        # the angles are applied Z, then Y, then X (not the other way round)
        _code, words, _ = emu.sent_data[device.sequence][unit + 2]
        z, y, x = (180 * w / 32767 for w in words[3:6])
        assert not np.allclose(proxy.matrix[:3, :3], (rx(x) @ ry(y) @ rz(z))[:3, :3], atol=1e-3)
    # the chassis got the element's settings
    for sensor in emu.sensors:
        assert sensor.status[6] == 0x64 and sensor.status[7] == 1 and sensor.status[10] == 0
    assert emu.measurement_rate == pytest.approx(86.1)


def test_sequence_numbers_follow_each_other_through_the_proxies(
    tmp_path, emulator, managers
) -> None:
    emu = emulator("motion", birds=2)
    manager = managers(star("Star", emu.port))
    device = manager.device("Star")
    samples: list[np.ndarray] = []
    assert wait_until(lambda: len(samples) >= 30, step=collect(manager, device, samples))
    first = sequence_of(emu, samples[0])
    for offset, sample in enumerate(samples):
        np.testing.assert_allclose(sample, poses_sent(emu, first + offset), atol=1e-9)
    # the proxies show the newest sample of the frame
    np.testing.assert_allclose(manager.proxy("Star 1").matrix, samples[-1][1])
    # Exact totals only once sampling has stopped: the sampling thread counts a packet, then
    # adds its sample, while this thread reads one count and then the other (a pause between
    # the two reads under load let two more packets in: 34 counted before, 36 in the store).
    manager.shutdown()
    assert device.sequence_gaps == 0
    assert device.packets == device.store.total(DeviceKind.POSITION) >= len(samples)


@pytest.mark.parametrize(
    ("filters", "scale", "warning"),
    [
        (
            units_filter(0.3048),
            0.3048,
            "device_units 0.3048, but the MotionStar reports inches: positions come out 12 times",
        ),
        ("", 1.0, "no position_transform_filter gives the device units"),
        (units_filter(0.0, custom_scale=0.0254), 0.0254, None),
    ],
)
def test_device_units_scale_and_warn(tmp_path, emulator, managers, filters, scale, warning) -> None:
    emu = emulator("idle", birds=2)
    manager = managers(star("Star", emu.port, filters=filters))
    device = manager.device("Star")
    found = [d.message for d in manager.diagnostics if d.code == "DRV024"]
    if warning is None:
        assert found == []
    else:
        assert len(found) == 1 and warning in found[0]
    assert wait_until(lambda: device.store.total(DeviceKind.POSITION) > 0)  # stored, not counted
    manager.update()
    np.testing.assert_allclose(
        manager.proxy("Star 0").matrix, poses_sent(emu, device.sequence, scale)[0], atol=1e-12
    )


def test_single_shot_mode_asks_for_every_packet(tmp_path, emulator, managers) -> None:
    emu = emulator("motion", birds=2)
    manager = managers(
        star("Star", emu.port, mode="Sample Individually", hemisphere="Upper", report_rate=3)
    )
    device = manager.device("Star")
    assert wait_until(lambda: device.packets >= 5)
    kinds = [kind for kind, _, _ in emu.received]
    assert 104 not in kinds and kinds.count(103) >= 5  # no streaming: one single shot per packet
    assert all(sensor.status[10] == 2 and sensor.status[7] == 3 for sensor in emu.sensors)
    assert device.sequence_gaps == 0


def test_garbage_is_skipped_without_a_fault(tmp_path, emulator, managers) -> None:
    emu = emulator("garbage", birds=2)
    manager = managers(star("Star", emu.port))
    device = manager.device("Star")
    samples: list[np.ndarray] = []
    assert wait_until(lambda: len(samples) >= 24, step=collect(manager, device, samples))
    first = sequence_of(emu, samples[0])
    for offset, sample in enumerate(samples):
        np.testing.assert_allclose(sample, poses_sent(emu, first + offset), atol=1e-9)
    assert device.bad_packets >= 24 and device.skipped_bytes > 0
    assert device.faults == 0 and device.sequence_gaps == 0


def test_only_junk_faults_the_device_and_samples_resume_when_data_return(
    tmp_path, emulator, managers, monkeypatch
) -> None:
    emu = emulator("motion", birds=2)
    manager = managers(star("Star", emu.port))
    device = manager.device("Star")
    monkeypatch.setattr(type(device), "data_timeout", 0.5)
    assert wait_until(lambda: device.packets > 0, step=manager.update)

    emu.noise.set()  # random bytes instead of data packets, on this and later connections
    assert wait_until(lambda: device.faults >= 1, timeout=10, step=manager.update)
    status = manager.status("Star")
    assert status.code == "DRV042" and "only junk for" in status.reason, status
    assert "bytes skipped, no data packet" in status.reason
    states: list[str] = []

    def watch() -> None:
        manager.update()
        state = manager.status("Star").state
        if not states or states[-1] != state:
            states.append(state)

    # reconnections do not help while only junk arrives, and none of them reads "running"
    assert wait_until(lambda: states.count("reconnecting") >= 2, timeout=15, step=watch)
    assert "running" not in states and {"faulted", "reconnecting"} >= set(states)
    assert "only junk for" in manager.status("Star").reason
    assert device.counters["skipped_bytes"] > 0 and device.counters["bad_packets"] >= 2

    packets = device.packets
    emu.noise.clear()
    assert wait_until(
        lambda: device.packets > packets and manager.status("Star").state == "running",
        timeout=10,
        step=manager.update,
    )


# -- faults and restarts ----------------------------------------------------------------------


def test_lost_server_faults_then_resumes_within_two_seconds(tmp_path, emulator, managers) -> None:
    emu_a = emulator("motion", birds=2)
    emu_b = emulator("motion", birds=2)
    manager = managers(star("Star A", emu_a.port) + star("Star B", emu_b.port))
    star_a, star_b = manager.device("Star A"), manager.device("Star B")
    samples_b: list[np.ndarray] = []
    frame = collect(manager, star_b, samples_b)

    assert wait_until(lambda: star_a.packets >= 3, step=frame)
    emu_a.stop()  # the chassis goes away: the connection closes
    assert wait_until(lambda: manager.status("Star A").state == "faulted", timeout=2, step=frame)
    status = manager.status("Star A")
    assert status.code == "DRV042" and "MotionStarDisconnected" in status.reason
    wait_until(lambda: False, timeout=0.6, step=frame)  # reconnections are refused meanwhile
    assert manager.status("Star A").state in ("faulted", "reconnecting")
    assert "cannot connect" in (manager.status("Star A").reason or "")

    # back on the same port
    resumes_within(
        manager,
        "Star A",
        lambda: emulator("motion", birds=2, port=emu_a.port),
        lambda: star_a.packets,
        step=frame,
    )
    assert star_a.restarts >= 1
    assert star_a.faults >= 1

    # the other chassis went on and lost nothing: consecutive packets, none missing
    assert star_b.faults == 0 and star_b.sequence_gaps == 0
    first = sequence_of(emu_b, samples_b[0])
    for offset, sample in enumerate(samples_b):
        np.testing.assert_allclose(sample, poses_sent(emu_b, first + offset), atol=1e-9)


def test_disconnect_scenario_faults_the_device(tmp_path, emulator, managers) -> None:
    emu = emulator("disconnect", birds=1, disconnect_after=4)
    manager = managers(star("Star", emu.port))
    assert emu.disconnected.wait(3)
    assert wait_until(lambda: manager.device("Star").faults >= 1, step=manager.update)
    assert manager.device("Star").packets >= 4


def test_stop_and_start_again(tmp_path, emulator, managers) -> None:
    emu = emulator("idle", birds=2)
    manager = managers(star("Star", emu.port))
    device = manager.device("Star")
    assert wait_until(lambda: device.packets > 0)
    manager.shutdown()  # stop-data and shut-down are sent
    assert [kind for kind, _, _ in emu.received][-2:] == [105, 11]
    assert device.ms is None
    device.start_sampling()
    try:
        assert wait_until(lambda: device.packets >= 2, step=device.sample)
        assert emu.connections == 2
    finally:
        device.stop_sampling()


# -- configuration ----------------------------------------------------------------------------


def test_configuration_errors_leave_the_element_pending(tmp_path, managers) -> None:
    body = (
        star("UDP", 5000)
        + star("No Address", 6000, address="")
        + star("Bad Format", 6000, data_format=6)
        + star("Bad Rate", 6000, report_rate=0)
        + '<motion_star name="Old" version="1"><address>mstar</address></motion_star>\n'
    )
    manager = managers(body)
    pending = {p.name: p for p in manager.pending()}
    assert set(pending) == {"UDP", "No Address", "Bad Format", "Bad Rate", "Old"}
    assert pending["UDP"].kind is PendingKind.CONFIG_FAILED
    assert "server_port 5000 selects BIRDNET over UDP" in pending["UDP"].message
    assert pending["No Address"].message.startswith("address is empty")
    assert pending["Bad Format"].message.startswith("data_format 6 is not one of")
    assert "report_rate 0" in pending["Bad Rate"].message
    assert pending["Old"].kind is PendingKind.TOO_OLD and pending["Old"].code == "DRV037"
    # their proxies exist but have no device
    assert manager.proxy("UDP 0").stupefied and "UDP" in manager.proxy("UDP 0").reason


def test_measurement_rate_outside_the_range_is_clamped_with_a_warning(
    tmp_path, emulator, managers
) -> None:
    emu = emulator("idle", birds=2)
    manager = managers(star("Star", emu.port, measurement_rate=500))
    assert not manager.pending()
    found = [d.message for d in manager.diagnostics if d.code == "DRV024"]
    assert found == [
        "Star: measurement_rate 500 Hz is outside 20-144 Hz; the chassis is set to 144 Hz"
    ]
    assert emu.measurement_rate == pytest.approx(144.0)


# -- the VR Juggler configuration -------------------------------------------------------------


def c4_files(tmp_path: Path, port: int) -> list[Path]:
    """C4.mstar.jconf pointed at the emulator, after C4.base.jconf as C4.closed.jconf loads them.
    C4.mstar.jconf is complete for input on its own; the base's user element takes its head
    position from VJHead, an alias of the MotionStar's HeadProxy. The displays and the RF wand
    of C4.closed.jconf need other drivers and are left out."""
    mstar = corpus_copy(
        "C4.mstar.jconf",
        tmp_path,
        ("<address>mstar3</address>", "<address>127.0.0.1</address>"),
        ("<server_port>6000</server_port>", f"<server_port>{port}</server_port>"),
    )
    return [corpus_file("C4.base.jconf"), mstar]


def c4_expected(emu: MotionStarEmulator, sequence: int) -> dict[str, np.ndarray]:
    """The C4 filters by hand: device level Pre·S(M) with Pre = T(0, 2.53999, 0.47625)·Rx(90)·Rz(180)
    and S scaling by device_units 0.3048; then each proxy's M·Post (device_units 1)."""
    pre = move(0.0, 2.53999, 0.47625) @ rx(90.0) @ ry(0.0) @ rz(180.0)
    poses = []
    for raw in poses_sent(emu, sequence, scale=1.0):
        scaled = raw.copy()
        scaled[:3, 3] *= 0.3048
        poses.append(pre @ scaled)
    head = poses[1] @ move(-0.0826008, 0.0, 0.0509016) @ ry(-90.0)
    wand = poses[0] @ rz(-90.0)
    return {"VJHead": head, "HeadProxy": head, "VJWand": wand, "WandProxy": wand}


def test_corpus_c4_mstar_delivers_through_its_proxies_and_aliases(
    tmp_path, emulator, managers
) -> None:
    emu = emulator("motion", birds=2)
    manager = managers(*c4_files(tmp_path, emu.port))
    assert not manager.pending(), [(p.name, p.message) for p in manager.pending()]
    device = manager.device("Motion Star master")
    assert device.is_master is False  # read, and ignored like the C++ driver does
    # the element's settings reached the chassis: Lower hemisphere, 72.4 Hz, position/angles
    assert all(s.status[10] == 3 and s.status[6] == 0x64 for s in emu.sensors)
    assert emu.measurement_rate == pytest.approx(72.4)
    # its filter says feet while the chassis reports inches, as upstream warned at start-up
    found = [d.message for d in manager.diagnostics if d.code == "DRV024"]
    assert len(found) == 1 and "device_units 0.3048" in found[0] and "12 times" in found[0]

    assert wait_until(lambda: device.store.total(DeviceKind.POSITION) >= 3)  # stored
    manager.update()
    for name, matrix in c4_expected(emu, device.sequence).items():
        proxy = manager.proxy(name)
        assert not proxy.stupefied, proxy.reason
        np.testing.assert_allclose(proxy.matrix, matrix, atol=1e-9)


def test_gadgetctl_monitor_reads_the_corpus_configuration(tmp_path, emulator) -> None:
    emu = emulator("motion", birds=2, rate=100.0)
    config = c4_files(tmp_path, emu.port)[1]
    done, records = monitor_ndjson(config, duration=1, timeout=30)
    samples = samples_of(records, "Motion Star master")
    assert samples, done.stdout[-2000:] + done.stderr[-2000:]
    assert {r["kind"] for r in samples} == {"position"} and {r["unit"] for r in samples} == {0, 1}
    assert len(samples) >= 20  # about 100 packets a second, two sensors each
    assert emu.connections >= 1
