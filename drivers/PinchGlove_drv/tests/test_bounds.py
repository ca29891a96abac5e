"""A glove line that never ends a frame or a reply: bounded frames and replies, over a pty."""

from __future__ import annotations

import pytest
from PinchGlove_drv.emulator import DEFAULT_INFO, PinchGloveEmulator
from PinchGlove_drv.standalone import MAX_FRAME_BODY, MAX_REPLY, PinchGlove, PinchGloveProtocolError

from gadgetctl.input.testing.fixtures import emulator_fixture

pytestmark = pytest.mark.timeout(20)
FAST = {"command_delay": 0.0, "echo_wait": 0.0, "read_timeout": 0.5, "poll_interval": 0.01}


emulator = emulator_fixture(PinchGloveEmulator, "idle", rate=200.0)


def test_a_frame_body_longer_than_any_frame_is_bad_and_the_rest_skipped(emulator) -> None:
    emu = emulator()
    with PinchGlove(emu.address, query_info=False, sample_timeout=2.0, **FAST) as glove:
        emu.send_raw(bytes([0x81]) + bytes([0x01]) * 3000)  # contact bytes, never an end
        emu.send_raw(bytes([0x81, 0x01, 0x01, 0x00, 0x05, 0x8F]))  # then a good frame
        sample = glove.sample()
    assert sample is not None and sample.digital == (1, 0, 0, 0, 0, 1, 0, 0, 0, 0)
    assert glove.bad_frames == 1 and glove.frames == 1
    assert glove.skipped_bytes == 3000 - MAX_FRAME_BODY  # skipped as junk, not kept


def test_a_reply_longer_than_any_reply_fails_the_start(emulator) -> None:
    info = {**DEFAULT_INFO, next(iter(DEFAULT_INFO)): "v" * 5000}
    emu = emulator(info=info)
    glove = PinchGlove(emu.address, sample_timeout=0.2, **FAST)
    with pytest.raises(PinchGloveProtocolError, match=f"longer than {MAX_REPLY}"):
        glove.open()
    assert not glove.is_open
