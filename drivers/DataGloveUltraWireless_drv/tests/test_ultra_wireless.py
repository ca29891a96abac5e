"""The 5DT Data Glove Ultra Wireless driver against its emulator over a real pty pair,
standalone and in an input manager."""

from __future__ import annotations

import pytest
from DataGloveUltraWireless_drv.emulator import UltraGloveEmulator, encode_record
from DataGloveUltraWireless_drv.standalone import (
    RECORD_SIZE,
    AutoRange,
    GloveRecord,
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


NO_RESET = "<auto_range_reset>false</auto_range_reset>"

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
    assert ranged.scale(got) == (None,) * 14  # an empty range reads as unknown
    lower = decode_record(bytes([0x3C, 0x42, 0x00, 0x00, 0x01]) + bytes(19) + bytes(4) + b">")
    assert ranged.scale(lower)[1] == 0.0 and ranged.scale(got)[1] == 1.0


def hand(index: float, middle: float, ring: float, little: float, far_offset: float = 0.0):
    """Fourteen scaled readings: each finger's near and far sensor at the value given (the far
    one moved by ``far_offset``), thumb and spreads half bent."""
    values = [0.5] * 14
    for near, value in zip((3, 6, 9, 12), (index, middle, ring, little), strict=True):
        values[near], values[near + 1] = value, value + far_offset
    return tuple(values)


@pytest.mark.parametrize(
    ("scaled", "number"),
    [
        (hand(0.0, 0.0, 0.0, 0.0), 15),  # flat hand: every finger open
        (hand(1.0, 1.0, 1.0, 1.0), 0),  # fist
        (hand(0.1, 0.9, 0.9, 0.9), 1),  # pointing: index open
        (hand(0.1, 0.1, 0.9, 0.9), 3),  # index and middle open
        (hand(0.9, 0.9, 0.9, 0.1), 8),  # little finger open
        (hand(0.2, 0.3, 0.9, 0.2), 11),
        (hand(0.1, 0.5, 0.1, 0.1), -1),  # middle between the thresholds
        ((0.0,) * 3 + (None, 0.9) + (0.0,) * 9, 14),  # one sensor undefined: the other decides
        ((0.0,) * 3 + (0.1, 0.9) + (0.0,) * 9, 14),  # one sensor closed: the finger is closed
        ((0.0,) * 3 + (0.1, 0.5) + (0.0,) * 9, 15),  # open beside undefined: open
        ((0.0,) * 3 + (None, None) + (0.0,) * 9, -1),  # both sensors unknown
    ],
)
def test_gesture_numbers_of_known_hands(scaled, number) -> None:
    # VR Juggler's computeGesture: a finger's bit is set while it is open (flat hand 15, fist
    # 0); getJointState: closed wins, else open wins, undefined only if both are
    assert gesture(scaled) == number


def test_thresholds_are_strict_and_configurable() -> None:
    assert gesture(hand(0.35, 0.35, 0.35, 0.35)) == -1  # not below the lower threshold
    assert gesture(hand(0.65, 0.65, 0.65, 0.65)) == -1  # not above the upper threshold
    assert gesture(hand(0.3, 0.3, 0.3, 0.7), lower=0.4, upper=0.6) == 7


def test_auto_range_reset_restarts_the_ends_at_flat_hands_and_fists() -> None:
    def record(value: int) -> GloveRecord:
        return GloveRecord(0, (value,) * 14)

    ranged = AutoRange(auto_reset=True)
    steps = []
    for value in (100, 3900, 600, 600, 3400, 3400, 1000, 700):
        scaled = ranged.scale(record(value))
        number = gesture(scaled)
        ranged.after_gesture(record(value), number)
        steps.append((round(scaled[3], 3) if scaled[3] is not None else None, number))
    assert steps == [
        (None, -1),  # an empty range: unknown
        (1.0, 0),  # a fist: 3900 stays the maximum
        (0.132, 15),  # flat: 600 becomes the minimum (100 is forgotten)
        (0.0, 15),
        (0.848, 0),  # a fist at 3400 becomes the maximum (3900 is forgotten)
        (1.0, 0),
        (0.143, 15),  # (1000 - 600) / (3400 - 600); now 1000 is the minimum
        (0.0, 15),  # 700 is below it: the minimum follows
    ]
    still = AutoRange(auto_reset=False)
    for value in (100, 3900, 600):
        scaled = still.scale(record(value))
        still.after_gesture(record(value), gesture(scaled))
    assert still.low[0][3] == 100 and still.high[0][3] == 3900


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


def test_units_of_both_gloves(emulator, managers) -> None:
    emu = emulator("buttons", rate=100.0)
    manager = managers(gloves("Gloves", emu.address, NO_RESET))
    assert not manager.pending()
    frame, analog, _commands = frame_recorder(
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


def test_flat_hands_read_15_and_fists_0(emulator, managers) -> None:
    # the buttons scenario: every sensor of a glove reads 400 then 3600 (its first records),
    # then 500 (flat hand) and 3500 (fist) in turn, three records of each per glove
    emu = emulator("buttons", rate=100.0)
    manager = managers(gloves("Gloves", emu.address))  # auto_range_reset is on by default
    frame, _analog, commands = frame_recorder(
        manager, "Gloves", DeviceKind.ANALOG, DeviceKind.COMMAND
    )
    assert wait_until(lambda: len(commands) > 20, step=frame)

    def expected(sent: list[tuple[int, tuple[int, ...]]]) -> list[tuple[int, int]]:
        gestures, seen, out = [-1, -1], [0, 0], []
        for port, raw in sent[: len(commands)]:
            # the first record of a glove leaves its ranges empty: no gesture yet
            gestures[port] = -1 if seen[port] == 0 else (15 if raw[0] <= 500 else 0)
            seen[port] += 1
            out.append(tuple(gestures))
        return out

    candidates = [expected(emu.sent), expected([emu.probe, *emu.sent])]
    assert [tuple(c) for c in commands] in candidates, commands[:8]
    assert {15, 0} <= {value for c in commands for value in c}


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
    manager = managers(gloves("Gloves", emu.address, NO_RESET))
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
