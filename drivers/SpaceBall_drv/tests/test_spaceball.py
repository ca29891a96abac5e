"""The SpaceMouse / SpaceBall driver against its emulator over a real pty pair, standalone and in
an input manager."""

from __future__ import annotations

from pathlib import Path

import pytest
from SpaceBall_drv.emulator import ESCAPE_AXES, MODELS, SpaceBallEmulator
from SpaceBall_drv.standalone import (
    MAX_RECORD,
    RecordSplitter,
    SpaceBall,
    decode_spaceball,
    decode_spacemouse,
)

from gadgetctl.input.devicetypes import DigitalState
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.testing import faults_then_resumes, frame_recorder, wait_until
from gadgetctl.input.testing.fixtures import emulator_fixture, managers_fixture

pytestmark = pytest.mark.timeout(30)

EXAMPLE = Path(__file__).resolve().parents[1] / "example.jconf"
FAST = {
    "reset_wait": 3.0,
    "sample_timeout": 0.02,
    "poll_interval": 0.005,
}  # reset_wait: a hang guard


def puck(name: str, port: str, model: str = "SpaceMouse") -> str:
    proxies = "".join(
        f'<digital_proxy name="{name} B{u + 1}" version="1"><device>{name}</device><unit>{u}</unit></digital_proxy>\n'
        for u in range(12)
    ) + "".join(
        f'<analog_proxy name="{name} A{u}" version="1"><device>{name}</device><unit>{u}</unit></analog_proxy>\n'
        for u in range(6)
    )
    return (
        f'<puck_device name="{name}" version="1"><device>{model}</device><port>{port}</port>'
        f"<baud>9600</baud></puck_device>\n" + proxies
    )


emulator = emulator_fixture(SpaceBallEmulator, rate=200.0)
managers = managers_fixture("SpaceBall_drv", tune={"puck_device": FAST})


# -- the wire format, from the protocol description (not from the emulator) ------------------


def test_spacemouse_records_decode_as_the_protocol_says() -> None:
    # axis value + 32768, four nibbles each, most significant first; 0x8000 is 0
    # nibble 8 -> 0x48 'H' (one bit set), 0 -> 0x30 '0', 5 -> 0x35 '5', 0xC -> 0x3C '<',
    # 7 -> 0x47 'G' (three bits set), 0xF -> 0x3F '?'
    record = b"d" + b"H000" + b"H005" + b"G???" + b"H<00" + b"0000" + b"????"
    got = decode_spacemouse(record)
    assert got.axes == (0, 5, -1, 0x0C00, -32768, 32767)
    # buttons: low nibble is buttons 1-4; 0x1 -> 'A' (0x41), 0x8 -> 'H', 0x0 -> '0'
    assert decode_spacemouse(b"kA0H").buttons == (1,) + (0,) * 10 + (1,)
    assert decode_spacemouse(b"k1") is None  # too short
    assert decode_spacemouse(b"kA0\x48\x00"[:3] + b"\x31") is None  # 0x31: 1 is sent as 'A'


def test_spaceball_records_decode_as_the_protocol_says() -> None:
    # 'D', two timer bytes, six big-endian int16; z and roll come negated
    words = (1, -2, 3, 300, -400, 500)
    body = b"\x00\x07" + b"".join(w.to_bytes(2, "big", signed=True) for w in words)
    assert decode_spaceball(b"D" + body).axes == (1, -2, -3, 300, -400, -500)
    # '.', first byte 01 L b12 b11 b10 b9 b8, second byte b7 1 b6..b1
    got = decode_spaceball(b"." + bytes([0b0100_0001, 0b1100_0001]))
    assert got.buttons == (1, 0, 0, 0, 0, 0, 1, 1, 0, 0, 0, 0) and got.left_handed is False
    assert decode_spaceball(b"." + bytes([0x60, 0x40])).left_handed is True
    assert decode_spaceball(b"." + bytes([0x00, 0x40])) is None  # fixed bits wrong
    # escapes: ^M is CR, ^Q XON, ^S XOFF, ^^ a caret
    escaped = b"D^M^Q" + b"\x00^S" + b"\x00^^" + b"\x00" * 8
    assert decode_spaceball(escaped).axes[:2] == (0x0013, 0x005E)
    assert decode_spaceball(b"D^x" + b"\x00" * 13) is None
    # the 2003B: K, 010 pick b8 b7 b6 b5, 0100 b4..b1; pick is button 9
    got = decode_spaceball(b"K" + bytes([0x51, 0x48]), "SpaceBall 2003B")
    assert got.buttons == (0, 0, 0, 1, 1, 0, 0, 0, 1, 0, 0, 0)


def test_the_2003b_escapes_like_the_4000() -> None:
    # VRPN and the C++ unescape for every model: a 2003B's D record holding CR, XON, XOFF or
    # a caret arrives escaped, and so does a K record whose first byte is 0x5E ('^')
    words = (0x0D00, 0x0011, 0x1300, 0x5E5E, -0x0D0D, 0)
    escaped = b"D^M^Q" + b"".join(
        {0x0D: b"^M", 0x11: b"^Q", 0x13: b"^S", 0x5E: b"^^"}.get(c, bytes([c]))
        for c in b"".join(w.to_bytes(2, "big", signed=True) for w in words)
    )
    got = decode_spaceball(escaped, "SpaceBall 2003B")
    assert got is not None and got.axes == (0x0D00, 0x0011, -0x1300, 0x5E5E, -0x0D0D, 0)
    buttons = decode_spaceball(b"K^^" + bytes([0x40]), "SpaceBall 2003B")  # 0x5E: b5, b6, b7, b8
    assert buttons is not None and buttons.buttons == (0, 0, 0, 0, 0, 1, 1, 1, 1, 0, 0, 0)


def test_overlong_runs_and_junk_are_counted_and_skipped_whole() -> None:
    splitter = RecordSplitter("SpaceMouse")
    good = b"kA00\r"
    got = splitter.feed(b"d" * (3 * MAX_RECORD) + b"d000" + b"\r" + good)
    got += splitter.feed(b"xx junk\r" + b"\xff" * 10 + b"\r" + good)
    assert [s.buttons[0] for s in got] == [1, 1]
    assert splitter.records == 2 and splitter.bad_records == 3
    assert splitter.skipped_bytes == 3 * MAX_RECORD + 5 + 8 + 11
    # bounded: a run without an end never grows a buffer past the longest record
    splitter.feed(b"d" * 100_000)
    assert len(splitter._partial) <= MAX_RECORD


# -- standalone over the pty ------------------------------------------------------------------


@pytest.mark.parametrize("model", MODELS)
def test_every_dialect_starts_and_decodes_what_the_puck_sends(emulator, model) -> None:
    emu = emulator("garbage" if model == "SpaceBall 4000 FLX" else "motion", model=model)
    with SpaceBall(emu.address, model, **FAST) as device:
        got = []
        assert wait_until(lambda: len(got) >= 20, step=lambda: got.extend(device.poll()))
    assert emu.commands[0] in (b"vQ", b"@")
    assert any(c[:1] in (b"m", b"c", b"M") for c in emu.commands)
    assert device.version
    decoded = [("axes", s.axes) if s.axes is not None else ("buttons", s.buttons) for s in got]
    assert decoded == emu.sent[: len(decoded)]
    if model == "SpaceBall 4000 FLX":
        assert device.decoder.bad_records > 0
    if model.startswith("SpaceBall"):
        assert decoded[0] == ("axes", ESCAPE_AXES)  # every escaped byte came through


# -- in the input manager ---------------------------------------------------------------------


def test_example_units_and_button_numbering(emulator, managers) -> None:
    emu = emulator("buttons", rate=100.0)
    manager = managers(puck("Puck", emu.address))
    assert not manager.pending()
    frame, _axes, buttons = frame_recorder(manager, "Puck", DeviceKind.ANALOG, DeviceKind.DIGITAL)
    assert wait_until(lambda: len(buttons) > 6, step=frame)
    assert buttons[0] == (0,) * 12  # released until the puck reports
    assert buttons[1:] == [v for _k, v in emu.sent[: len(buttons) - 1]]
    # button N is digital unit N-1 and reads 0/1: button 1, release, button 2, release
    assert buttons[1:5] == [(1,) + (0,) * 11, (0,) * 12, (0, 1) + (0,) * 10, (0,) * 12]


def test_axes_are_raw_counts_normalised_by_the_dialect_range(emulator, managers) -> None:
    emu = emulator("motion", rate=100.0, model="SpaceBall 4000 FLX")
    manager = managers(puck("Ball", emu.address, "SpaceBall 4000 FLX"))
    frame, axes, _buttons = frame_recorder(manager, "Ball", DeviceKind.ANALOG, DeviceKind.DIGITAL)
    assert wait_until(lambda: len(axes) > 8, step=frame)
    expected = [v for k, v in emu.sent if k == "axes"][: len(axes) - 1]
    assert axes[1:] == [tuple(float(a) for a in v) for v in expected]
    device = manager.device("Ball")
    assert (device.analog_min, device.analog_max) == (-2000.0, 2000.0)
    latest = device.store.latest(DeviceKind.ANALOG).values
    proxy = manager.proxy("Ball A0").data
    assert proxy == pytest.approx((min(max(latest[0], -2000), 2000) + 2000) / 4000)


@pytest.mark.parametrize(
    ("model", "span"),
    [("SpaceMouse", 500), ("SpaceBall 4000 FLX", 2000), ("SpaceBall 2003B", 2000)],
)
def test_a_centred_axis_reads_half_whatever_min_and_max_say(emulator, managers, model, span):
    # VRJConfig writes the definition's defaults, min 0 and max 255, into the files it saves;
    # the C++ uses the model's range whatever they say, and so does this driver
    emu = emulator("idle", model=model)
    written = "<min>0.0</min><max>255.0</max></puck_device>"
    manager = managers(puck("Puck", emu.address, model).replace("</puck_device>", written))
    device = manager.device("Puck")
    assert (device.analog_min, device.analog_max) == (-span, span)
    assert wait_until(lambda: emu.streaming.is_set())
    manager.update()
    assert [manager.proxy(f"Puck A{u}").data for u in range(6)] == [0.5] * 6  # at rest
    # the scanner counts a record before the wrapper stores its sample: wait for the store
    before = device.store.total(DeviceKind.ANALOG)
    push = {"SpaceMouse": b"d" + b"H000" + b"HA<D" + b"H000" * 4 + b"\r"}.get(model)
    if push is None:  # a SpaceBall: timer, then tx = span / 2 and ty = -span
        words = (span // 2, -span, 0, 0, 0, 0)
        push = b"D\x00\x00" + b"".join(w.to_bytes(2, "big", signed=True) for w in words) + b"\r"
        expected = (0.75, 0.0)
    else:  # tx 0x8000 - 32768 = 0, ty 0x81C4 - 32768 = 452
        expected = (0.5, (452 + 500) / 1000)
    emu.send_raw(push)
    assert wait_until(lambda: device.store.total(DeviceKind.ANALOG) > before)
    manager.update()
    got = (manager.proxy("Puck A0").data, manager.proxy("Puck A1").data)
    assert got == pytest.approx(expected)


def test_garbage_is_resynchronised_and_counted_without_a_fault(emulator, managers) -> None:
    emu = emulator("garbage")
    manager = managers(puck("Puck", emu.address))
    frame, axes, buttons = frame_recorder(manager, "Puck", DeviceKind.ANALOG, DeviceKind.DIGITAL)
    assert wait_until(lambda: len(axes) + len(buttons) > 30, step=frame)
    device = manager.device("Puck")
    sent_axes = [tuple(float(a) for a in v) for k, v in emu.sent if k == "axes"]
    sent_buttons = [v for k, v in emu.sent if k == "buttons"]
    assert axes[1:] == sent_axes[: len(axes) - 1]
    assert buttons[1:] == sent_buttons[: len(buttons) - 1]
    assert device.bad_records > 5 and device.skipped_bytes > 200
    assert device.faults == 0 and manager.status("Puck").state == "running"


def test_lost_line_faults_then_samples_within_two_seconds(tmp_path, emulator, managers) -> None:
    link = tmp_path / "puck"
    emu = emulator("disconnect", rate=100.0, disconnect_after=5, link=link)
    manager = managers(puck("Puck", str(link)))
    frame, axes, _buttons = frame_recorder(manager, "Puck", DeviceKind.ANALOG, DeviceKind.DIGITAL)
    # the puck is back behind the same link
    faults_then_resumes(
        manager,
        "Puck",
        emu,
        lambda: emulator("motion", rate=100.0, link=link),
        lambda: len(axes),
        step=frame,
    )


def test_buttons_reach_digital_proxies_as_toggles(emulator, managers) -> None:
    emu = emulator("idle")
    manager = managers(puck("Puck", emu.address))
    device = manager.device("Puck")
    assert wait_until(lambda: emu.streaming.is_set())
    before = device.store.total(DeviceKind.DIGITAL)  # stored, not only counted by the scanner
    emu.send_raw(b"kA0H\r")  # buttons 1 and 12
    assert wait_until(lambda: device.store.total(DeviceKind.DIGITAL) > before)
    manager.update()
    states = [manager.proxy(f"Puck B{n}").data for n in range(1, 13)]
    assert states[0] == DigitalState.TOGGLE_ON and states[11] == DigitalState.TOGGLE_ON
    assert set(states[1:11]) == {DigitalState.OFF}


def test_a_baud_other_than_9600_leaves_the_element_pending(managers) -> None:
    manager = managers(puck("Puck", "/dev/null").replace("<baud>9600", "<baud>19200"))
    assert "9600" in manager.status("Puck").reason
