"""Batched framing (gadgetctl.serve.framing) gives the bytes of one pack_message per message,
and a server's broadcast of a batch drops whole messages for a full client, counted."""

from __future__ import annotations

import socket

import numpy as np
import pytest
from vrpn_peers import Broadcasts

from gadgetctl.serve.framing import (
    CHANGE_SIZE,
    POSE_MESSAGE,
    POSE_SIZE,
    analog_size,
    fill_poses,
    pack_analogs,
    pack_button_changes,
    pack_poses,
)
from gadgetctl.vrpn import codecs
from gadgetctl.vrpn.endpoint import Endpoint
from gadgetctl.vrpn.wire import MAX_DATAGRAM, decode_datagram, pack_message


def times(n: int) -> np.ndarray:
    return 1795425140.0 + np.arange(n) * 0.0013 + 0.9999996  # includes a microsecond carry


def test_poses_match_one_message_per_sensor():
    rng = np.random.default_rng(3)
    t = times(5)
    positions, quats = rng.normal(size=(5, 3, 3)), rng.normal(size=(5, 3, 4))
    expected = b"".join(
        pack_message(7, 2, codecs.encode_pose(s, tuple(positions[i, s]), tuple(quats[i, s])), t[i])
        for i in range(5)
        for s in range(3)
    )
    data = pack_poses(
        2,
        7,
        np.repeat(t, 3),
        np.tile(np.arange(3), 5),
        positions.reshape(-1, 3),
        quats.reshape(-1, 4),
    )
    assert data == expected and len(data) == 15 * POSE_SIZE


def test_poses_framed_in_place_into_a_larger_buffer_are_the_same_messages():
    """fill_poses (what serve's outlet frames a row with, in place) writes pack_poses'
    messages into a view of a larger buffer, and leaves the rest of it alone; one sensor
    number for every row is the same as an array of it."""
    rng = np.random.default_rng(5)
    t = times(6)
    positions, quats = rng.normal(size=(6, 3)), rng.normal(size=(6, 4))
    expected = b"".join(
        pack_message(7, 2, codecs.encode_pose(0, tuple(positions[i]), tuple(quats[i])), t[i])
        for i in range(6)
    )
    assert pack_poses(2, 7, t, 0, positions, quats) == expected
    memory = bytearray(b"\xab" * 10 * POSE_SIZE)
    buffer = np.frombuffer(memory, dtype=np.dtype((np.void, POSE_SIZE)))
    fill_poses(buffer[3:9].view(POSE_MESSAGE), 2, 7, t, 0, positions, quats)
    assert bytes(memory[3 * POSE_SIZE : 9 * POSE_SIZE]) == expected
    assert memory[: 3 * POSE_SIZE] + memory[9 * POSE_SIZE :] == b"\xab" * 4 * POSE_SIZE


def test_analogs_and_button_changes_match():
    t = times(4)
    values = np.arange(12, dtype=float).reshape(4, 3) / 7
    assert pack_analogs(1, 9, t, values) == b"".join(
        pack_message(9, 1, codecs.encode_analog(list(values[i])), t[i]) for i in range(4)
    )
    assert len(pack_analogs(1, 9, t, values)) == 4 * analog_size(3)
    buttons, states = np.array([0, 3, 3, 255]), np.array([1, 1, 0, 5])
    assert pack_button_changes(0, 4, t, buttons, states) == b"".join(
        pack_message(4, 0, codecs.encode_button_change(int(b), int(s)), t[i])
        for i, (b, s) in enumerate(zip(buttons, states, strict=True))
    )
    assert CHANGE_SIZE == 32


def test_a_full_buffer_drops_whole_messages_and_udp_datagrams_hold_whole_messages():
    a, b = socket.socketpair()
    try:
        endpoint = Endpoint(a, out_limit=24 + 10 * POSE_SIZE)  # the cookie is queued first
        data = pack_poses(1, 4, times(16), np.zeros(16), np.zeros((16, 3)), np.zeros((16, 4)))
        assert endpoint.queue_batch(data, POSE_SIZE, reliable=True) == 10
        assert endpoint.dropped == 6 and len(endpoint.out) == 24 + 10 * POSE_SIZE
        assert endpoint.queue_batch(data, POSE_SIZE, reliable=True) == 0 and endpoint.dropped == 22
        receiver = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        receiver.bind(("127.0.0.1", 0))
        receiver.settimeout(5)
        udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        udp.connect(receiver.getsockname())
        endpoint.udp = udp
        assert endpoint.queue_batch(data, POSE_SIZE, reliable=False) == 16
        endpoint.flush()
        got = 0
        while got < 16:
            datagram = receiver.recv(65536)
            assert len(datagram) <= MAX_DATAGRAM and len(datagram) % POSE_SIZE == 0
            got += len(decode_datagram(datagram))
        assert got == 16
        receiver.close()
    finally:
        a.close()
        b.close()


def test_a_written_batch_goes_out_whole_then_queues_the_rest_and_drops_whole_messages():
    """``queue_batch(write=True)`` sends from the shared bytes when nothing waits: a reader
    gets them all; against a peer that stopped reading, the message the socket took in part
    is finished from the buffer and only whole messages beyond the limit are dropped."""
    a, b = socket.socketpair()
    try:
        a.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 4096)
        endpoint = Endpoint(a, out_limit=8 * POSE_SIZE)
        endpoint.flush()  # the cookie
        b.recv(64)
        data = pack_poses(1, 4, times(3), np.zeros(3), np.zeros((3, 3)), np.zeros((3, 4)))
        assert endpoint.queue_batch(data, POSE_SIZE, write=True) == 3
        assert not endpoint.out and b.recv(4096) == data
        big = pack_poses(
            1, 4, times(2000), np.zeros(2000), np.zeros((2000, 3)), np.zeros((2000, 4))
        )
        taken = endpoint.queue_batch(big, POSE_SIZE, write=True)
        assert endpoint.dropped == 2000 - taken and 0 < endpoint.dropped < 2000
        assert len(endpoint.out) <= 8 * POSE_SIZE + POSE_SIZE
        b.setblocking(False)
        received = bytearray()
        while len(received) < taken * POSE_SIZE:
            try:
                received += b.recv(1 << 16)
            except BlockingIOError:
                endpoint.flush()
        assert bytes(received) == big[: taken * POSE_SIZE] and not endpoint.out
    finally:
        a.close()
        b.close()


def test_windows_of_arrays_computed_ahead_give_the_bytes_of_their_batches():
    """A device publishing windows of a block (waveform) is framed a stretch ahead and cut
    per frame: every frame's bytes are those of framing its window's samples there and then,
    for one sensor and several, across the end of a stretch and a new block, mixed with a
    sender whose windows are not float64 and one sent as a plain batch."""
    from gadgetctl.serve.catalog import Role, ServedElement
    from gadgetctl.serve.outlet import FRAME_AHEAD, VrpnOutlet

    rng = np.random.default_rng(5)

    def block(n: int, sensors: int, dtype=np.float64) -> tuple[np.ndarray, np.ndarray]:
        matrices = np.tile(np.eye(4), (n, sensors, 1, 1))
        angle = rng.uniform(0, np.pi, size=(n, sensors))
        matrices[..., 0, 0] = matrices[..., 2, 2] = np.cos(angle)
        matrices[..., 0, 2], matrices[..., 2, 0] = np.sin(angle), -np.sin(angle)
        matrices[..., :3, 3] = rng.normal(size=(n, sensors, 3))
        return 100.0 + np.arange(n) * 0.001, matrices.astype(dtype)

    catalog = [
        ServedElement(name, name, "device", "waveform_device", (Role.TRACKER,))
        for name in ("One", "Three", "Single", "Batch")
    ]
    windowed, batched = Broadcasts(), Broadcasts()
    outlets = [VrpnOutlet(windowed, catalog), VrpnOutlet(batched, catalog)]
    for outlet in outlets:
        outlet.audience = True
    blocks = {
        "One": [block(700, 1), block(50, 1)],
        "Three": [block(400, 3)],
        "Single": [block(300, 2, np.float32)],
    }
    offset = 1.7e9
    position = {name: (0, 0) for name in blocks}  # (block, next sample)
    for frame in range(260):
        windows, plain = [], []
        for name, blocks_of in blocks.items():
            which, start = position[name]
            times, matrices = blocks_of[which % len(blocks_of)]
            stop = min(len(times), start + 1 + frame % 4)
            windows.append((name, times, matrices, start, stop))
            plain.append((name, times[start:stop], np.asarray(matrices[start:stop], np.float64)))
            position[name] = (which + 1, 0) if stop == len(times) else (which, stop)
        extra = ("Batch", *block(2, 1))
        outlets[0].tracker_windows(windows, offset)
        outlets[0].trackers([extra], offset)
        outlets[1].trackers([*plain, extra], offset)
        for outlet in outlets:
            outlet.end_frame()
            outlet.audience = True
        assert windowed.sent[-1] == batched.sent[-1], f"frame {frame}"
    assert outlets[0].messages == outlets[1].messages
    assert FRAME_AHEAD < 700  # the stretches did run out within the first block


@pytest.mark.parametrize("upcoming", [False, True], ids=["framed-at-the-frame", "framed-ahead"])
@pytest.mark.parametrize("count", [4, 18], ids=["few-slots-one-by-one", "many-slots-with-numpy"])
def test_shared_windows_give_the_bytes_of_their_batches(upcoming, count):
    """A frame group's shared windows (every slot's window at once) frame to the same bytes
    as the same samples handed over as plain batches: across rows running out, new arrays
    (generations), windows of several samples, several sensors, a slot not in the frame,
    and a slot whose arrays are not float64 (framed with the frame's other trackers); with
    the arrays to come offered ahead, their rows are framed between frames (prepare); for a
    few slots (cut slot by slot) as for more (one numpy gather)."""
    from gadgetctl.input.kinds import DeviceKind
    from gadgetctl.input.samples import FEW_SLOTS, SampleStore, SharedWindows

    assert (count <= FEW_SLOTS) == (count == 4)
    from gadgetctl.serve.catalog import Role, ServedElement
    from gadgetctl.serve.outlet import FRAME_AHEAD, VrpnOutlet

    rng = np.random.default_rng(11)

    def block(n: int, sensors: int, dtype=np.float64):
        matrices = np.tile(np.eye(4), (n, sensors, 1, 1))
        angle = rng.uniform(0, np.pi, size=(n, sensors))
        matrices[..., 0, 0] = matrices[..., 1, 1] = np.cos(angle)
        matrices[..., 0, 1], matrices[..., 1, 0] = -np.sin(angle), np.sin(angle)
        matrices[..., :3, 3] = rng.normal(size=(n, sensors, 3))
        return 50.0 + np.arange(n) * 0.001, ((DeviceKind.POSITION, matrices.astype(dtype)),)

    names = [chr(ord("A") + i) for i in range(count)]
    sensors = {name: (1, 3, 1, 2)[i % 4] for i, name in enumerate(names)}
    dtypes = {names[-1]: np.float32}  # last: framed after the others, as in the plain batches
    catalog = [ServedElement(n, n, "device", "waveform_device", (Role.TRACKER,)) for n in names]
    shared_server, batched_server = Broadcasts(), Broadcasts()
    shared_outlet, batched_outlet = (
        VrpnOutlet(shared_server, catalog),
        VrpnOutlet(batched_server, catalog),
    )
    windows = SharedWindows([SampleStore([DeviceKind.POSITION]) for _ in names])
    arrays = {n: block(300, sensors[n], dtypes.get(n, np.float64)) for n in names}
    position = dict.fromkeys(names, 0)
    following = {}  # the next arrays of a slot near its end, offered ahead
    spares = []
    take_spare = shared_outlet._take_spare
    shared_outlet._take_spare = lambda *args: spares.append(take_spare(*args)) or spares[-1]
    offset = 1.7e9
    for frame in range(300):
        shared_outlet.audience = batched_outlet.audience = True
        slots, starts, stops, plain = [], [], [], []
        for slot, name in enumerate(names):
            if (name == "C" and frame % 5 == 0) or (name in dtypes and frame % 3):
                continue  # not in this frame
            times, items = arrays[name]
            start = position[name]
            stop = min(len(times), start + 1 + (frame + slot) % 3)
            windows.set_arrays(slot, times, items)
            slots.append(slot)
            starts.append(start)
            stops.append(stop)
            matrices = items[0][1]
            plain.append((name, times[start:stop], np.asarray(matrices[start:stop], np.float64)))
            if stop == len(times):
                arrays[name] = following.pop(name, None) or block(
                    300, sensors[name], dtypes.get(name, np.float64)
                )
                position[name] = 0
            else:
                position[name] = stop
                if upcoming and len(times) - stop < 40 and name not in following:
                    following[name] = block(300, sensors[name], dtypes.get(name, np.float64))
                    windows.set_upcoming(slot, *following[name])
        picked = np.array(slots)
        windows.publish(float(frame), picked, np.array(starts), np.array(stops))
        shared_outlet.tracker_shared(
            windows, picked, np.array([names[s] for s in slots], dtype=object), offset
        )
        batched_outlet.trackers(plain, offset)
        shared_outlet.end_frame()
        batched_outlet.end_frame()
        shared_outlet.audience = True
        shared_outlet.prepare()
        # the same bytes (the float32 slot, last, is framed with the frame's other trackers)
        assert shared_server.sent[-1] == batched_server.sent[-1], f"frame {frame}"
    assert shared_outlet.messages == batched_outlet.messages
    assert FRAME_AHEAD < 300 * 3  # rows ran out within an array
    assert any(spares) == upcoming  # rows framed ahead were used when arrays were offered


def test_shared_rotations_are_converted_once_with_the_same_bytes():
    """Issue 27 goal 2: the quaternions of read-only matrices devices share (a waveform
    configuration's values) are converted once for every stretch cut from them, with the
    bytes of a conversion of the stretch itself; other arrays are converted as before."""
    from gadgetctl.input.transforms import quaternions_xyzw
    from gadgetctl.serve.outlet import _SharedRotations

    rng = np.random.default_rng(3)
    angles = rng.uniform(-np.pi, np.pi, size=(300, 2))  # rotations of every size: all branches
    owner = np.zeros((300, 2, 4, 4))
    owner[:] = np.eye(4)
    c, s = np.cos(angles), np.sin(angles)
    owner[:, :, 0, 0], owner[:, :, 0, 1], owner[:, :, 1, 0], owner[:, :, 1, 1] = c, -s, s, c
    owner[:, :, :3, 3] = rng.normal(size=(300, 2, 3))
    owner.flags.writeable = False
    rotations = _SharedRotations()
    for start, stop in ((0, 300), (17, 18), (40, 299), (123, 260)):
        flat = owner[start:stop].reshape(-1, 4, 4)
        assert rotations.quaternions(flat).tobytes() == quaternions_xyzw(flat).tobytes()
    assert len(rotations._kept) == 1  # one conversion for every stretch
    mine = np.array(owner)  # writable: converted on its own, not kept
    flat = mine[5:50].reshape(-1, 4, 4)
    assert rotations.quaternions(flat).tobytes() == quaternions_xyzw(flat).tobytes()
    assert len(rotations._kept) == 1
