"""TUIO_drv against bytes that do not come from our emulator (issue 23, item 7 and "What to
build" 1): OSC packets byte-exact from the OSC 1.0 specification's examples, and TUIO 1.1
frames packed by python-osc's own builders (``pythonosc.osc_bundle_builder`` and
``osc_message_builder``, another implementation), laid out as the TUIO 1.1 specification
(tuio.org/?specification) and the reference TuioClient (github.com/mkalten/TUIO11_CPP,
TUIO11_JAVA) define them: ``source``, ``alive``, ``set``, ``fseq`` per bundle. python-osc's
decoder also reads what our emulator sends, as a check of the emulator."""

from __future__ import annotations

import struct

import pytest
from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder
from pythonosc.osc_message_builder import OscMessageBuilder
from pythonosc.osc_packet import OscPacket
from TUIO_drv.emulator import frame_bundle, late_bundle
from TUIO_drv.osc import MAX_DEPTH, OscError, OscMessage, decode_packet
from TUIO_drv.standalone import TuioReceiver

pytestmark = pytest.mark.timeout(30)

# Source: "Examples Supporting the OpenSoundControl 1.0 Spec", Matt Wright, March 29 2002
# (opensoundcontrol.org/spec-1_0-examples), "OSC Message Examples": the message
# "/oscillator/4/frequency" with the float 440.0, 32 bytes, ...
SPEC_FREQUENCY = bytes.fromhex(
    "2f6f7363 696c6c61 746f722f 342f6672 65717565 6e637900 2c660000 43dc0000"
)
# ... and "/foo" with 1000, -1, "hello", 1.234 and 5.678, 40 bytes.
SPEC_FOO = bytes.fromhex(
    "2f666f6f 00000000 2c696973 66660000 000003e8 ffffffff 68656c6c 6f000000 3f9df3b6 40b5b22d"
)


def test_the_osc_specification_examples_decode_as_the_specification_says() -> None:
    (frequency,) = decode_packet(SPEC_FREQUENCY).messages
    assert frequency == OscMessage("/oscillator/4/frequency", (440.0,))
    (foo,) = decode_packet(SPEC_FOO).messages
    assert foo.address == "/foo" and foo.arguments[:3] == (1000, -1, "hello")
    assert foo.arguments[3:] == pytest.approx((1.234, 5.678), abs=1e-6)


def cursor(*args: object) -> bytes:
    """A /tuio/2Dcur message packed by python-osc (ints as i, floats as f, strings as s)."""
    builder = OscMessageBuilder("/tuio/2Dcur")
    for value in args:
        builder.add_arg(value)
    return builder.build().dgram


def tracker_frame(source: str | None, fseq: int, *fingers: tuple[int, float, float]) -> bytes:
    """One TUIO 1.1 frame as a tracker sends it, packed by python-osc's bundle builder."""
    bundle = OscBundleBuilder(IMMEDIATELY)
    if source is not None:
        bundle.add_content(OscPacket(cursor("source", source)).messages[0].message)
    for packed in (
        cursor("alive", *(s for s, _, _ in fingers)),
        *(cursor("set", s, x, y, 0.0, 0.0, 0.0) for s, x, y in fingers),
        cursor("fseq", fseq),
    ):
        bundle.add_content(OscPacket(packed).messages[0].message)
    return bundle.build().dgram


def test_source_messages_are_valid_and_each_source_keeps_its_own_fingers() -> None:
    receiver = TuioReceiver(0, 4)
    # two trackers on one port, both numbering their sessions from 1 (sessions are per source)
    for fseq in range(1, 6):
        assert receiver.feed(tracker_frame("left@10.0.0.1", fseq, (1, 0.25, 0.5)))
        assert receiver.feed(tracker_frame("right@10.0.0.2", fseq + 500, (1, 0.75, 0.5)))
        assert receiver.slots.digital() == [1, 1, 0, 0]  # never one finger lifting the other
        assert receiver.slots.analog()[:4] == [0.25, 0.5, 0.75, 0.5]
    assert receiver.slots.bad_records == 0 and receiver.ledger.bad_count == 0
    assert receiver.ledger.decoded_count == 10 and receiver.slots.late_frames == 0


def test_a_late_frame_is_dropped_as_the_reference_client_drops_it() -> None:
    receiver = TuioReceiver(0, 2)
    receiver.feed(tracker_frame("pad@host", 10, (7, 0.5, 0.5)))
    assert not receiver.feed(tracker_frame("pad@host", 8))  # late: fseq 8 < 10, within 100
    assert receiver.slots.digital() == [1, 0] and receiver.slots.late_frames == 1
    assert receiver.feed(tracker_frame("pad@host", 10, (7, 0.625, 0.5)))  # the same fseq again
    assert receiver.slots.analog()[:2] == [0.625, 0.5]
    assert receiver.feed(tracker_frame("pad@host", 150, (7, 0.5, 0.5)))
    assert receiver.feed(tracker_frame("pad@host", 1))  # 100+ back: the tracker restarted
    assert receiver.slots.digital() == [0, 0] and receiver.slots.late_frames == 1
    receiver.feed(tracker_frame("pad@host", -1, (8, 0.1, 0.1)))  # fseq -1: applied unordered
    assert receiver.slots.digital() == [1, 0]


def _bundle_of(packet: bytes):
    from pythonosc.osc_bundle import OscBundle

    return OscBundle(packet)


def nested(depth: int) -> bytes:
    """A frame (number 5) inside ``depth`` bundles, packed by python-osc."""
    packet = tracker_frame(None, 5, (1, 0.5, 0.5))
    for _ in range(depth - 1):
        bundle = OscBundleBuilder(IMMEDIATELY)
        bundle.add_content(_bundle_of(packet))
        packet = bundle.build().dgram
    return packet


def test_a_tuio_1_0_frame_without_source_and_nested_bundles_decode() -> None:
    receiver = TuioReceiver(0, 2)
    assert receiver.feed(tracker_frame(None, 3, (4, 0.125, 0.875)))
    assert receiver.slots.digital() == [1, 0] and receiver.slots.analog()[:2] == [0.125, 0.875]
    assert receiver.feed(nested(3))  # session 1 alone now, at 0.5, 0.5
    assert receiver.slots.digital() == [1, 0] and receiver.slots.analog()[:2] == [0.5, 0.5]


def deeply_nested(depth: int) -> bytes:
    """``depth`` bundles, each holding the next, by the OSC 1.0 framing (python-osc's own
    parser recurses, so it cannot build this many)."""
    packet = tracker_frame(None, 1, (1, 0.5, 0.5))
    for _ in range(depth - 1):
        packet = b"#bundle\x00" + bytes(7) + b"\x01" + struct.pack(">i", len(packet)) + packet
    return packet


def test_nesting_is_bounded_and_too_deep_a_packet_is_bad() -> None:
    assert decode_packet(nested(MAX_DEPTH)).depth == MAX_DEPTH
    with pytest.raises(OscError, match="nest deeper than 8"):
        decode_packet(nested(MAX_DEPTH + 1))
    receiver = TuioReceiver(0, 2)
    deep = deeply_nested(1100)
    assert len(deep) > 20_000
    assert not receiver.feed(deep)  # issue 24 item 5: a RecursionError before
    assert receiver.ledger.bad_count == 1 and receiver.ledger.first_error == (
        "not OSC: bundles nest deeper than 8"
    )


def test_python_osc_reads_what_our_emulator_sends() -> None:
    for packet in (frame_bundle(12, 3, "motion", source=2), late_bundle(12)):
        theirs = [(m.message.address, m.message.params) for m in OscPacket(packet).messages]
        ours = [(m.address, list(m.arguments)) for m in decode_packet(packet).messages]
        assert theirs == ours and theirs[0] == ("/tuio/2Dcur", ["source", theirs[0][1][1]])
    x = struct.unpack(">f", struct.pack(">f", 0.3))[0]  # what a float32 keeps of 0.3
    assert decode_packet(cursor("set", 1, 0.3, 0.3)).messages[0].arguments[2] == x
