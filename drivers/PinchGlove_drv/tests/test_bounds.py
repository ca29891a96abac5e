"""A glove line that never ends a frame or a reply: bounded frames and replies, and a setup
bounded in time however the line trickles, over a pty."""

from __future__ import annotations

import threading
import time

import pytest
from PinchGlove_drv.emulator import DEFAULT_INFO, PinchGloveEmulator
from PinchGlove_drv.standalone import (
    MAX_FRAME_BODY,
    MAX_REPLY,
    PinchGlove,
    PinchGloveProtocolError,
    PinchGloveTimeout,
)

from gadgetctl.emulation.testing import FixtureLine
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


def test_a_line_that_trickles_junk_fails_the_setup_within_its_timeout() -> None:
    """Found by make fuzz (serial.pinchglove): a byte now and then, never a reply, kept
    open() (and the input manager's frame that started the device) for 30 to 95 s."""
    outcome: list[BaseException | None] = []
    with FixtureLine() as line:
        glove = PinchGlove(line.address, **{**FAST, "read_timeout": 2.0, "setup_timeout": 1.0})

        def start() -> None:
            try:
                glove.open()
                outcome.append(None)
            except Exception as err:
                outcome.append(err)

        opener = threading.Thread(target=start, daemon=True)
        began = time.monotonic()
        opener.start()
        while opener.is_alive() and time.monotonic() - began < 6.0:
            line.feed(b"\x00" * 10)  # junk, never a reply: each byte keeps it reading
            time.sleep(0.02)
        opener.join(1.0)
        took = time.monotonic() - began
    assert not opener.is_alive(), "open() still reading after 6 s"
    assert isinstance(outcome[0], PinchGloveTimeout) and "within 1 s" in str(outcome[0])
    assert took < 4.0 and not glove.is_open
