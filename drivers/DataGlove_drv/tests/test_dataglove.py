"""The 5DT DataGlove driver against its emulator over a real pty pair, standalone and in an
input manager."""

from __future__ import annotations

import math

import numpy as np
import pytest
from DataGlove_drv.emulator import LEFT, RIGHT, DataGloveEmulator, encode_packet
from DataGlove_drv.standalone import (
    NO_GESTURE,
    PACKET_SIZE,
    DataGlove,
    DataGloveNoAnswer,
    PacketScanner,
    decode_packet,
    gesture,
)

from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.testing import faults_then_resumes, frame_recorder, gather, wait_until
from gadgetctl.input.testing.fixtures import emulator_fixture, managers_fixture

pytestmark = pytest.mark.timeout(30)

FAST = {"sample_timeout": 0.02, "poll_interval": 0.005}
TUNE = {**FAST, "reply_timeout": 2.0}


def glove(name: str, port: str) -> str:
    proxies = "".join(
        f'<analog_proxy name="{name} A{u}" version="1"><device>{name}</device><unit>{u}</unit></analog_proxy>\n'
        for u in range(9)
    )
    return (
        f'<data_glove name="{name}" version="1"><port>{port}</port><baud>38400</baud></data_glove>\n'
        f'<glove_proxy name="{name} Hand" version="1"><device>{name}</device><unit>0</unit></glove_proxy>\n'
        + proxies
    )


def expected(data: tuple[int, ...], capability: int = 0) -> tuple[float, ...]:
    """Analog units 0..8 from the protocol description, written out independently."""
    flex = [b / 255 for b in data[:5]]
    index_open, middle_open, ring_open, pinky_open = (
        flex[1] < 0.5,
        flex[2] < 0.5,
        flex[3] < 0.5,
        flex[4] < 0.35,
    )
    table = {  # (index, middle, ring, pinky) open -> the C++ driver's gesture number
        (False, False, False, False): 0,
        (True, False, False, False): 1,
        (False, True, False, False): 2,
        (True, True, False, False): 3,
        (False, True, True, False): 4,
        (True, False, True, False): 5,
        (True, True, True, False): 7,
        (False, False, False, True): 8,
        (True, True, False, True): 9,
        (False, True, False, True): 10,
        (False, False, True, True): 12,
        (True, False, True, True): 13,
        (False, True, True, True): 14,
        (True, True, True, True): 15,
    }
    number = table.get((index_open, middle_open, ring_open, pinky_open), 16)
    return (*flex, data[5] * 180 / 255, data[6] * 180 / 255, float(number), float(capability))


emulator = emulator_fixture(DataGloveEmulator, rate=200.0)
managers = managers_fixture("DataGlove_drv", tune={"data_glove": TUNE})


def aligned(decoded: list[tuple[float, ...]], emu: DataGloveEmulator, capability: int = 0) -> None:
    """``decoded`` is what was sent, value for value and with no gap, from the first packet
    the driver could read on. Packets written before the driver opened the line are discarded
    by the open, unless still on their way through the pty (on a loaded machine more than one
    can be): the run starts at one of the first packets sent."""
    sent = [emu.probe, *emu.sent] if emu.probe is not None else list(emu.sent)
    for first in range(min(len(sent), 8)):
        want = [expected(d, capability) for d in sent[first : first + len(decoded)]]
        if decoded == [pytest.approx(w) for w in want]:
            return
    want = [expected(d, capability) for d in emu.sent[: len(decoded)]]
    assert decoded == [pytest.approx(w) for w in want]


# -- the wire format, from the protocol description -------------------------------------------


def test_packets_decode_as_the_protocol_says() -> None:
    data = bytes([255, 0, 128, 51, 200, 0, 255])
    check = 255 ^ 0 ^ 128 ^ 51 ^ 200 ^ 0 ^ 255
    got = decode_packet(bytes([0x80]) + data + bytes([check, 6]))
    assert got.flexure == pytest.approx((1.0, 0.0, 128 / 255, 0.2, 200 / 255))
    assert (got.pitch, got.roll, got.hand) == (0.0, 180.0, "left")
    # index and ring open, middle and pinky bent: gesture 5
    assert got.gesture == 5
    # the checksum must match (the C++ kept only packets where it did not)
    assert decode_packet(bytes([0x80]) + data + bytes([check ^ 1, 6])) is None
    # any 10th byte real gloves send is accepted, and 9-byte packets (the manual's)
    for tenth in (0x00, 0x06, 0x01, 0x40, 0x55, 0x03):
        assert decode_packet(bytes([0x80]) + data + bytes([check, tenth])).capability == tenth
    assert decode_packet(bytes([0x80]) + data + bytes([check]), capability=6).hand == "left"
    assert gesture(0.9, 0.9, 0.9, 0.9) == 0 and gesture(0.1, 0.1, 0.1, 0.1) == 15
    assert gesture(0.9, 0.9, 0.1, 0.9) == NO_GESTURE  # ring open alone is no gesture


def test_junk_runs_are_counted_once_and_the_buffer_stays_bounded() -> None:
    good = encode_packet((1, 2, 3, 4, 5, 6, 7))
    scanner = PacketScanner()
    # (a run of 0x80 alone would be packets: seven 128s XOR to 128, a valid checksum)
    junk = bytes([0x80, 1, 2]) + bytes(range(0x70, 0x90)) + b"\x80\x01\x02" * 17
    got = scanner.feed(junk[:20]) + scanner.feed(junk[20:] + good + good)
    assert len(got) == 2 and scanner.bad_records == 1
    assert scanner.skipped_bytes == len(junk)
    scanner.feed(b"\x80\x01\x02" * 33_000)
    assert len(scanner.buffer) <= PACKET_SIZE and scanner.bad_records == 2


def test_nine_and_ten_byte_packets_mix_and_the_last_waits_for_its_next_byte() -> None:
    data = [(i, 2 * i, 3, 4, 5, 128, 128) for i in range(1, 7)]
    stream = b"".join(
        encode_packet(d, tenth)
        for d, tenth in zip(data, (None, 0x55, None, 0x40, 0x01, None), strict=True)
    )
    scanner = PacketScanner(capability=6)
    got = scanner.feed(stream)
    assert [g.flexure[0] for g in got] == pytest.approx([i / 255 for i in range(1, 6)])
    assert [g.capability for g in got] == [6, 0x55, 6, 0x40, 0x01]
    assert scanner.buffer == bytearray(encode_packet(data[5], None))  # a 10th byte may come
    last = scanner.feed(b"", quiet=True)  # the line went quiet: it was a 9-byte packet
    assert len(last) == 1 and last[0].capability == 6
    assert scanner.bad_records == 0 and scanner.skipped_bytes == 0


# -- standalone over the pty ------------------------------------------------------------------


def test_standalone_reads_every_packet_in_order(emulator) -> None:
    emu = emulator("motion", hand=LEFT)
    with DataGlove(emu.address, **FAST) as device:
        got = []
        assert wait_until(lambda: len(got) >= 30, step=lambda: got.extend(device.poll()))
    aligned([s.analog for s in got], emu, capability=LEFT)
    assert all(s.hand == "left" for s in got)
    assert device.scanner.bad_records == 0


@pytest.mark.parametrize(
    ("model", "hand", "capability"),
    [
        ("classic", LEFT, 6),
        ("wireless", RIGHT, 0x01),
        ("wireless", LEFT, 0x40),
        ("wired", LEFT, 6),  # 9-byte packets: the hand from the G answer
        ("wired", RIGHT, 0),
        ("wired-55", RIGHT, 0x55),
    ],
)
def test_every_kind_of_glove_is_read(emulator, model, hand, capability) -> None:
    emu = emulator("motion", model=model, hand=hand)
    with DataGlove(emu.address, **FAST, reply_timeout=2.0) as device:
        got = gather(device.poll, 20)
    aligned([s.analog for s in got], emu, capability=capability)
    assert device.scanner.bad_records == 0
    if model.startswith("wired"):
        assert b"".join(emu.commands) == b"AGD"  # init, information, stream
        assert device.info is not None and device.info.right == (hand == RIGHT)
        assert device.info.name == "5DT Data Glove 5" and device.info.pitch_roll
    else:
        assert device.info is None  # it streamed without being asked


def test_a_wired_glove_that_never_answers_fails_to_start(tmp_path) -> None:
    from gadgetctl.emulation.testing import FixtureLine

    with FixtureLine() as line:
        with pytest.raises(DataGloveNoAnswer, match="no answer"):
            DataGlove(line.address, **FAST, reply_timeout=0.2).open()
        assert bytes(line.received) == b"A"


# -- in the input manager ---------------------------------------------------------------------


def test_units_scaling_and_glove_angles(emulator, managers) -> None:
    emu = emulator("buttons", rate=100.0)
    manager = managers(glove("Glove", emu.address))
    assert not manager.pending()
    frame, analog = frame_recorder(manager, "Glove", DeviceKind.ANALOG)
    assert wait_until(lambda: len(analog) > 12, step=frame)
    aligned(analog, emu)
    assert {a[7] for a in analog} >= {0.0, 15.0}  # a fist, then an open hand
    device = manager.device("Glove")
    latest = device.store.latest(DeviceKind.ANALOG).values
    angles = manager.proxy("Glove Hand").data
    assert angles.shape == (6, 4)
    for finger in range(5):
        np.testing.assert_allclose(angles[finger, :3], latest[finger] * math.pi / 2)
        assert angles[finger, 3] == 0
    assert not angles[5].any()
    assert manager.proxy("Glove A1").data == pytest.approx(latest[1])  # flexure is 0..1 already


def test_garbage_is_resynchronised_and_counted_without_a_fault(emulator, managers) -> None:
    emu = emulator("garbage")
    manager = managers(glove("Glove", emu.address))
    frame, analog = frame_recorder(manager, "Glove", DeviceKind.ANALOG)
    assert wait_until(lambda: len(analog) > 30, step=frame)
    aligned(analog, emu)
    device = manager.device("Glove")
    assert device.bad_records >= 20 and device.skipped_bytes > 100
    assert device.faults == 0 and manager.status("Glove").state == "running"


def test_lost_line_faults_then_samples_within_two_seconds(tmp_path, emulator, managers) -> None:
    link = tmp_path / "glove"
    emu = emulator("disconnect", rate=100.0, disconnect_after=5, link=link)
    manager = managers(glove("Glove", str(link)))
    frame, analog = frame_recorder(manager, "Glove", DeviceKind.ANALOG)
    faults_then_resumes(
        manager,
        "Glove",
        emu,
        lambda: emulator("motion", rate=100.0, link=link),
        lambda: len(analog),
        step=frame,
    )


def test_a_wired_glove_streams_to_the_manager_once_started(emulator, managers) -> None:
    # a wired glove sends nothing until asked (A, G, D), and then 9-byte packets
    emu = emulator("buttons", rate=100.0, model="wired", hand=LEFT)
    manager = managers(glove("Glove", emu.address))
    frame, analog = frame_recorder(manager, "Glove", DeviceKind.ANALOG)
    assert wait_until(lambda: len(analog) > 12, step=frame)
    assert b"".join(emu.commands) == b"AGD"
    aligned(analog, emu, capability=LEFT)  # 9-byte packets: the hand the G answer gave
    assert {a[7] for a in analog} >= {0.0, 15.0}
    device = manager.device("Glove")
    assert device.bad_records == 0 and device.faults == 0
