"""The :class:`~gadgetctl.serve.feed.Outlet` that frames reports as VRPN messages and hands
them to the server, which queues them for every connected client (each with its own
bounded buffer). Every message is framed once, whatever the number of clients.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np

from gadgetctl.input.samples import FEW_SLOTS
from gadgetctl.input.transforms import quaternions_xyzw
from gadgetctl.serve.catalog import Role, ServedElement, served_positions
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

#: Messages of a window's arrays framed at once (the window and the samples after it, up to
#: the end of the arrays): a waveform device's block of 500 samples of one sensor is framed
#: in one go, not one frame's sample at a time.
FRAME_AHEAD = 512

#: The message types each VRPN device class registers (the C++ classes register the same).
ROLE_TYPES: dict[Role, tuple[str, ...]] = {
    Role.TRACKER: codecs.TRACKER_TYPES,
    Role.BUTTON: codecs.BUTTON_TYPES,
    Role.ANALOG: (codecs.ANALOG_CHANNEL,),
    Role.TEXT: (),
}


_RECORD = np.dtype((np.void, POSE_SIZE))


class _SharedStretches:
    """What a :class:`VrpnOutlet` framed ahead for the slots of one
    :class:`~gadgetctl.input.samples.SharedWindows`: per slot a row of :data:`FRAME_AHEAD`
    framed messages (samples ``first`` .. ``last - 1`` of the slot's arrays of generation
    ``generation``, ``sensors`` messages each), so that a frame's messages of every slot are
    cut from the rows in one numpy gather; and a spare row per slot, framed between frames
    from the arrays the slot will use next (``spare_for``: their timestamps array)."""

    def __init__(self, windows: object, slots: int) -> None:
        self.windows = windows
        self.records = np.zeros(2 * slots * FRAME_AHEAD, dtype=_RECORD)
        self.row = np.arange(slots, dtype=np.int64) * 2  # each slot's current row
        self.generation = np.full(slots, -1, dtype=np.int64)
        self.first = np.zeros(slots, dtype=np.int64)
        self.last = np.zeros(slots, dtype=np.int64)
        self.sensors = np.ones(slots, dtype=np.int64)
        #: Per slot, where sample 0 of its arrays would begin in :attr:`records` (its row's
        #: start less ``first * sensors``): a window's first message is ``origin + start *
        #: sensors``. Set with ``row``, ``first`` and ``sensors`` (:meth:`place`).
        self.origin = self.row * FRAME_AHEAD
        self.narrow = True  # every slot's rows hold one sensor
        self.offset = 0.0
        self.names: list[str | None] = [None] * slots  # the sender each slot is served as
        self.upcoming_seen = np.zeros(slots, dtype=np.int64)
        self.upcoming_serial = -1  # the windows' upcoming_serial when last looked at
        self.spare_for: list[object | None] = [None] * slots
        self.spare = np.zeros((slots, 3), dtype=np.int64)  # first, last, sensors
        self.spare_offset = np.zeros(slots)

    def place(self, slot: int, first: int, last: int, sensors: int) -> None:
        """Slot ``slot``'s row (``row[slot]``) holds samples ``first`` .. ``last - 1`` of its
        arrays, ``sensors`` messages each."""
        self.first[slot], self.last[slot], self.sensors[slot] = first, last, sensors
        self.origin[slot] = int(self.row[slot]) * FRAME_AHEAD - first * sensors


class _SharedRotations:
    """The quaternions of read-only arrays of matrices that devices share (a waveform device
    configuration's values, :class:`~gadgetctl.input.waveform._SharedSignals`), converted
    once for every device whose windows are cut from them: at most :data:`KEPT` arrays of
    at most :data:`MOST` matrices each."""

    KEPT = 8
    MOST = 1 << 16

    def __init__(self) -> None:
        self._kept: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def quaternions(self, flat: np.ndarray) -> np.ndarray:
        """:func:`quaternions_xyzw` of ``flat`` (n, 4, 4), from the shared conversion when
        ``flat`` is a stretch of a read-only owner's matrices."""
        owner = flat.base
        if (
            not isinstance(owner, np.ndarray)
            or owner.flags.writeable
            or owner.dtype != np.float64
            or owner.size > 16 * self.MOST
            or owner.shape[-2:] != (4, 4)
            or not owner.flags.c_contiguous
            or not flat.flags.c_contiguous
        ):
            return quaternions_xyzw(flat)
        skip, rest = divmod(flat.ctypes.data - owner.ctypes.data, 128)
        if rest or skip < 0 or skip + len(flat) > owner.size // 16:
            return quaternions_xyzw(flat)
        kept = self._kept.get(id(owner))
        if kept is None or kept[0] is not owner:
            if len(self._kept) >= self.KEPT:
                self._kept.pop(next(iter(self._kept)))
            kept = self._kept[id(owner)] = (owner, quaternions_xyzw(owner.reshape(-1, 4, 4)))
        return kept[1][skip : skip + len(flat)]


def _framable(matrices: object) -> bool:
    """Whether ``matrices`` is a float64 array of (samples, sensors, 4, 4), sensors > 0."""
    shape = getattr(matrices, "shape", None)
    return (
        shape is not None
        and len(shape) == 4
        and shape[1] > 0
        and shape[2:] == (4, 4)
        and matrices.dtype == np.float64  # type: ignore[attr-defined]
    )


class VrpnOutlet:
    """Registers every served name and the types of its device classes with ``server``,
    then frames reports for it."""

    def __init__(self, server, catalog: Iterable[ServedElement]) -> None:
        self.server = server
        self.senders: dict[str, int] = {}
        self.types: dict[str, int] = {}
        for entry in catalog:
            if entry.roles:
                self.senders[entry.vrpn_name] = server.register_sender(entry.vrpn_name)
        # every type of every device class, so that a kind that starts late is served too
        for name in (*codecs.BASE_TYPES, *(t for types in ROLE_TYPES.values() for t in types)):
            self.types[name] = server.register_type(name)
        self._pose = self.types.get(codecs.TRACKER_POS_QUAT, -1)
        self._change = self.types.get(codecs.BUTTON_CHANGE, -1)
        self._states = self.types.get(codecs.BUTTON_STATES, -1)
        self._analog = self.types.get(codecs.ANALOG_CHANNEL, -1)
        self._text = self.types[codecs.TEXT_MESSAGE]
        self.button_states: dict[str, np.ndarray] = {}
        self.messages = 0
        self._poses: list[tuple[int, np.ndarray, np.ndarray]] = []  # times: Unix seconds
        # batches whose times are on the input manager's clock, and the offset to Unix time
        self._clock_poses: list[tuple[int, np.ndarray, np.ndarray]] = []
        self._clock_offset = 0.0
        # per sender: a stretch of a window's arrays framed ahead, (matrices, first, last,
        # bytes, bytes per sample, offset), and this frame's pieces cut from such stretches
        self._framed: dict[int, tuple[np.ndarray, int, int, memoryview, int, float]] = {}
        self._pieces: list[memoryview | bytes] = []
        self._shared: dict[int, _SharedStretches] = {}  # by id of the shared windows
        self._rotations = _SharedRotations()
        # whether a client is connected (refreshed every frame and on connection): with
        # nobody to send to, reports are not framed at all
        self.audience = False

    # -- Outlet -------------------------------------------------------------------------

    def tracker(self, sender: str, times: np.ndarray, matrices: np.ndarray) -> None:
        # kept until the end of the frame: every tracker of a frame is framed in one go
        if self.audience:
            self._poses.append((self.senders[sender], times, matrices))

    def trackers(self, batches: list[tuple[str, np.ndarray, np.ndarray]], offset: float) -> None:
        """A frame's tracker batches, times on the input manager's clock plus ``offset``."""
        if self.audience:
            senders = self.senders
            self._clock_poses.extend(
                (senders[name], times, matrices) for name, times, matrices in batches
            )
            self._clock_offset = offset

    def tracker_windows(
        self, windows: list[tuple[str, np.ndarray, np.ndarray, int, int]], offset: float
    ) -> None:
        """A frame's windows of arrays computed ahead (times on the input manager's clock plus
        ``offset``), each cut from bytes framed earlier for a stretch of the same arrays; the
        senders whose stretch ran out (a few per frame at most) are framed again together,
        one numpy pass for all of them, :data:`FRAME_AHEAD` messages ahead."""
        if not self.audience:
            return
        framed = self._framed
        pieces = self._pieces
        senders = self.senders
        refill: list[tuple[int, int, np.ndarray, np.ndarray, int, int]] = []
        count = 0
        for name, times, matrices, start, stop in windows:
            sender = senders[name]
            stretch = framed.get(sender)
            if (
                stretch is None
                or stretch[0] is not matrices
                or start < stretch[1]
                or stop > stretch[2]
                or stretch[5] != offset
            ):
                if not _framable(matrices):  # as Outlet.tracker would take it, or not at all
                    self._other_window(sender, times, matrices, start, stop, offset)
                    continue
                refill.append((len(pieces), sender, times, matrices, start, stop))
                pieces.append(memoryview(b""))  # its place, cut once framed
                continue
            first, step = stretch[1], stretch[4]
            pieces.append(stretch[3][(start - first) * step : (stop - first) * step])
            count += (stop - start) * matrices.shape[1]
        if refill:
            count += self._frame_ahead(refill, offset)
        self.messages += count

    def tracker_shared(
        self, windows, slots: np.ndarray, senders: np.ndarray, offset: float
    ) -> None:
        """A frame's tracker windows of a frame group's shared windows
        (:class:`~gadgetctl.input.samples.SharedWindows`): ``slots`` (fresh, each with position
        data only) served as ``senders`` (VRPN sender names), times on the input manager's
        clock plus ``offset``. The slots' messages are cut from rows framed ahead
        (:data:`FRAME_AHEAD` messages a slot, framed again when a window leaves its row, or
        taken from the spare row :meth:`prepare` framed), in one numpy gather for all of
        them, in the order of ``slots``."""
        if not self.audience or not len(slots):
            return
        state = self._shared.get(id(windows))
        if state is None or state.windows is not windows:
            state = self._shared[id(windows)] = _SharedStretches(windows, len(windows.stores))
        if len(slots) <= FEW_SLOTS and state.offset == offset and self._cut_few(state, slots):
            return
        taken = windows.select(slots)  # a slice when they are all the slots
        starts = windows.starts[taken]
        stops = windows.stops[taken]
        stale = state.generation[taken] != windows.generation[taken]
        stale |= starts < state.first[taken]
        stale |= stops > state.last[taken]
        if state.offset != offset:
            stale[:] = True
            state.offset = offset
        # (bool arrays counted with count_nonzero: all() and any() cost a few times more)
        if np.count_nonzero(stale):
            keep = np.ones(len(slots), dtype=bool)
            for index in stale.nonzero()[0].tolist():
                slot, start, stop = int(slots[index]), int(starts[index]), int(stops[index])
                state.names[slot] = senders[index]
                if not self._take_spare(state, slot, start, stop):
                    keep[index] = self._frame_row(state, slot, start, stop)
            state.narrow = not np.count_nonzero(state.sensors != 1)
            if np.count_nonzero(keep) != len(keep):
                slots, starts, stops = slots[keep], starts[keep], stops[keep]
                taken = slots
                if not len(slots):
                    return
        if state.narrow:
            begins = state.origin[taken] + starts
            counts = stops - starts
        else:
            sensors = state.sensors[taken]
            begins = state.origin[taken] + starts * sensors
            counts = (stops - starts) * sensors
        if np.count_nonzero(counts == 1) == len(counts):  # a message each: the usual frame
            picks = begins
        else:
            picks = np.repeat(begins - (np.cumsum(counts) - counts), counts) + np.arange(
                int(np.add.reduce(counts))
            )
        self._pieces.append(state.records[picks].tobytes())
        self.messages += len(picks)

    def _cut_few(self, state: _SharedStretches, slots: np.ndarray) -> bool:
        """:meth:`tracker_shared` for a few slots whose windows all lie in their rows, slot by
        slot with Python numbers: each slot's messages are one slice of its row (numpy's
        fixed cost per call is most of the work for a few slots). False, having done
        nothing, when some slot's row must be framed again."""
        windows = state.windows
        starts, stops, generation = windows.starts, windows.stops, windows.generation
        records, pieces, count = state.records, [], 0
        for slot in slots.tolist():
            start, stop, first = int(starts[slot]), int(stops[slot]), int(state.first[slot])
            if (
                state.generation[slot] != generation[slot]
                or start < first
                or stop > state.last[slot]
            ):
                return False
            sensors = int(state.sensors[slot])
            begin = int(state.row[slot]) * FRAME_AHEAD + (start - first) * sensors
            size = (stop - start) * sensors
            pieces.append(records[begin : begin + size].tobytes())
            count += size
        self._pieces += pieces
        self.messages += count
        return True

    def _take_spare(self, state: _SharedStretches, slot: int, start: int, stop: int) -> bool:
        """Make slot ``slot``'s spare row its row when it was framed from the slot's current
        arrays and holds the window ``start`` .. ``stop``."""
        windows = state.windows
        first, last, sensors = state.spare[slot].tolist()
        if (
            state.spare_for[slot] is not windows.arrays[slot][0]
            or state.spare_offset[slot] != state.offset
            or not first <= start < stop <= last
        ):
            return False
        state.row[slot] ^= 1
        state.place(slot, first, last, sensors)
        state.generation[slot] = windows.generation[slot]
        state.spare_for[slot] = None
        return True

    def prepare(self, limit: int = 1) -> None:
        """Between frames: frame the spare rows of (at most ``limit``) served slots whose
        arrays to come became known (:attr:`SharedWindows.upcoming`), so that the frame that
        moves to them finds their messages framed (one a frame keeps up with a hundred
        1 kHz devices' half-second blocks, known a tenth of a second ahead)."""
        if not self.audience:
            return
        for state in self._shared.values():
            windows = state.windows
            serial = windows.upcoming_serial
            if state.upcoming_serial == serial:
                continue  # no slot's upcoming arrays were set since every one was looked at
            stale = np.flatnonzero(windows.upcoming_generation != state.upcoming_seen)
            if len(stale) <= limit:
                state.upcoming_serial = serial  # all of them are looked at now
            for slot in stale[:limit].tolist():
                state.upcoming_seen[slot] = windows.upcoming_generation[slot]
                upcoming, name = windows.upcoming[slot], state.names[slot]
                if upcoming is None or name is None:
                    continue
                times, items = upcoming
                matrices = served_positions(items)
                if _framable(matrices):
                    first, last, sensors = self._frame_into(
                        state, int(state.row[slot] ^ 1), name, times, matrices, 0
                    )
                    state.spare[slot] = first, last, sensors
                    state.spare_for[slot] = times
                    state.spare_offset[slot] = state.offset
                limit -= 1
            if limit <= 0:
                return

    def _frame_row(self, state: _SharedStretches, slot: int, start: int, stop: int) -> bool:
        """Frame slot ``slot``'s row from ``start`` (its window and what follows it in its
        arrays, up to :data:`FRAME_AHEAD` messages); False when the window cannot be cut from
        a row (framed with the frame's other trackers instead, or ignored, as
        :meth:`Outlet.tracker` would)."""
        windows = state.windows
        times, items = windows.arrays[slot]
        matrices = served_positions(items)
        name = state.names[slot]
        if not _framable(matrices) or (stop - start) * matrices.shape[1] > FRAME_AHEAD:
            if matrices is not None:
                self._other_window(self.senders[name], times, matrices, start, stop, state.offset)
            state.generation[slot] = -1
            return False
        first, last, sensors = self._frame_into(
            state, int(state.row[slot]), name, times, matrices, start
        )
        state.generation[slot] = windows.generation[slot]
        state.place(slot, first, last, sensors)
        return True

    def _frame_into(
        self, state: _SharedStretches, row: int, name: str, times, matrices, start: int
    ) -> tuple[int, int, int]:
        """Frame samples ``start`` .. (up to :data:`FRAME_AHEAD` messages) of ``times`` and
        ``matrices`` as ``name``'s into row ``row``; returns (first, last, sensors)."""
        sensors = matrices.shape[1]
        last = min(len(matrices), start + FRAME_AHEAD // sensors)
        flat = matrices[start:last].reshape(-1, 4, 4)
        times = np.asarray(times[start:last], dtype=np.float64) + state.offset
        base = row * FRAME_AHEAD
        fill_poses(  # framed in place, in the row
            state.records[base : base + len(flat)].view(POSE_MESSAGE),
            self.senders[name],
            self._pose,
            np.repeat(times, sensors) if sensors > 1 else times,
            np.tile(np.arange(sensors), last - start) if sensors > 1 else 0,
            flat[:, :3, 3],
            self._rotations.quaternions(flat),
        )
        return start, last, sensors

    def _frame_ahead(
        self, refill: list[tuple[int, int, np.ndarray, np.ndarray, int, int]], offset: float
    ) -> int:
        """Frame, in one pass, each window of ``refill`` and the samples after it in its
        arrays (up to :data:`FRAME_AHEAD` messages in all, to the end of the arrays); keep
        each sender's stretch and put its window in its place among the frame's pieces.
        Returns the messages of the windows."""
        spans = []
        for _, sender, _times, matrices, start, stop in refill:
            sensors = matrices.shape[1]
            last = min(len(matrices), max(stop, start + FRAME_AHEAD // sensors))
            spans.append((sender, start, last, sensors))
        stamps = np.concatenate(
            [
                times[start:last]
                for (_, _, times, _, _, _), (_, start, last, _) in zip(refill, spans, strict=True)
            ]
        )
        stamps += offset
        flat = np.concatenate(
            [
                m[start:last].reshape(-1, 4, 4)
                for (_, _, _, m, _, _), (_, start, last, _) in zip(refill, spans, strict=True)
            ]
        )
        sizes = np.array([(last - start) * sensors for _, start, last, sensors in spans])
        widths = np.array([sensors for *_, sensors in spans])
        senders = np.repeat(np.array([sender for sender, *_ in spans], dtype=np.int32), sizes)
        times = np.repeat(stamps, np.repeat(widths, sizes // widths))
        starts = np.repeat(np.cumsum(sizes) - sizes, sizes)
        sensor_numbers = (np.arange(len(flat)) - starts) % np.repeat(widths, sizes)
        data = memoryview(
            pack_poses(
                senders, self._pose, times, sensor_numbers, flat[:, :3, 3], quaternions_xyzw(flat)
            )
        )
        framed, pieces = self._framed, self._pieces
        at = 0
        count = 0
        for (place, sender, _, matrices, start, stop), (_, first, last, sensors) in zip(
            refill, spans, strict=True
        ):
            size = (last - first) * sensors * POSE_SIZE
            step = sensors * POSE_SIZE
            stretch = framed[sender] = (matrices, first, last, data[at : at + size], step, offset)
            at += size
            pieces[place] = stretch[3][: (stop - first) * step]
            count += (stop - start) * sensors
        return count

    def _other_window(
        self, sender: int, times: object, matrices: object, start: int, stop: int, offset: float
    ) -> None:
        """A window whose arrays are not float64 (samples, sensors, 4, 4): framed with the
        frame's other tracker batches when it converts to that shape, else ignored."""
        values = np.asarray(matrices[start:stop], dtype=np.float64)
        if values.ndim == 4 and values.shape[1] and values.shape[2:] == (4, 4):
            self._clock_poses.append(
                (sender, np.asarray(times[start:stop], dtype=np.float64), values)
            )
            self._clock_offset = offset

    def buttons(
        self, sender: str, changes: Sequence[tuple[float, int, int]], states: np.ndarray
    ) -> None:
        self.button_states[sender] = np.array(states, copy=True)  # for clients to come, too
        if not self.audience:
            return
        times, buttons, values = zip(*changes, strict=True)
        data = pack_button_changes(
            self.senders[sender],
            self._change,
            np.asarray(times),
            np.asarray(buttons),
            np.asarray(values),
        )
        self.messages += len(changes)
        self.server.broadcast(data, CHANGE_SIZE, reliable=True)

    def analog(self, sender: str, times: np.ndarray, values: np.ndarray) -> None:
        if not self.audience:
            return
        values = values[:, : codecs.MAX_CHANNELS]
        data = pack_analogs(self.senders[sender], self._analog, times, values)
        self.messages += values.shape[0]
        self.server.broadcast(data, analog_size(values.shape[1]), reliable=False)

    def text(self, sender: str, moment: float, level: int, text: str) -> None:
        if not self.audience:
            return
        self.messages += 1
        self.server.send(
            self.senders[sender],
            self._text,
            codecs.encode_text(text, 0, level),
            timestamp=moment,
            reliable=True,
            flush=False,
        )

    def end_frame(self) -> None:
        """Frame and queue the frame's tracker reports: the pieces cut from stretches framed
        ahead, then one conversion to quaternions and one framing for all the others, however
        many devices and sensors; queued as one bytes object for every client."""
        pieces = self._pieces
        if self._poses or self._clock_poses:
            pieces.append(self._frame_poses())
        if pieces:
            self._pieces = []
            self.server.broadcast(b"".join(pieces), POSE_SIZE, reliable=False, flush=True)
        self.audience = self.server.audience

    def _frame_poses(self) -> bytes:
        clock, self._clock_poses = self._clock_poses, []
        wall, self._poses = self._poses, []
        pending = (clock + wall if wall else clock) if clock else wall
        # every batch's times in one array (a new one: the offset is added in place, once)
        stamps = np.concatenate([times for _, times, _ in pending])
        if clock:
            if wall:
                stamps[: sum(len(times) for _, times, _ in clock)] += self._clock_offset
            else:
                stamps += self._clock_offset
        # (samples, sensors) of each batch read as Python ints: one small array per list,
        # not an array built from a hundred tuples
        ids: list[int] = []
        counts: list[int] = []
        widths: list[int] = []
        for sender, _, matrices in pending:
            ids.append(sender)
            counts.append(matrices.shape[0])
            widths.append(matrices.shape[1])
        if len(set(widths)) == 1 and len(set(counts)) == 1:  # the usual frame: alike batches
            samples, sensors = counts[0], widths[0]
            senders = np.repeat(np.array(ids, dtype=np.int32), samples * sensors)
            times = np.repeat(stamps, sensors) if sensors > 1 else stamps
            sensor_numbers = np.tile(np.arange(sensors), len(pending) * samples)
        else:
            samples_of = np.array(counts)
            sensors_of = np.array(widths)
            sizes = samples_of * sensors_of
            senders = np.repeat(np.array(ids, dtype=np.int32), sizes)
            times = np.repeat(stamps, np.repeat(sensors_of, samples_of))
            # sensor number of each row: its place in its batch, modulo its sensor count
            starts = np.repeat(np.cumsum(sizes) - sizes, sizes)
            sensor_numbers = (np.arange(len(senders)) - starts) % np.repeat(sensors_of, sizes)
        flat = np.concatenate([v.reshape(-1, 4, 4) for _, _, v in pending])
        data = pack_poses(
            senders, self._pose, times, sensor_numbers, flat[:, :3, 3], quaternions_xyzw(flat)
        )
        self.messages += len(flat)
        return data

    # -- for new clients ----------------------------------------------------------------

    def send_states(self, client, sender: str | None = None) -> None:
        """``vrpn_Button States`` of every button sender (or of ``sender``) to one client, as a
        C++ button server does when a client connects and when it is pinged."""
        for name in self.button_states if sender is None else (sender,):
            states = self.button_states.get(name)
            if states is not None and name in self.senders:
                payload = codecs.encode_button_states(
                    [int(s) for s in states[: codecs.MAX_BUTTONS]]
                )
                self.server.send_to(client, self.senders[name], self._states, payload)
