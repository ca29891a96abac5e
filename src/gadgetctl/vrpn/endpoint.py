"""One VRPN connection once its TCP socket exists, shared by the client and the server side.

An :class:`Endpoint` writes the cookie, checks the peer's, frames and unframes messages,
keeps the per-connection translation tables (the peer's sender and type ids to names), opens
the outgoing UDP channel when the peer announces one, and holds a bounded output buffer: a
message that does not fit is dropped and counted, so a peer that stops reading never blocks
the side that sends.

The translation tables hold at most one name per id, and ids run from 0 to
``MAX_IDS - 1`` (2000, the C++ limit), so a peer that keeps describing new names under the
same ids replaces names rather than adding them: each such renaming is counted
(``renamed_senders``, ``renamed_types``) and never grows a table.

Whatever the C++ side answers by dropping the connection (a refused cookie, a message too
long, a malformed description, a system type at or below -2000) raises
:class:`ConnectionDropped` with the reason.
"""

from __future__ import annotations

import socket
from collections import Counter
from collections.abc import Callable, Iterator
from typing import NoReturn

from .codecs import STRICT_LENGTHS, CodecError, StrictLengthError
from .wire import (
    COOKIE_SIZE,
    DISCONNECT_MESSAGE,
    FATAL_SYSTEM_TYPE,
    HEADER_SIZE,
    LOG_DESCRIPTION,
    MAX_DATAGRAM,
    MAX_IDS,
    SENDER_DESCRIPTION,
    TYPE_DESCRIPTION,
    UDP_DESCRIPTION,
    Block,
    BulkIds,
    CookieError,
    FramingError,
    Message,
    StreamDecoder,
    check_cookie,
    decode_datagram,
    decode_description,
    decode_udp_description,
    make_cookie,
    pack_description,
    split_messages,
)

RECV_CHUNK = 256 * 1024
#: (sender id, type id) pairs :meth:`Endpoint.bulk_ids` sets apart at most (a peer may give
#: one name to many ids; messages of the pairs beyond are taken one by one).
MAX_BULK_IDS = 64


class ConnectionDropped(ConnectionError):
    """The connection ended; ``reason`` says why (peer closed, protocol violation...)."""

    def __init__(self, reason: str) -> None:
        super().__init__(reason)
        self.reason = reason


class NameTable:
    """One side's own senders or types: ids 0, 1, 2... in registration order."""

    def __init__(self, limit: int = MAX_IDS) -> None:
        self.limit = limit
        self.names: list[str] = []
        self._ids: dict[str, int] = {}

    def register(self, name: str) -> tuple[int, bool]:
        """(id, whether it is new); registering a known name returns its id."""
        ident = self._ids.get(name)
        if ident is not None:
            return ident, False
        if len(self.names) >= self.limit:
            raise ValueError(f"more than {self.limit} VRPN names")
        pack_description(SENDER_DESCRIPTION, 0, name)  # checks the name's length
        ident = len(self.names)
        self.names.append(name)
        self._ids[name] = ident
        return ident, True

    def id(self, name: str) -> int | None:
        return self._ids.get(name)

    def __iter__(self) -> Iterator[tuple[int, str]]:
        return iter(enumerate(list(self.names)))

    def __len__(self) -> int:
        return len(self.names)


class Endpoint:
    """The protocol state of one TCP connection (non-blocking socket)."""

    def __init__(
        self,
        sock: socket.socket,
        *,
        out_limit: int = 1 << 20,
        tcp_only: bool = False,
        log_mode: int = 0,
    ) -> None:
        self.sock = sock
        #: The socket's own (for select: a built-in method, no Python frame per call).
        self.fileno: Callable[[], int] = sock.fileno
        sock.setblocking(False)
        try:
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        except OSError:
            pass
        try:
            self.peer = sock.getpeername()
        except OSError:
            self.peer = ("?", 0)
        self.tcp_only = tcp_only
        self.out_limit = out_limit
        self.out = bytearray(make_cookie(log_mode=log_mode))
        self.opened = False  # the peer's cookie was accepted
        self.closed = False
        self.peer_version: str | None = None
        self.remote_senders: dict[int, str] = {}
        self.remote_types: dict[int, str] = {}
        #: Ids of the senders the peer described in its setup (before its first type
        #: description), and of those it described later: a C++ peer describes back every
        #: name *we* describe that it did not have, so a later name is not necessarily one it
        #: really serves. Ids, not names: at most ``MAX_IDS`` each, whatever the peer sends.
        self._setup_ids: set[int] = set()
        self._later_ids: set[int] = set()
        self._tables_version = 0  # changes with every description (see bulk_ids)
        self._bulk_cache: tuple[int, frozenset[tuple[str, str]], BulkIds] | None = None
        self.udp: socket.socket | None = None  # outgoing unreliable channel, once announced
        self._udp_batch = bytearray()
        self._cookie = bytearray()
        self._decoder = StreamDecoder()
        self.dropped = 0  # messages not queued because the output buffer was full
        self.sent_messages = 0
        self.bytes_read = 0
        self.counters: Counter[str] = Counter()
        #: ``codecs.decode`` to attach reports to user messages, or None.
        self.decode: Callable[[str, bytes], object] | None = None

    @property
    def setup_senders(self) -> set[str]:
        """Names of the senders the peer described in its setup (their current names)."""
        names = self.remote_senders
        return {names[i] for i in self._setup_ids if i in names}

    @property
    def later_senders(self) -> set[str]:
        """Names of the senders the peer described after its setup (their current names)."""
        names = self.remote_senders
        return {names[i] for i in self._later_ids if i in names}

    # -- reading ------------------------------------------------------------------------------

    def read(self, received: float, size: int = RECV_CHUNK) -> list[Message]:
        """Read what the socket has, at most ``size`` bytes (counted in ``bytes_read``); the
        peer's user messages, ids translated to names."""
        data = self._receive(size)
        if not data:
            return []
        try:
            messages = self._decoder.feed(data, received)
        except FramingError as exc:
            self._framing_error(exc)
        return self.translate(messages)

    def read_bulk(
        self, received: float, bulk: frozenset[tuple[str, str]], size: int = RECV_CHUNK
    ) -> tuple[list[Message], list[Block]]:
        """As :meth:`read`, but the messages of the (sender, type) name pairs in ``bulk``
        (tracker reports) come back framed, not unpacked: a :class:`~.wire.Block` per pair
        per read, checked as the C++ remote checks them (exact length, sensor not negative;
        the others go the usual way, and fail there)."""
        data = self._receive(size)
        if not data:
            return [], []
        ids = self.bulk_ids(bulk)
        try:
            messages, found, whole = self._decoder.feed_split(data, received, ids)
        except FramingError as exc:
            self._framing_error(exc)
        return self._blocks(messages, found, whole, received)

    def read_datagrams(
        self, datagrams: list[bytes], received: float, bulk: frozenset[tuple[str, str]]
    ) -> tuple[list[Message], list[Block], list[int]]:
        """The messages of datagrams that came on this connection's UDP channel, split as
        :meth:`read_bulk` does, and the indices of the datagrams refused (not whole
        messages: counted as ``bad_datagrams``)."""
        ids = self.bulk_ids(bulk)
        data = b"".join(datagrams)
        messages: list[Message] = []
        found: dict[tuple[str, str], list[int]] = {}
        refused: list[int] = []
        start = 0
        for index, datagram in enumerate(datagrams):
            end = start + len(datagram)
            try:
                pos, some, more = split_messages(data, start, end, received, ids)
                if pos != end:
                    raise FramingError("a datagram that is not whole messages")
            except FramingError:
                refused.append(index)
            else:
                messages += some
                for key, offsets in more.items():
                    found.setdefault(key, []).extend(offsets)
            start = end
        self.counters["bad_datagrams"] += len(refused)
        out, blocks = self._blocks(messages, found, data, received, udp=True)
        return out, blocks, refused

    def bulk_ids(self, bulk: frozenset[tuple[str, str]]) -> BulkIds:
        """The peer's (sender id, type id) pairs of the name pairs in ``bulk`` (worked out
        again only when a description changed the tables)."""
        if not bulk:
            return {}
        cached = self._bulk_cache
        if cached is not None and cached[0] == self._tables_version and cached[1] == bulk:
            return cached[2]
        sender_names = {sender for sender, _ in bulk}
        type_names = {name for _, name in bulk if name in STRICT_LENGTHS}
        senders = [(i, n) for i, n in self.remote_senders.items() if n in sender_names]
        types = [(i, n) for i, n in self.remote_types.items() if n in type_names]
        ids: BulkIds = {}
        for sender_id, sender in senders:
            for type_id, type_name in types:
                if len(ids) >= MAX_BULK_IDS:
                    break  # a peer naming many ids alike: the rest go the usual way
                if (sender, type_name) in bulk:
                    length = HEADER_SIZE + STRICT_LENGTHS[type_name]
                    ids[sender_id, type_id] = ((sender, type_name), length)
        self._bulk_cache = (self._tables_version, bulk, ids)
        return ids

    def _blocks(
        self,
        messages: list[Message],
        found: dict[tuple[str, str], list[int]],
        data: bytes,
        received: float,
        *,
        udp: bool = False,
    ) -> tuple[list[Message], list[Block]]:
        blocks = [
            Block(data, offsets, sender, type_name, received)
            for (sender, type_name), offsets in found.items()
        ]
        self.counters["messages"] += sum(len(b.offsets) for b in blocks)
        return self.translate(messages, udp), blocks

    def _framing_error(self, exc: FramingError) -> NoReturn:
        self.counters["oversized" if "too long" in str(exc) else "bad_frames"] += 1
        raise ConnectionDropped(str(exc)) from None

    def _receive(self, size: int) -> bytes:
        """What the socket has, at most ``size`` bytes, after the peer's cookie (b"" when
        nothing is)."""
        try:
            data = self.sock.recv(size)
        except (BlockingIOError, InterruptedError):
            return b""
        except OSError as exc:
            raise ConnectionDropped(f"connection error: {exc.strerror or exc}") from None
        if not data:
            raise ConnectionDropped("closed by the peer")
        self.bytes_read += len(data)
        if not self.opened:
            need = COOKIE_SIZE - len(self._cookie)
            self._cookie += data[:need]
            data = data[need:]
            if len(self._cookie) < COOKIE_SIZE:
                return b""
            try:
                self.peer_version = check_cookie(bytes(self._cookie))
            except CookieError as exc:
                self.counters["bad_cookies"] += 1
                raise ConnectionDropped(f"cookie refused: {exc}") from None
            self.opened = True
        return data

    def read_datagram(self, data: bytes, received: float) -> list[Message]:
        """The user messages of a datagram that came on this connection's UDP channel."""
        try:
            messages = decode_datagram(data, received)
        except FramingError:
            self.counters["bad_datagrams"] += 1
            return []
        return self.translate(messages, udp=True)

    def translate(self, messages: list[Message], udp: bool = False) -> list[Message]:
        """User messages with their sender and type names (and, with :attr:`decode`, their
        reports); system messages are handled here."""
        out: list[Message] = []
        senders, types, decode = self.remote_senders, self.remote_types, self.decode
        counters = self.counters
        new = tuple.__new__
        for m in messages:
            type_id = m[0]
            if type_id < 0:
                if udp:
                    counters["udp_system_ignored"] += 1  # system messages go by TCP only
                else:
                    self._system(m)
                continue
            counters["messages"] += 1
            type_name = types.get(type_id)
            if type_name is None:
                counters["undescribed"] += 1  # as the C++ side: silently dropped
                continue
            sender = senders.get(m[1])
            report = None
            if decode is not None:
                try:
                    report = decode(type_name, m[4])
                except StrictLengthError as exc:
                    # The C++ remote's handler fails on these, and that drops the connection.
                    counters["bad_reports"] += 1
                    raise ConnectionDropped(f"bad {type_name} from {sender}: {exc}") from None
                except CodecError:
                    counters["bad_reports"] += 1
                    continue
            out.append(
                new(Message, (type_id, m[1], m[2], m[3], m[4], sender, type_name, m[7], report))
            )
        return out

    def _system(self, m: Message) -> None:
        kind = m.type_id
        self._tables_version += 1
        if kind in (SENDER_DESCRIPTION, TYPE_DESCRIPTION):
            if not 0 <= m.sender_id < MAX_IDS:
                self.counters["bad_descriptions"] += 1
                raise ConnectionDropped(
                    f"description of id {m.sender_id} (ids are 0 to {MAX_IDS - 1})"
                )
            try:
                name = decode_description(m.payload)
            except FramingError as exc:
                self.counters["bad_descriptions"] += 1
                raise ConnectionDropped(f"bad description: {exc}") from None
            sender = kind == SENDER_DESCRIPTION
            table = self.remote_senders if sender else self.remote_types
            before = table.get(m.sender_id)
            if before is not None and before != name:
                self.counters["renamed_senders" if sender else "renamed_types"] += 1
            table[m.sender_id] = name  # one name per id: ids are bounded, so is the table
            if sender:
                (self._later_ids if self.remote_types else self._setup_ids).add(m.sender_id)
        elif kind == UDP_DESCRIPTION:
            self._open_udp(m)
        elif kind == DISCONNECT_MESSAGE:
            self.remote_senders.clear()
            self.remote_types.clear()
            self._setup_ids.clear()
            self._later_ids.clear()
        elif kind == LOG_DESCRIPTION:
            self.counters["log_requests_ignored"] += 1
        elif kind <= FATAL_SYSTEM_TYPE:
            self.counters["bad_system_messages"] += 1
            raise ConnectionDropped(f"system message type {kind}")
        else:
            self.counters["unknown_system_messages"] += 1

    def _open_udp(self, m: Message) -> None:
        if self.tcp_only:
            self.counters["udp_descriptions_ignored"] += 1
            return
        try:
            ip, port = decode_udp_description(m)
        except ValueError:
            self.counters["bad_udp_descriptions"] += 1
            return
        if ip != self.peer[0]:
            # Unreliable traffic only ever goes back to the host at the other end of the TCP
            # connection, never to a third address a peer names (C++ would send anywhere).
            self.counters["udp_descriptions_refused"] += 1
            return
        if self.udp is not None:
            self.udp.close()
        udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        udp.setblocking(False)
        try:
            udp.connect((ip, port))
        except OSError:
            udp.close()
            self.counters["bad_udp_descriptions"] += 1
            return
        self.udp = udp

    # -- writing ------------------------------------------------------------------------------

    def queue(self, data: bytes, reliable: bool = True) -> bool:
        """Queue one framed message (or several); False (and counted) when the buffer is full."""
        if not reliable and self.udp is not None and len(data) <= MAX_DATAGRAM:
            if len(self._udp_batch) + len(data) > MAX_DATAGRAM:
                self._send_udp()
            self._udp_batch += data
            self.sent_messages += 1
            return True
        if len(self.out) + len(data) > self.out_limit:
            self.dropped += 1
            return False
        self.out += data
        self.sent_messages += 1
        return True

    def queue_batch(
        self, data: bytes, size: int, reliable: bool = True, *, write: bool = False
    ) -> int:
        """Queue messages framed back to back, each ``size`` bytes long; how many were taken.
        Unreliable ones fill UDP datagrams (whole messages each); by TCP, the messages that
        do not fit the output buffer are dropped and counted, whole.

        With ``write``, also write now what the socket takes: when nothing waits before them,
        straight from ``data`` (shared by every client, not copied into this one's buffer;
        only what the socket does not take is queued)."""
        count = len(data) // size
        if not count:
            return 0
        if not reliable and self.udp is not None and size <= MAX_DATAGRAM:
            per_datagram = MAX_DATAGRAM // size * size
            view = memoryview(data)
            for start in range(0, count * size, per_datagram):
                chunk = view[start : start + per_datagram]
                if len(self._udp_batch) + len(chunk) > MAX_DATAGRAM:
                    self._send_udp()
                self._udp_batch += chunk
            self.sent_messages += count
            if write:
                self._send_udp()
            return count
        if write and not self.out:
            return self.write_batch(data, size, count)
        room = max(0, self.out_limit - len(self.out)) // size
        taken = min(count, room)
        if taken:
            self.out += data if taken == count else memoryview(data)[: taken * size]
        self.sent_messages += taken
        self.dropped += count - taken
        if write:
            self.flush()
        return taken

    def write_batch(self, data: bytes, size: int, count: int) -> int:
        """Send ``data`` (``count`` messages of ``size`` bytes) by TCP when the output buffer
        is empty (the caller checks ``out``): the rest of a message the socket took in part
        is queued whatever the limit, then the whole messages that fit; how many were taken."""
        try:
            written = self.sock.send(data)
        except (BlockingIOError, InterruptedError):
            written = 0
        except OSError as exc:
            raise ConnectionDropped(f"connection error: {exc.strerror or exc}") from None
        if written == len(data):
            self.sent_messages += count
            return count
        view = memoryview(data)
        begun = -(-written // size)  # messages written at least in part
        self.out += view[written : begun * size]
        rest = count - begun
        taken = min(rest, max(0, self.out_limit - len(self.out)) // size)
        if taken:
            self.out += view[begun * size : (begun + taken) * size]
        self.sent_messages += begun + taken
        self.dropped += rest - taken
        return begun + taken

    def _send_udp(self) -> None:
        batch = self._udp_batch
        if not batch or self.udp is None:
            return
        try:
            self.udp.send(batch)
        except OSError:
            self.counters["udp_send_errors"] += 1
        self._udp_batch = bytearray()

    @property
    def wants_write(self) -> bool:
        return bool(self.out)

    def flush(self) -> None:
        """Write what the socket takes now, never waiting; raises :class:`ConnectionDropped`."""
        if self._udp_batch:
            self._send_udp()
        out = self.out
        while out:
            try:
                n = self.sock.send(out)
            except (BlockingIOError, InterruptedError):
                return
            except OSError as exc:
                raise ConnectionDropped(f"connection error: {exc.strerror or exc}") from None
            del out[:n]

    def close(self) -> None:
        if self.closed:
            return
        self.closed = True
        for s in (self.sock, self.udp):
            if s is not None:
                try:
                    s.close()
                except OSError:
                    pass
        self.udp = None
