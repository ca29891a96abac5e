"""PinchGlove standalone driver against the emulator over a real pty pair."""

from __future__ import annotations

import math
import time

import pytest
import serial
from PinchGlove_drv.emulator import DEFAULT_INFO, TOUCH_SEQUENCE, PinchGloveEmulator
from PinchGlove_drv.standalone import (
    PinchGlove,
    PinchGloveDisconnected,
    PinchGloveTimeout,
    PinchSample,
    decode_frame,
)

from gadgetctl.input.testing.fixtures import emulator_fixture

pytestmark = pytest.mark.timeout(10)

FAST = {
    "command_delay": 0.0,
    "echo_wait": 0.0,
    "read_timeout": 1.0,
    "sample_timeout": 1.0,
    "poll_interval": 0.01,
}
OPEN = (0,) * 10


emulator = emulator_fixture(PinchGloveEmulator, "touches", rate=200.0)


def digital_of(left: int, right: int) -> tuple[int, ...]:
    """Expected digital units from the protocol: bit k of left/right -> unit k / 5+k."""
    return tuple((left >> k) & 1 for k in range(5)) + tuple((right >> k) & 1 for k in range(5))


def expected_digital(groups: tuple[tuple[int, int], ...]) -> tuple[int, ...]:
    left = right = 0
    for lbits, rbits in groups:
        left |= lbits
        right |= rbits
    return digital_of(left, right)


def read_samples(glove: PinchGlove, count: int) -> list[PinchSample]:
    samples = []
    while len(samples) < count:
        sample = glove.sample()
        assert sample is not None, f"no frame after {len(samples)} samples"
        samples.append(sample)
    return samples


def test_startup_queries_and_initial_state(emulator) -> None:
    emu = emulator("idle")
    glove = PinchGlove(emu.address, **FAST)
    with glove:
        assert emu.commands == [b"CL", b"CR", b"CP", b"CT", b"T1"]
        assert glove.info == DEFAULT_INFO
        assert glove.last.digital == OPEN
        assert [h.hand for h in glove.last.hands] == ["left", "right"]
        assert all(a == (0.0,) * 4 for h in glove.last.hands for a in h.angles)
        # the pty cannot set RTS; the driver carries on
        assert glove.control_lines is False
        glove.sample_timeout = 0.05
        assert glove.sample() is None  # an idle glove sends nothing
    assert not glove.is_open


def test_touch_frames_decode_to_digital_and_glove(emulator) -> None:
    emu = emulator("touches")
    with PinchGlove(emu.address, **FAST) as glove:
        samples = read_samples(glove, len(TOUCH_SEQUENCE))

    # Step by step, written out from the protocol description: unit k is bit k of the hand's
    # byte, pinky (0x01) first, thumb (0x10) last.
    assert samples[0].digital == (0, 0, 0, 1, 1, 0, 0, 0, 0, 0)  # left thumb + index
    assert samples[1].digital == OPEN
    assert samples[2].digital == (0, 0, 0, 0, 0, 0, 0, 1, 0, 1)  # right thumb + middle
    assert samples[4].digital == (0, 0, 0, 0, 1, 0, 0, 0, 0, 1)  # both thumbs
    assert samples[5].digital == (1, 0, 0, 0, 1, 1, 1, 0, 0, 0)  # two groups ORed
    assert samples[5].groups == ((0b10001, 0), (0, 0b00011))
    assert samples[6].digital == OPEN

    for sample, (groups, stamp) in zip(samples, emu.sent, strict=False):
        assert sample.digital == expected_digital(groups)
        assert sample.timestamp == stamp

    thumbs = samples[4]
    assert thumbs.left.finger("thumb") and thumbs.right.finger("thumb")
    assert thumbs.left.angles[0] == (math.pi / 2,) * 4
    assert thumbs.right.angles[0] == (math.pi / 2,) * 4
    assert thumbs.left.angles[1] == (0.0,) * 4
    assert sum(sum(f) for h in samples[6].hands for f in h.angles) == 0.0


def test_timestamps_off_gives_plain_frames(emulator) -> None:
    emu = emulator("touches")
    with PinchGlove(emu.address, timestamps=False, query_info=False, **FAST) as glove:
        assert emu.commands == [b"T0"]
        first = glove.sample()
    assert first is not None
    assert first.timestamp is None
    assert first.digital == (0, 0, 0, 1, 1, 0, 0, 0, 0, 0)


def test_motion_scenario_is_deterministic(emulator) -> None:
    emu = emulator("motion")
    with PinchGlove(emu.address, query_info=False, **FAST) as glove:
        samples = read_samples(glove, 10)
    # thumb taps index, middle, ring, pinky (releases in between), then the right hand
    assert [s.digital for s in samples[0:8:2]] == [
        digital_of(0b11000, 0),
        digital_of(0b10100, 0),
        digital_of(0b10010, 0),
        digital_of(0b10001, 0),
    ]
    assert all(s.digital == OPEN for s in samples[1:8:2])
    assert samples[8].digital == digital_of(0, 0b11000)


def test_garbage_is_counted_and_skipped(emulator) -> None:
    emu = emulator("garbage")
    count = 2 * len(TOUCH_SEQUENCE)
    with PinchGlove(emu.address, query_info=False, **FAST) as glove:
        samples = read_samples(glove, count)
        assert glove.frames == count
        # each junk kind went out twice; the broken frames among them (truncated,
        # odd length, bits no finger has, too short) are counted as bad frames
        assert glove.bad_frames == 8
        assert glove.skipped_bytes > 0
    # no valid frame lost, no junk decoded as a frame
    assert [s.digital for s in samples] == [expected_digital(g) for g, _ in emu.sent[:count]]
    assert [s.timestamp for s in samples] == [t for _, t in emu.sent[:count]]


def test_truncated_frame_then_silence_is_counted(emulator) -> None:
    emu = emulator("idle")
    with PinchGlove(
        emu.address, query_info=False, **{**FAST, "read_timeout": 0.05, "sample_timeout": 0.2}
    ) as glove:
        emu.send_raw(bytes([0x81, 0x01]))  # a frame that never ends
        assert glove.sample() is None
        assert glove.bad_frames == 1
        emu.send_raw(bytes([0x81, 0x01, 0x01, 0x05, 0x00, 0x8F]))  # timestamp low 7 bits first
        sample = glove.sample()
    assert sample is not None
    assert sample.digital == (1, 0, 0, 0, 0, 1, 0, 0, 0, 0)
    assert sample.timestamp == 5


def test_disconnect_is_reported(emulator) -> None:
    emu = emulator("disconnect", disconnect_after=3)
    with PinchGlove(emu.address, query_info=False, **FAST) as glove:
        read_samples(glove, 3)
        assert emu.disconnected.wait(2)
        with pytest.raises(PinchGloveDisconnected):
            for _ in range(5):
                glove.sample()


@pytest.mark.parametrize("echo_wait", [0.05, 0.0])
def test_stray_byte_in_glove_is_recovered(emulator, echo_wait: float) -> None:
    emu = emulator("idle")
    port = serial.Serial(emu.address, 9600, timeout=0.01)
    try:
        port.write(b"X")  # leaves the glove half-way through a command
        deadline = time.monotonic() + 2
        while emu.bytes_received < 1 and time.monotonic() < deadline:
            time.sleep(0.005)
        with PinchGlove(port, **{**FAST, "echo_wait": echo_wait}) as glove:
            assert glove.info == DEFAULT_INFO
        assert emu.commands[0] == b"XC"
        assert emu.commands[-5:] == [b"CL", b"CR", b"CP", b"CT", b"T1"]
        assert port.is_open  # an injected port is not closed by the driver
    finally:
        port.close()


def test_data_format_version_sends_v(emulator) -> None:
    emu = emulator("idle")
    with PinchGlove(emu.address, query_info=False, **FAST) as glove:
        glove.set_data_format_version()
    assert emu.commands[-1] == b"V1"


def test_spy_url_passes_through_serial_for_url(emulator, tmp_path) -> None:
    emu = emulator("touches")
    log = tmp_path / "spy.txt"
    with PinchGlove(f"spy://{emu.address}?file={log}", query_info=False, **FAST) as glove:
        assert glove.sample() is not None
    assert log.stat().st_size > 0


def test_loop_url_without_glove_times_out_quickly() -> None:
    start = time.monotonic()
    with pytest.raises(PinchGloveTimeout):
        PinchGlove("loop://", **{**FAST, "read_timeout": 0.05}).open()
    assert time.monotonic() - start < 2


def test_missing_port_is_reported_as_unavailable(tmp_path) -> None:
    with pytest.raises(PinchGloveDisconnected):
        PinchGlove(str(tmp_path / "no-such-tty"), **FAST).open()


def test_decode_frame_rules() -> None:
    sample = decode_frame(0x81, bytes([0x01, 0x01, 0x12, 0x34]))
    assert sample is not None
    assert sample.digital == (1, 0, 0, 0, 0, 1, 0, 0, 0, 0)
    assert sample.timestamp == 0x34 << 7 | 0x12  # low 7 bits first
    released = decode_frame(0x81, bytes([0x00, 0x07]))
    assert released is not None and released.digital == OPEN and released.groups == ()
    assert decode_frame(0x80, bytes([0x01])) is None  # odd pair bytes
    assert decode_frame(0x81, bytes([0x01])) is None  # no room for the timestamp
    assert decode_frame(0x80, bytes([0x20, 0x00])) is None  # no sixth finger


def test_emulator_main_prints_where_to_point(tmp_path, capsys) -> None:
    from PinchGlove_drv.emulator import main

    link = tmp_path / "pinchglove"
    assert (
        main(["--scenario", "idle", "--rate", "5", "--duration", "0.1", "--port", str(link)]) == 0
    )
    out = capsys.readouterr().out
    assert "/dev/pts/" in out and f"<port>{link}</port>" in out
    assert not link.exists()  # the symlink goes away with the emulator
