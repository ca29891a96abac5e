"""The Wanda protocol half and device against the emulator over a real pty pair."""

from __future__ import annotations

import time
from pathlib import Path

import pytest
from Wanda_drv.emulator import GARBAGE_CHUNKS, WandaEmulator, encode_packet
from Wanda_drv.standalone import PacketScanner, Wanda, WandaDisconnected, decode_packet

from gadgetctl.emulation.testing import FixtureLine
from gadgetctl.input.devicetypes import DigitalState
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.testing import (
    frames_until,
    gather,
    reads_past_garbage,
    serial_line_lost_then_resumes,
    wait_until,
)
from gadgetctl.input.testing.commands import monitor_ndjson, run_gadgetctl, samples_of
from gadgetctl.input.testing.configs import corpus_copy
from gadgetctl.input.testing.fixtures import emulator_fixture, managers_fixture

pytestmark = pytest.mark.timeout(30)

FAST = {"reset_time": 0.0, "hello_timeout": 2.0}


emulator = emulator_fixture(WandaEmulator, rate=100.0)
managers = managers_fixture("Wanda_drv", tune={"wanda": FAST})


def test_packet_bits_sign_and_button_numbering() -> None:
    # byte 0: sync, button 0 (bit 5), Y bits 7..6 = 11, X bits 7..6 = 00; X 5 sent, Y -3
    packet = bytes((0x40 | 0x20 | 0x0C, 0x05, 0x3D))
    decoded = decode_packet(packet)
    assert decoded is not None
    assert decoded.buttons == (1, 0, 0) and decoded.axes == (-5, -3)  # X is negated
    middle = decode_packet(bytes((0x40 | 0x10, 0, 0, 0x20)))
    assert middle is not None and middle.buttons == (0, 1, 1)  # 0/1, never raw bits
    clamped = decode_packet(bytes((0x40 | 0x01, 0x00, 0x3F)))  # X raw 64 -> -64 -> -34
    assert clamped is not None and clamped.axes == (-34, 34 if 0x3F > 34 else 0x3F)
    assert decode_packet(bytes((0x40, 0x41, 0x00))) is None  # a sync bit inside
    for buttons, axes in (((1, 1, 0), (34, -34)), ((0, 0, 1), (-7, 12))):
        assert decode_packet(encode_packet(buttons, axes)) is not None
        assert decode_packet(encode_packet(buttons, axes)).axes == axes  # type: ignore[union-attr]


def test_scanner_resynchronises_by_whole_runs() -> None:
    a, b = encode_packet((1, 0, 0), (3, 4)), encode_packet((0, 1, 0), (-5, 6))
    scanner = PacketScanner()
    out = scanner.feed(b"".join(GARBAGE_CHUNKS) + a + b"\x93" + bytes(40) + b)
    out += scanner.feed(b"", quiet=True)  # b's 4th byte came: nothing held
    assert [p.buttons for p in out] == [(1, 0, 0), (0, 1, 0)]
    assert scanner.bad_records == 2 and scanner.records == 2
    assert scanner.skipped_bytes == sum(map(len, GARBAGE_CHUNKS)) + 41
    held = scanner.feed(a)
    assert held == [] and scanner.feed(b"", quiet=True)[0].axes == (3, 4)


def test_hello_and_motion_over_a_pty(emulator) -> None:
    emu = emulator("motion")
    with Wanda(emu.address, reset_time=0.0) as wanda:
        assert wanda.degraded  # the pty stays 8N1 (and has no RTS): tolerated
        got = gather(wanda.read, 30)
    for packet, (buttons, axes) in zip(got, emu.sent[: len(got)], strict=True):
        assert packet.buttons == buttons and packet.axes == axes
    assert {abs(p.axes[0]) for p in got} & {34}  # the joystick reaches its limit


def test_lost_line_raises_disconnected(emulator) -> None:
    emu = emulator("disconnect", disconnect_after=15)
    with Wanda(emu.address, reset_time=0.0) as wanda:
        got: list = []
        with pytest.raises(WandaDisconnected):
            wait_until(lambda: False, timeout=5, step=lambda: got.extend(wanda.read()))
    assert len(got) == 15 and emu.disconnected.is_set()


def element(port: str) -> str:
    return (
        f'<wanda name="W" version="1"><port>{port}</port></wanda>\n'
        + "".join(
            f'<digital_proxy name="B{u}" version="1"><device>W</device><unit>{u}</unit>'
            "</digital_proxy>\n"
            for u in range(3)
        )
        + '<analog_proxy name="X" version="1"><device>W</device><unit>0</unit></analog_proxy>\n'
    )


def test_buttons_and_joystick_reach_proxies(tmp_path, emulator, managers) -> None:
    emu = emulator("buttons")
    manager = managers(element(emu.address))
    assert not manager.pending()
    device = manager.device("W")
    seen: list[tuple] = []

    def frame() -> None:
        manager.update()
        seen.extend(s.values for s in device.store.frame(DeviceKind.DIGITAL))

    assert wait_until(
        lambda: {(1, 0, 0), (0, 1, 0), (0, 0, 1)} <= set(seen), timeout=10, step=frame
    ), set(seen)
    assert device.store.latest(DeviceKind.ANALOG).values == (0.0, 0.0)
    # the analog range is -34..34 whatever min/max say (definition defaults 0..255)
    assert manager.proxy("X").data == pytest.approx(0.5)
    assert all(isinstance(manager.proxy(f"B{u}").data, DigitalState) for u in range(3))


def test_garbage_is_counted_without_a_fault(tmp_path, emulator, managers) -> None:
    emu = emulator("garbage")
    manager = managers(element(emu.address))
    device = reads_past_garbage(manager, "W", 30, timeout=10)
    assert device.bad_records >= 20 and device.skipped_bytes > 0
    sent = list(emu.sent)
    assert device.store.latest(DeviceKind.ANALOG).values in {tuple(map(float, a)) for _b, a in sent}


def test_lost_line_faults_then_resumes_within_two_seconds(tmp_path, emulator, managers) -> None:
    link = tmp_path / "wanda"
    emu = emulator("disconnect", disconnect_after=20, link=link)
    manager = managers(element(str(link)))
    serial_line_lost_then_resumes(
        manager, "W", emu, lambda: emulator("motion", link=link), 20, reopened=True
    )


def test_a_wanda_at_rest_is_silent_and_stays_connected(emulator, managers) -> None:
    # a real Wanda sends nothing while the ball rests and no button changes (VRPN's
    # vrpn_Wanda.C); the driver used to call 2 s of that a lost line and reconnect
    emu = emulator("idle")
    manager = managers(element(emu.address))
    device = manager.device("W")
    assert wait_until(lambda: emu.reader, step=manager.update)
    resting_until = time.monotonic() + 3.0  # longer than the 2 s the driver used to allow
    while time.monotonic() < resting_until:
        manager.update()
        assert device.faults == 0 and manager.status("W").state == "running"
        time.sleep(0.02)
    assert emu.sent == [] and device.records == 0  # it really was silent
    emu.send_raw(encode_packet((0, 0, 1), (0, 0)))  # then a button is pressed
    assert wait_until(
        lambda: device.store.latest(DeviceKind.DIGITAL) is not None, step=manager.update
    )
    assert device.store.latest(DeviceKind.DIGITAL).values == (0, 0, 1)
    assert device.restarts == 0


def test_a_ball_let_go_without_a_centred_packet_reads_centred(emulator, managers) -> None:
    # VRPN found the Wanda may not send the packet that says the ball is centred again, and
    # centres its joystick after 0.2 s without a packet
    emu = emulator("idle")
    manager = managers(element(emu.address))
    device = manager.device("W")
    assert wait_until(lambda: emu.reader, step=manager.update)
    emu.send_raw(encode_packet((0, 0, 0), (20, -10)))
    seen: list[tuple] = []

    def frame() -> None:
        manager.update()
        seen.extend(s.values for s in device.store.frame(DeviceKind.ANALOG))

    assert wait_until(lambda: seen[-1:] == [(0.0, 0.0)], step=frame), seen
    assert seen == [(20.0, -10.0), (0.0, 0.0)]
    assert manager.proxy("X").data == pytest.approx(0.5)


def test_the_emulator_is_silent_at_rest_and_sends_changes_only() -> None:
    from Wanda_drv.emulator import REST, TURN, controls, sends

    steps = [controls("buttons", step) for step in range(40)]
    changes = [i for i in range(1, 40) if sends(steps[i], steps[i - 1])]
    assert changes == [5, 10, 15, 20, 25, 30, 35]  # press and release, nothing between
    assert not sends(controls("idle", 7), controls("idle", 6))
    resting = [controls("motion", s) for s in range(TURN, TURN + REST)]
    assert all(not sends(now, resting[0]) for now in resting)


def corpus_example(tmp_path: Path, port: str) -> Path:
    return corpus_copy(
        "example.wanda.jconf",
        tmp_path,
        ("<port>/dev/ttyS1</port>", f"<port>{port}</port>"),
    )


def test_corpus_example_delivers_through_its_aliases(tmp_path, emulator, managers) -> None:
    emu = emulator("buttons")
    manager = managers(corpus_example(tmp_path, emu.address))
    assert not manager.pending()
    pressed: set[str] = set()

    def frame() -> None:
        manager.update()
        for alias in ("VJButton0", "VJButton1", "VJButton2"):
            if manager.proxy(alias).data in (DigitalState.ON, DigitalState.TOGGLE_ON):
                pressed.add(alias)

    assert wait_until(lambda: len(pressed) == 3, timeout=10, step=frame), pressed
    assert manager.proxy("VJAnalog0").data == pytest.approx(0.5)  # centred: (0 + 34) / 68


def test_gadgetctl_monitor_reads_the_corpus_example(tmp_path, emulator) -> None:
    emu = emulator("motion")
    config = corpus_example(tmp_path, emu.address)
    done, records = monitor_ndjson(config, duration=3, timeout=40)
    samples = samples_of(records, "Wanda")
    assert {r["kind"] for r in samples} == {"digital", "analog"}, done.stderr[-2000:]
    for command in (["validate"], ["doctor"], ["config", "pending"]):
        out = run_gadgetctl(*command, str(config), timeout=30)
        text = out.stdout + out.stderr
        assert "DRV001" not in text and "PENDING" not in text and "stays pending" not in text, text
        if command == ["config", "pending"]:
            assert "0 pending" in text


def test_a_line_of_nothing_but_junk_shows_the_wanda_undecodable(managers) -> None:
    """Issue 23 item 4: bytes a 7-bit serial mouse never sends (bit 7 set) are junk; while
    nothing else comes the device is undecodable, not running, and says how much it skipped."""
    with FixtureLine() as line:
        manager = managers(f'<wanda name="W" version="1"><port>{line.address}</port></wanda>\n')
        line.feed(bytes(range(0x80, 0x100)))
        frames_until(manager, lambda: manager.status("W").state == "undecodable")
        assert manager.status("W").reason == "128 bytes of junk skipped (1 run), no record decoded"
