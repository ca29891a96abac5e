"""The 5DT Data Glove Ultra Wireless driver against its emulator over a real pty pair,
standalone and in an input manager."""

from __future__ import annotations

import pytest
from DataGloveUltraWireless_drv.emulator import UltraGloveEmulator, encode_record
from DataGloveUltraWireless_drv.standalone import (
    RECORD_SIZE,
    AutoRange,
    RecordScanner,
    UltraGlove,
    decode_record,
    gesture,
)

from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.testing import faults_then_resumes, frame_recorder, wait_until
from gadgetctl.input.testing.fixtures import emulator_fixture, managers_fixture

pytestmark = pytest.mark.timeout(30)

FAST = {"sample_timeout": 0.02, "poll_interval": 0.005}


def gloves(name: str, port: str, extra: str = "") -> str:
    return (
        f'<data_glove_ultra_wireless name="{name}" version="2"><port>{port}</port>{extra}'
        "</data_glove_ultra_wireless>\n"
        f'<command_proxy name="{name} A" version="1"><device>{name}</device><unit>0</unit></command_proxy>\n'
        f'<command_proxy name="{name} B" version="1"><device>{name}</device><unit>1</unit></command_proxy>\n'
        f'<analog_proxy name="{name} B0" version="1"><device>{name}</device><unit>14</unit></analog_proxy>\n'
    )


def auto_ranged(sent: list[tuple[int, tuple[int, ...]]]) -> list[tuple[int, tuple[float, ...]]]:
    """Each record's readings placed in their sensor's range so far, per glove, written out
    from the description (not with the driver's AutoRange)."""
    low: dict[tuple[int, int], int] = {}
    high: dict[tuple[int, int], int] = {}
    out = []
    for port, raw in sent:
        scaled = []
        for i, v in enumerate(raw):
            lo = low[port, i] = min(low.get((port, i), v), v)
            hi = high[port, i] = max(high.get((port, i), v), v)
            scaled.append((v - lo) / (hi - lo) if hi > lo else 0.0)
        out.append((port, tuple(scaled)))
    return out


emulator = emulator_fixture(UltraGloveEmulator, rate=200.0)
managers = managers_fixture("DataGloveUltraWireless_drv", tune={"data_glove_ultra_wireless": FAST})


# -- the wire format --------------------------------------------------------------------------


def test_records_decode_as_the_protocol_says() -> None:
    # three nibbles per reading, most significant first: 0xABC, 0x123, then zeros
    body = bytes([0xAB, 0xC1, 0x23]) + bytes(18)
    record = bytes([0x3C, 0x42, 0x00]) + body + bytes(4) + b">"
    got = decode_record(record)
    assert got.port == 0 and got.raw[:3] == (0xABC, 0x123, 0) and len(got.raw) == 14
    assert decode_record(bytes([0x3C, 0x43]) + record[2:]).port == 0  # id 3 is port A too
    assert decode_record(bytes([0x3C, 0x45]) + record[2:]).port == 1
    assert decode_record(record[:-1] + b"!") is None  # no end marker
    ranged = AutoRange()
    assert ranged.scale(got) == (0.0,) * 14  # an empty range reads 0
    lower = decode_record(bytes([0x3C, 0x42, 0x00, 0x00, 0x01]) + bytes(19) + bytes(4) + b">")
    assert ranged.scale(lower)[1] == 0.0 and ranged.scale(got)[1] == 1.0
    # gesture bits: index, middle, ring, little bent (their near and far sensors)
    fist = (1.0,) * 14
    assert gesture(fist) == 15 and gesture((0.0,) * 14) == 0
    point = tuple(0.0 if i in (3, 4) else 1.0 for i in range(14))
    assert gesture(point) == 0b1110
    assert gesture((0.5,) * 14) == -1


def test_junk_runs_are_counted_once_and_the_buffer_stays_bounded() -> None:
    good = encode_record(1, tuple(range(14)))
    scanner = RecordScanner()
    junk = b"\x00<<" + b"<" + bytes(27) + b"!"
    got = scanner.feed(junk + good[:10]) + scanner.feed(good[10:] + good)
    assert [r.raw for r in got] == [tuple(range(14))] * 2
    assert scanner.bad_records == 1 and scanner.skipped_bytes == len(junk)
    scanner.feed(b"<" * 100_000)
    assert len(scanner.buffer) < RECORD_SIZE and scanner.bad_records == 2


# -- standalone over the pty ------------------------------------------------------------------


def test_standalone_reads_both_ports_in_order(emulator) -> None:
    emu = emulator("motion")
    with UltraGlove(emu.address, **FAST) as receiver:
        got = []
        assert wait_until(lambda: len(got) >= 30, step=lambda: got.extend(receiver.poll()))
    decoded = [(r.port, r.raw) for r in got]
    assert decoded in (emu.sent[: len(got)], [emu.probe, *emu.sent][: len(got)])
    assert {r.port for r in got} == {0, 1}


# -- in the input manager ---------------------------------------------------------------------


def test_units_of_both_gloves_and_their_gestures(emulator, managers) -> None:
    emu = emulator("buttons", rate=100.0)
    manager = managers(gloves("Gloves", emu.address))
    assert not manager.pending()
    frame, analog, commands = frame_recorder(
        manager, "Gloves", DeviceKind.ANALOG, DeviceKind.COMMAND
    )
    assert wait_until(lambda: len(analog) > 16, step=frame)

    def replayed(sent: list[tuple[int, tuple[int, ...]]]) -> list[tuple[float, ...]]:
        a, b, out = [0.0] * 14, [0.0] * 14, []
        for port, scaled in auto_ranged(sent[: len(analog)]):
            (a if port == 0 else b)[:] = scaled
            out.append(tuple(a + b))  # glove A in 0..13, glove B in 14..27
        return out

    # the record sent before the driver came is discarded, unless it was on its way
    candidates = [replayed(emu.sent), replayed([emu.probe, *emu.sent])]
    assert any(analog == [pytest.approx(w) for w in want] for want in candidates), analog[:3]
    seen = {value for c in commands for value in c}
    assert {0, 15} <= seen  # open hands and fists on both gloves
    manager.update()
    assert manager.proxy("Gloves A").data in (0, 15, -1)


def test_a_disabled_port_is_not_read(emulator, managers) -> None:
    emu = emulator("motion")
    manager = managers(gloves("Gloves", emu.address, "<port_a_enabled>false</port_a_enabled>"))
    frame, analog, commands = frame_recorder(
        manager, "Gloves", DeviceKind.ANALOG, DeviceKind.COMMAND
    )
    assert wait_until(lambda: len(analog) > 10, step=frame)
    device = manager.device("Gloves")
    assert device.ignored > 0
    assert all(not any(sample[:14]) for sample in analog)  # glove A stays at 0
    assert all(c[0] == -1 for c in commands)


def test_garbage_is_resynchronised_and_counted_without_a_fault(emulator, managers) -> None:
    emu = emulator("garbage")
    manager = managers(gloves("Gloves", emu.address))
    frame, analog, _commands = frame_recorder(
        manager, "Gloves", DeviceKind.ANALOG, DeviceKind.COMMAND
    )
    assert wait_until(lambda: len(analog) > 30, step=frame)
    device = manager.device("Gloves")
    assert device.records >= len(analog)
    last = analog[-1]
    matches = []
    for sent in (emu.sent, [emu.probe, *emu.sent]):  # the probe, if it was on its way
        port, scaled = auto_ranged(sent[: len(analog)])[-1]
        matches.append(last[14 * port : 14 * port + 14] == pytest.approx(scaled))
    assert any(matches)
    assert device.bad_records >= 20 and device.skipped_bytes > 100
    assert device.faults == 0 and manager.status("Gloves").state == "running"


def test_lost_line_faults_then_samples_within_two_seconds(tmp_path, emulator, managers) -> None:
    link = tmp_path / "gloves"
    emu = emulator("disconnect", rate=100.0, link=link)
    manager = managers(gloves("Gloves", str(link)))
    frame, analog, _commands = frame_recorder(
        manager, "Gloves", DeviceKind.ANALOG, DeviceKind.COMMAND
    )
    faults_then_resumes(
        manager,
        "Gloves",
        emu,
        lambda: emulator("motion", rate=100.0, link=link),
        lambda: len(analog),
        step=frame,
    )


def test_no_glove_enabled_leaves_the_element_pending(managers) -> None:
    extra = "<port_a_enabled>false</port_a_enabled><port_b_enabled>false</port_b_enabled>"
    manager = managers(gloves("Gloves", "/dev/null", extra))
    assert "no glove" in manager.status("Gloves").reason
