"""The PinchGlove wrapper in an input manager, against the emulator over a real pty pair."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from PinchGlove_drv.emulator import (
    DEFAULT_INFO,
    L_INDEX,
    L_PINKY,
    L_RING,
    L_THUMB,
    R_INDEX,
    R_PINKY,
    R_RING,
    R_THUMB,
    PinchGloveEmulator,
    encode_frame,
)

from gadgetctl.input import InputManager
from gadgetctl.input.devicetypes import DigitalState
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.testing import hangs_up, resumes_within, wait_until
from gadgetctl.input.testing.commands import monitor_ndjson, samples_of
from gadgetctl.input.testing.configs import corpus_copy, rewritten
from gadgetctl.input.testing.fixtures import emulator_fixture, managers_fixture

pytestmark = pytest.mark.timeout(20)

EXAMPLE = Path(__file__).resolve().parents[1] / "example.jconf"
EXAMPLE_PORT = "<port>/tmp/gadgetctl-pinch</port>"

FAST = {
    "command_delay": 0.0,
    "echo_wait": 0.0,
    "read_timeout": 0.5,
    "sample_timeout": 0.05,
    "poll_interval": 0.005,
}
OPEN = (0,) * 10
BENT = math.pi / 2
FINGERS = ("Thumb", "Index", "Middle", "Ring", "Pinky")


emulator = emulator_fixture(PinchGloveEmulator, "idle", rate=100.0)
managers = managers_fixture("PinchGlove_drv", tune={"pinch_glove": FAST})


def glove_element(name: str, port: str) -> str:
    proxies = "".join(
        f'<digital_proxy name="{name} {hand} {finger}" version="1"><device>{name}</device>'
        f"<unit>{5 * h + 4 - f}</unit></digital_proxy>\n"  # unit k is bit k: pinky 0, thumb 4
        for h, hand in enumerate(("Left", "Right"))
        for f, finger in enumerate(FINGERS)
    )
    return (
        f'<pinch_glove name="{name}" version="1"><port>{port}</port><baud>9600</baud></pinch_glove>\n'
        f'<glove_proxy name="{name} Left Hand" version="1"><device>{name}</device><unit>0</unit></glove_proxy>\n'
        f'<glove_proxy name="{name} Right Hand" version="1"><device>{name}</device><unit>1</unit></glove_proxy>\n'
        + proxies
    )


def digital_of(groups: tuple[tuple[int, int], ...]) -> tuple[int, ...]:
    """Units from the protocol description: bit k of the left byte is unit k, of the right 5+k."""
    left = right = 0
    for lbits, rbits in groups:
        left |= lbits
        right |= rbits
    return tuple(left >> k & 1 for k in range(5)) + tuple(right >> k & 1 for k in range(5))


def digital_states(manager: InputManager, names: list[str]) -> list[DigitalState]:
    return [manager.proxy(name).data for name in names]


# -- units and values -------------------------------------------------------------------------


def test_initial_state_then_touch_frames_reach_proxies_and_aliases(
    tmp_path, emulator, managers
) -> None:
    emu = emulator("idle")
    manager = managers(rewritten(EXAMPLE, tmp_path, (EXAMPLE_PORT, f"<port>{emu.address}</port>")))
    assert not manager.pending()
    device = manager.device("PinchGlove")
    assert emu.commands == [b"CL", b"CR", b"CP", b"CT", b"T1"]  # hardware queries, timestamps on
    assert device.info == DEFAULT_INFO

    # Before any touch the glove reports open hands (the box sends nothing until then).
    manager.update()
    assert device.store.total(DeviceKind.DIGITAL) == 1
    lefts = [f"PinchLeft{f}" for f in FINGERS]
    rights = [f"PinchRight{f}" for f in FINGERS]
    assert digital_states(manager, lefts + rights) == [DigitalState.OFF] * 10
    for alias in ("VJLeftGlove", "VJRightGlove"):
        proxy = manager.proxy(alias)
        assert not proxy.stupefied and proxy.data.shape == (6, 4) and not proxy.data.any()

    def touch(groups: tuple[tuple[int, int], ...]) -> None:
        before = device.store.total(DeviceKind.GLOVE)  # stored last, after the digital sample
        emu.send_raw(encode_frame(groups, 5))
        assert wait_until(lambda: device.store.total(DeviceKind.GLOVE) > before)
        manager.update()

    touch(((L_THUMB, R_THUMB),))  # both thumbs touch each other
    on, off = DigitalState.TOGGLE_ON, DigitalState.OFF
    assert digital_states(manager, lefts) == [on, off, off, off, off]
    assert digital_states(manager, rights) == [on, off, off, off, off]  # right thumb is unit 9
    for alias in ("VJLeftGlove", "VJRightGlove"):
        angles = manager.proxy(alias).data
        np.testing.assert_array_equal(angles[0], [BENT] * 4)
        assert not angles[1:].any()  # other fingers open, wrist row untouched
    manager.update()
    assert manager.proxy("PinchLeftThumb").data == DigitalState.ON

    # Two contact groups in one frame are ORed: left thumb+pinky, right ring+pinky.
    touch(((L_THUMB | L_PINKY, 0), (0, R_RING | R_PINKY)))
    assert digital_states(manager, lefts) == [DigitalState.ON, off, off, off, on]
    assert digital_states(manager, rights) == [DigitalState.TOGGLE_OFF, off, off, on, on]
    right = manager.proxy("VJRightGlove").data
    assert [bool(row.any()) for row in right] == [False, False, False, True, True, False]
    assert device.store.frame(DeviceKind.DIGITAL).newest.values == (1, 0, 0, 0, 1, 1, 1, 0, 0, 0)

    touch(())  # hands open again
    assert all(
        s in (DigitalState.OFF, DigitalState.TOGGLE_OFF)
        for s in digital_states(manager, lefts + rights)
    )
    assert not manager.proxy("VJLeftGlove").data.any()


def test_touch_stream_arrives_in_order(tmp_path, emulator, managers) -> None:
    emu = emulator("touches", rate=200.0)
    manager = managers(glove_element("Glove", emu.address))
    device = manager.device("Glove")
    received: list[tuple[int, ...]] = []

    def frame() -> None:
        manager.update()
        received.extend(s.values for s in device.store.frame(DeviceKind.DIGITAL))

    assert wait_until(lambda: len(received) > 15, step=frame)
    assert received[0] == OPEN  # the start-up state
    expected = [digital_of(groups) for groups, _ in emu.sent[: len(received) - 1]]
    assert received[1:] == expected
    # glove unit 1 bends exactly the right-hand fingers of the newest frame
    angles = device.store.latest(DeviceKind.GLOVE).values
    assert angles.shape == (2, 6, 4)
    digital = device.store.latest(DeviceKind.DIGITAL).values
    for unit in range(10):  # unit k is bit k (pinky 0 .. thumb 4); glove rows start at the thumb
        assert (angles[unit // 5, 4 - unit % 5] == (BENT if digital[unit] else 0.0)).all()


def test_garbage_is_skipped_without_a_fault(tmp_path, emulator, managers) -> None:
    emu = emulator("garbage", rate=200.0)
    manager = managers(glove_element("Glove", emu.address))
    device = manager.device("Glove")
    received: list[tuple[int, ...]] = []

    def frame() -> None:
        manager.update()
        received.extend(s.values for s in device.store.frame(DeviceKind.DIGITAL))

    assert wait_until(lambda: len(received) > 15, step=frame)
    assert received[1:] == [digital_of(groups) for groups, _ in emu.sent[: len(received) - 1]]
    assert device.bad_frames > 0 and device.skipped_bytes > 0
    assert device.faults == 0 and manager.status("Glove").state == "running"


# -- faults and restarts ----------------------------------------------------------------------


def test_lost_line_faults_then_resumes_within_two_seconds(tmp_path, emulator, managers) -> None:
    link_a, link_b = tmp_path / "glove-a", tmp_path / "glove-b"
    emu_a = emulator("touches", link=link_a)
    emu_b = emulator("touches", link=link_b)
    body = glove_element("Glove A", str(link_a)) + glove_element("Glove B", str(link_b))
    manager = managers(body)  # the default restart policy
    glove_a, glove_b = manager.device("Glove A"), manager.device("Glove B")
    received_b: list[tuple[int, ...]] = []

    def frame() -> None:
        manager.update()
        received_b.extend(s.values for s in glove_b.store.frame(DeviceKind.DIGITAL))

    assert wait_until(lambda: glove_a.frames >= 3, step=frame)
    emu_a.stop()  # the box goes away: its pty and symlink vanish
    assert wait_until(lambda: manager.status("Glove A").state == "faulted", timeout=2, step=frame)
    status = manager.status("Glove A")
    assert status.reason and "serial line lost" in status.reason and status.code == "DRV042"
    assert status.stats.faults == 1
    assert manager.proxy("Glove A Left Thumb").stupefied is False  # proxies keep the last state

    wait_until(lambda: False, timeout=0.6, step=frame)  # restarts keep failing meanwhile
    assert manager.status("Glove A").state in ("faulted", "reconnecting")
    # the box is back, on a new pty behind the same link
    resumes_within(
        manager,
        "Glove A",
        lambda: emulator("touches", link=link_a),
        lambda: glove_a.frames,
        step=frame,
    )
    assert glove_a.restarts >= 1

    # the other glove went on and lost nothing
    assert glove_b.faults == 0 and glove_b.restarts == 0
    assert received_b[0] == OPEN
    assert received_b[1:] == [digital_of(groups) for groups, _ in emu_b.sent[: len(received_b) - 1]]


def test_disconnect_scenario_faults_the_device(tmp_path, emulator, managers) -> None:
    emu = emulator("disconnect", disconnect_after=3, link=tmp_path / "glove")
    manager = managers(glove_element("Glove", str(tmp_path / "glove")))
    hangs_up(manager, "Glove", emu, timeout=3, fault_timeout=3.0)
    assert manager.device("Glove").frames == 3


def test_stop_and_start_again(tmp_path, emulator, managers) -> None:
    emu = emulator("idle")
    manager = managers(glove_element("Glove", emu.address))
    device = manager.device("Glove")
    # The manager's sampling thread must end first: it calls sample() on its own, and
    # stopping the device under it made it fault and close the glove the test reopened.
    manager.shutdown()
    assert device.glove is None
    device.stop_sampling()  # twice is fine
    device.start_sampling()  # the port can be opened again
    try:
        assert emu.commands[-1] == b"T1" and emu.commands.count(b"CL") == 1  # info asked once
        emu.send_raw(encode_frame(((L_INDEX, R_INDEX),), 9))
        assert wait_until(lambda: device.frames == 1, step=device.sample)
        assert device.store.total(DeviceKind.DIGITAL) == 3  # open hands twice, then the touch
    finally:
        device.stop_sampling()


# -- configuration ----------------------------------------------------------------------------


def test_configuration_errors_leave_the_element_pending(tmp_path, managers) -> None:
    body = (
        '<pinch_glove name="No Port" version="1"><port></port></pinch_glove>\n'
        '<pinch_glove name="No Box" version="1"><port>/nonexistent/tty</port></pinch_glove>\n'
    )
    manager = managers(body)
    pending = {p.name: p for p in manager.pending()}
    assert pending["No Port"].message.startswith("port is empty")
    assert pending["No Port"].code == "DRV032"
    assert (
        "failed to start" in pending["No Box"].message
        and "/nonexistent/tty" in pending["No Box"].message
    )


# -- the VR Juggler configuration -------------------------------------------------------------


def test_corpus_pinch_mixin_delivers_through_its_proxies(tmp_path, emulator, managers) -> None:
    """pinch.mixin.jconf with only its port changed. Its right-hand digital proxies are numbered
    6-10, one more than the driver's units 5-9 (reference 3.4; Glove.cpp maps 5*hand+finger):
    the driver warns, PinchRightPinky (unit 10) is stupefied. Its names also take unit 0 for
    the thumb, where the glove box's bit 0 is the pinky (Vrui and VESS agree; VR Juggler's
    PinchGloveStandalone only passes bit k on as unit k): on real hardware "PinchLeftThumb"
    follows the left pinky and "PinchRightThumb" (unit 6) the right ring finger."""
    emu = emulator("idle")
    manager = managers(
        corpus_copy(
            "pinch.mixin.jconf",
            tmp_path,
            ("<port>/dev/ttyd1</port>", f"<port>{emu.address}</port>"),
        )
    )
    pending = {p.name for p in manager.pending()}
    assert pending == {"VJGlove", "VJGesture"}  # aliases whose proxy is left empty upstream
    warnings = [d for d in manager.diagnostics if d.code == "CFG034"]  # the rule validate applies
    assert len(warnings) == 1 and "'PinchRightPinky' reads digital unit 10" in warnings[0].message
    assert "units 0-9" in warnings[0].message
    assert warnings[0].line is not None and "6-10" in warnings[0].hint

    device = manager.device("FakespacePinchGlove")
    assert device.glove_position_proxies == ["GlovePos Proxy"]  # read, unlike the C++ wrapper
    before = device.store.total(DeviceKind.GLOVE)  # stored last, after the digital sample
    emu.send_raw(encode_frame(((L_PINKY | L_RING, R_PINKY | R_RING),), 1))
    assert wait_until(lambda: device.store.total(DeviceKind.GLOVE) > before)
    manager.update()

    assert manager.proxy("PinchLeftThumb").data == DigitalState.TOGGLE_ON  # unit 0: left pinky
    assert manager.proxy("PinchLeftIndex").data == DigitalState.TOGGLE_ON  # unit 1: left ring
    assert manager.proxy("PinchLeftMiddle").data == DigitalState.OFF
    assert manager.proxy("PinchRightThumb").data == DigitalState.TOGGLE_ON  # unit 6: right ring
    assert manager.proxy("PinchRightIndex").data == DigitalState.OFF  # unit 7: right middle
    pinky = manager.proxy("PinchRightPinky")
    assert pinky.stupefied and "unit 10 is out of range" in pinky.reason
    glove = manager.proxy("GloveProxy")  # unit 0, the left hand
    assert not glove.stupefied
    np.testing.assert_array_equal(glove.data[3:5], np.full((2, 4), BENT))  # ring and pinky rows
    assert not glove.data[:3].any() and not glove.data[5:].any()
    # the glove's position comes from its glove_position proxy (the simulated tracker)
    np.testing.assert_allclose(glove.position, manager.proxy("GlovePos Proxy").matrix)
    assert not np.allclose(glove.position, np.eye(4))


def test_gadgetctl_monitor_reads_the_corpus_configuration(tmp_path, emulator) -> None:
    emu = emulator("touches", rate=50.0)
    config = corpus_copy(
        "pinch.mixin.jconf",
        tmp_path,
        ("<port>/dev/ttyd1</port>", f"<port>{emu.address}</port>"),
    )
    done, records = monitor_ndjson(config, duration=1, timeout=30)
    samples = samples_of(records, "FakespacePinchGlove")
    assert {r["kind"] for r in samples} == {"digital", "glove"}, (
        done.stdout[-2000:] + done.stderr[-2000:]
    )
    assert {r["unit"] for r in samples if r["kind"] == "digital"} == set(range(10))
    assert {r["unit"] for r in samples if r["kind"] == "glove"} == {0, 1}
    assert emu.commands[-1] == b"T1"
