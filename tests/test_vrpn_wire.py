"""The VRPN wire format against the byte vectors of the reference (section 13)."""

from __future__ import annotations

import ast
import struct
from pathlib import Path

import pytest

from gadgetctl.vrpn import codecs, wire
from gadgetctl.vrpn.names import VrpnNameError, parse_device_name, parse_location

T = {"sec": 0x12345678, "usec": 0x0009ABCD}


def test_cookie_bytes_match_the_live_server():
    expected = bytes.fromhex("7672706e3a207665722e2030372e33382020300000000000")
    assert wire.make_cookie() == expected
    assert wire.check_cookie(expected) == "07.38"


@pytest.mark.parametrize(
    ("magic", "ok"),
    [(b"vrpn: ver. 07.35", True), (b"vrpn: ver. 08.00", False), (b"HTTP/1.1 200 OK\r\n", False)],
)
def test_cookie_acceptance_follows_the_major_version(magic, ok):
    cookie = (magic[:16] + b"  0").ljust(24, b"\0")
    if ok:
        assert wire.check_cookie(cookie) == magic[11:16].decode()
    else:
        with pytest.raises(wire.CookieError):
            wire.check_cookie(cookie)


def test_cookie_with_a_bad_log_digit_is_refused():
    with pytest.raises(wire.CookieError, match="log-mode"):
        wire.check_cookie(wire.MAGIC + b"  7" + b"\0" * 5)


def test_sender_description_vector():
    frame = wire.pack_message(wire.SENDER_DESCRIPTION, 1, wire.description_payload("Tracker0"), **T)
    expected = bytes.fromhex(
        "00000025123456780009abcd00000001ffffffff0000000000000009547261636b65723000000000"
    )
    assert frame == expected
    (m,) = wire.StreamDecoder().feed(expected)
    assert (m.type_id, m.sender_id) == (-1, 1)
    assert wire.decode_description(m.payload) == "Tracker0"


def test_pos_quat_vector():
    payload = codecs.encode_pose(1, (0.5, -1.0, 2.0))
    frame = wire.pack_message(4, 1, payload, **T)
    assert len(frame) == 88
    assert frame[:4] == bytes.fromhex("00000058")
    assert frame[12:24] == bytes.fromhex("000000010000000400000000")
    assert payload[:16] == bytes.fromhex("00000001000000013fe0000000000000")
    assert payload[16:24] == bytes.fromhex("bff0000000000000")
    assert payload[24:32] == bytes.fromhex("4000000000000000")
    assert payload[32:56] == bytes(24)
    assert payload[56:] == bytes.fromhex("3ff0000000000000")
    assert codecs.decode(codecs.TRACKER_POS_QUAT, payload) == codecs.TrackerPose(
        1, (0.5, -1.0, 2.0), (0.0, 0.0, 0.0, 1.0)
    )


def test_button_change_and_udp_description_vectors():
    frame = wire.pack_message(7, 3, codecs.encode_button_change(2, 1), **T)
    assert frame[:4] == bytes.fromhex("00000020")
    assert frame[24:] == bytes.fromhex("0000000200000001")
    udp = wire.pack_udp_description("127.0.0.1", 50488)
    assert len(udp) == 40
    assert udp[:4] == bytes.fromhex("00000022")
    assert udp[12:20] == bytes.fromhex("0000c538fffffffd")
    assert udp[24:34] == b"127.0.0.1\0"
    (m,) = wire.decode_datagram(udp)
    assert wire.decode_udp_description(m) == ("127.0.0.1", 50488)


def test_padding_is_ignored_and_messages_split_anywhere():
    # Garbage in the padding (as the live server sends) and a stream cut at every byte.
    states = codecs.encode_button_states([1, 0, 1, 1])  # 20 bytes -> 4 padding bytes
    one = wire.pack_message(5, 2, states, **T)
    one = one[:-4] + bytes.fromhex("6b01789c")
    stream = one + wire.pack_message(6, 2, b"", **T) + one
    for cut in range(len(stream)):
        dec = wire.StreamDecoder()
        got = dec.feed(stream[:cut]) + dec.feed(stream[cut:])
        assert [m.type_id for m in got] == [5, 6, 5]
        assert codecs.decode(codecs.BUTTON_STATES, got[2].payload).states == (1, 0, 1, 1)
        assert dec.pending == 0


def test_header_limits_match_the_cpp_receiver():
    # 64,032 bytes is the largest message accepted, 64,040 is "too long".
    assert wire.check_header(64032) == 64008
    with pytest.raises(wire.FramingError, match="too long"):
        wire.StreamDecoder().feed(struct.pack(">IiiiiI", 64040, 0, 0, 0, 0, 0))
    with pytest.raises(wire.FramingError, match="shorter"):
        wire.StreamDecoder().feed(struct.pack(">IiiiiI", 23, 0, 0, 0, 0, 0))
    # A header claiming 4 GB is refused before anything is waited for or allocated.
    with pytest.raises(wire.FramingError):
        wire.StreamDecoder().feed(struct.pack(">IiiiiI", 0xFFFFFFFF, 0, 0, 0, 0, 0))


def test_datagram_framing_errors():
    good = wire.pack_message(1, 0, b"abc")
    assert len(wire.decode_datagram(good + good)) == 2
    with pytest.raises(wire.FramingError):
        wire.decode_datagram(good + good[:10])
    with pytest.raises(wire.FramingError):
        wire.decode_datagram(good[:-8][:26])


def test_description_limits():
    with pytest.raises(ValueError):
        wire.description_payload("x" * 96)
    wire.description_payload("x" * 95)
    with pytest.raises(wire.FramingError):
        wire.decode_description(struct.pack(">I", 200) + b"abc\0")
    with pytest.raises(wire.FramingError):
        wire.decode_description(b"\0" * 101)


@pytest.mark.parametrize(
    ("data", "ok"),
    [
        (b"127.0.0.1 40123\0", ("127.0.0.1", 40123)),
        (b"10.0.0.7 1024\0garbage", ("10.0.0.7", 1024)),
        (b"127.0.0.1 1023\0", None),
        (b"127.0.0.1 70000\0", None),
        (b"my-host 4000\0", None),
        (b"127.0.0.1\0", None),
        (b"\xff\xfe 4000", None),
        (b"", None),
        (b"a" * 5000, None),
    ],
)
def test_lob_parsing(data, ok):
    if ok:
        assert wire.parse_lob(data) == ok
        assert wire.parse_lob(wire.lob_request(*ok)) == ok
    else:
        with pytest.raises(wire.LobError):
            wire.parse_lob(data)


@pytest.mark.parametrize(
    ("text", "device", "host", "port", "tcp"),
    [
        ("Tracker0@localhost", "Tracker0", "localhost", 3883, False),
        ("Tracker0@host:4000", "Tracker0", "host", 4000, False),
        ("Wand@tcp://10.1.2.3:3884", "Wand", "10.1.2.3", 3884, True),
        ("Wand@tcp:10.1.2.3:3884", "Wand", "10.1.2.3", 3884, True),
        ("Wand@tcp://server", "Wand", "server", 3883, True),
        ("Wand@x-vrpn://server:5000", "Wand", "server", 5000, False),
        ("Dev@Other@host", "Dev", "Other@host", 3883, False),
    ],
)
def test_device_names(text, device, host, port, tcp):
    name = parse_device_name(text)
    assert (name.device, name.location.host, name.location.port, name.location.tcp) == (
        device,
        host,
        port,
        tcp,
    )


@pytest.mark.parametrize(
    "text", ["Tracker0", "@host", "T@", "T@host:0", "T@host:abc", "T@x-vrsh://h/srv", "T@file:/x"]
)
def test_bad_device_names(text):
    with pytest.raises(VrpnNameError):
        parse_device_name(text)
    assert parse_location("h:1").port == 1


def test_codecs_round_trip_and_bounds():
    assert codecs.decode(codecs.ANALOG_CHANNEL, codecs.encode_analog([0.25, -1.0, 3.0])) == (
        codecs.AnalogChannels((0.25, -1.0, 3.0))
    )
    # Live vector: three channels start with 3.0 as a double.
    assert codecs.encode_analog([0, 0, 0])[:8] == bytes.fromhex("4008000000000000")
    assert codecs.decode(codecs.DIAL_UPDATE, codecs.encode_dial(3, 0.05)) == codecs.DialUpdate(
        3, 0.05
    )
    assert len(codecs.encode_dial(3, 0.05)) == 12
    text = codecs.encode_text("hello", 1, 2) + b"junk" * 10
    assert codecs.decode(codecs.TEXT_MESSAGE, text) == codecs.TextReport(1, 2, "hello")
    vel = codecs.decode(codecs.TRACKER_VELOCITY, codecs.encode_velocity(0, (1, 2, 3), dt=0.5))
    assert vel.velocity == (1, 2, 3) and vel.dt == 0.5
    with pytest.raises(codecs.StrictLengthError):
        codecs.decode(codecs.TRACKER_POS_QUAT, b"\0" * 63)
    with pytest.raises(codecs.StrictLengthError):
        codecs.decode(codecs.BUTTON_CHANGE, b"\0" * 12)
    with pytest.raises(codecs.CodecError):  # 2**31 buttons claimed in 8 bytes
        codecs.decode(codecs.BUTTON_STATES, struct.pack(">ii", 2**31 - 1, 1))
    with pytest.raises(codecs.CodecError):
        codecs.decode(codecs.ANALOG_CHANNEL, struct.pack(">d", 1e300))
    with pytest.raises(codecs.CodecError):
        codecs.decode(codecs.ANALOG_CHANNEL, struct.pack(">d", float("nan")))
    with pytest.raises(codecs.CodecError):
        codecs.decode(codecs.ANALOG_CHANNEL, struct.pack(">dd", 4.0, 1.0))
    assert codecs.decode("vrpn_Something else", b"xyz") is None


def test_split_time():
    assert wire.split_time(1.9999999) == (2, 0)
    assert wire.split_time(10.25) == (10, 250000)


def test_the_vrpn_package_imports_nothing_else_from_gadgetctl():
    package = Path(wire.__file__).parent
    offenders = []
    for path in sorted(package.glob("*.py")):
        tree = ast.parse(path.read_text(), str(path))
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level > 1:
                    offenders.append(f"{path.name}:{node.lineno} relative import beyond vrpn")
                names = [node.module or ""] if node.level == 0 else []
            else:
                continue
            offenders += [
                f"{path.name}:{node.lineno} imports {n}"
                for n in names
                if n.split(".")[0] == "gadgetctl"
            ]
            offenders += [
                f"{path.name}:{node.lineno} imports {n}"
                for n in names
                if n.split(".")[0] in {"typer", "rich", "numpy", "lxml"}
            ]
    assert package.name == "vrpn" and len(list(package.glob("*.py"))) >= 7
    assert offenders == []


def test_bulk_reports_are_framed_apart_and_checked_as_the_cpp_remote_does():
    pose = wire.pack_message(3, 1, codecs.encode_pose(0, (1.0, 2.0, 3.0)), 5.0)
    negative = wire.pack_message(3, 1, struct.pack(">ii3d4d", -1, 0, 0, 0, 0, 0, 0, 0, 1), 5.0)
    short = wire.pack_message(3, 1, b"\0" * 40, 5.0)
    other = wire.pack_message(4, 1, b"abc", 5.0)
    described = wire.pack_description(wire.TYPE_DESCRIPTION, 3, "something else")
    bulk = {(1, 3): (("Tracker0", codecs.TRACKER_POS_QUAT), 88)}
    data = pose * 3 + negative + short + other + pose + described + pose
    end, messages, found = wire.split_messages(data, 0, len(data), 1.0, bulk)
    assert end == len(data)
    poses = found[("Tracker0", codecs.TRACKER_POS_QUAT)]
    assert poses == [0, 88, 176, 88 * 4 + 64 + 32]  # the run, then the lone one
    # a negative sensor and a wrong length go the usual way (where they drop the connection,
    # as in the C++ remote); after a description nothing more is set apart
    assert [m.type_id for m in messages] == [3, 3, 4, wire.TYPE_DESCRIPTION, 3]
    assert len(messages[0].payload) == 64 and len(messages[1].payload) == 40


def test_alternating_bulk_reports_are_each_set_apart():
    # a C++ tracker sends pose, velocity and acceleration of each sensor in turn
    pose = wire.pack_message(3, 1, codecs.encode_pose(0, (1.0, 2.0, 3.0)), 5.0)
    velocity = wire.pack_message(4, 1, codecs.encode_velocity(0, (0.0, 0.0, 0.0)), 5.0)
    bulk = {
        (1, 3): (("Tracker0", codecs.TRACKER_POS_QUAT), 88),
        (1, 4): (("Tracker0", codecs.TRACKER_VELOCITY), 96),
    }
    data = (pose + velocity) * 3 + pose * 2
    end, messages, found = wire.split_messages(data, 0, len(data), 1.0, bulk)
    assert end == len(data) and messages == []
    assert found[("Tracker0", codecs.TRACKER_POS_QUAT)] == [0, 184, 368, 552, 640]
    assert found[("Tracker0", codecs.TRACKER_VELOCITY)] == [88, 272, 456]
