"""Writing and reading recordings: NDJSON files that stay readable if the writer dies.

Every record is one line appended with a single write and flushed to the operating system
per batch (and at least every ``flush_interval`` seconds while single samples keep coming),
so after SIGINT, SIGTERM or SIGKILL every complete line is a valid record. The reader
ignores a truncated last line and reports malformed lines instead of raising.
"""

from __future__ import annotations

import contextlib
import itertools
import json
import os
import signal
import time
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import BinaryIO, NamedTuple

from gadgetctl.boundedread import NotRegularFile, bounded_lines, open_regular
from gadgetctl.errors import GadgetctlError
from gadgetctl.monitor.records import (
    FORMAT_NAME,
    FORMAT_VERSION,
    EndRecord,
    FrameRecord,
    HeaderRecord,
    MarkerRecord,
    Record,
    RecordFormatError,
    SampleRecord,
    StatsRecord,
    StatusRecord,
    UnknownRecordType,
    decode_line,
    decode_record,
    encode_header_parts,
    encode_record,
    encode_samples,
    encode_stats_parts,
    encode_status_parts,
)
from gadgetctl.safewrite import WriteError, create_new

MAX_HEADER_BYTES = 1 << 20
MAX_RECORD_BYTES = 16 << 20  # one record line; far above what the recorder writes


class RecordingError(GadgetctlError):
    """A recording that cannot be written, or a file that is not a readable recording."""


class Terminated(BaseException):
    """Raised inside :func:`raise_on_stop_signals` when the process receives SIGTERM."""


@contextlib.contextmanager
def raise_on_stop_signals() -> Iterator[None]:
    """Within the block SIGINT raises KeyboardInterrupt and SIGTERM :class:`Terminated`, so
    ``with Recorder(...)`` blocks write their end record. Main thread only.

    SIGINT is set explicitly because a process started with SIGINT ignored (a background
    job) would otherwise keep ignoring it.
    """

    def terminate(signum: int, frame: object) -> None:
        raise Terminated(signum)

    previous_int = signal.signal(signal.SIGINT, signal.default_int_handler)
    previous_term = signal.signal(signal.SIGTERM, terminate)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous_term)
        signal.signal(signal.SIGINT, previous_int)


class Recorder:
    """Appends records to a new recording file; use it as a context manager, from one thread.

    The header is written when the recorder is created. :meth:`close` (or leaving the
    ``with`` block) writes the end record; its ``reason`` is ``closed``, ``interrupted``
    (KeyboardInterrupt), ``terminated`` (:class:`Terminated`) or ``error``.
    """

    def __init__(
        self,
        path: str | Path,
        header_info: Mapping[str, object] | None = None,
        *,
        overwrite: bool = False,
        flush_interval: float = 0.1,
        clock: Callable[[], float] = time.monotonic,
        stream: BinaryIO | None = None,
    ) -> None:
        self.path = Path(path)
        self.flush_interval = flush_interval
        self.samples = self.markers = self.frames = 0
        self.closed = False
        self._clock = clock
        self._pending: list[str] = []
        self._pending_samples = 0
        self._writing = False
        self._owns_file = stream is None
        # the header is not kept: its info lists every element (megabytes for 10,000)
        header = HeaderRecord.now(header_info, clock=clock)
        if stream is not None:
            self._file = stream
        else:
            try:  # never through a symbolic link, even with overwrite
                self._file = os.fdopen(create_new(self.path, overwrite=overwrite), "wb")
            except WriteError as exc:
                raise RecordingError(str(exc)) from None
        try:
            # in parts of about a megabyte (one line all the same; see write_stats)
            for part in encode_header_parts(header):
                self._write(part)
                self._writing = True  # until the line ends: close() ends a line cut short
            self._writing = False
        except BaseException:
            if self._owns_file:
                with contextlib.suppress(OSError):  # the write error is the one to report
                    self._file.close()
            raise
        self._last_flush = clock()

    @classmethod
    def to_stream(
        cls,
        stream: BinaryIO,
        header_info: Mapping[str, object] | None = None,
        *,
        name: str = "<stdout>",
        clock: Callable[[], float] = time.monotonic,
    ) -> Recorder:
        """A recorder writing to an open binary stream (e.g. ``sys.stdout.buffer``), which
        :meth:`close` flushes but leaves open."""
        return cls(name, header_info, clock=clock, stream=stream)

    def __enter__(self) -> Recorder:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: object
    ) -> None:
        if exc_type is None:
            self.close("closed")
            return
        if issubclass(exc_type, KeyboardInterrupt):
            reason = "interrupted"
        elif issubclass(exc_type, Terminated):
            reason = "terminated"
        else:
            reason = "error"
        with contextlib.suppress(RecordingError):  # do not hide the exception that ended the block
            self.close(reason)

    # ---------------------------------------------------------------- writing

    def _write(self, text: str) -> None:
        if self.closed:
            raise RecordingError(f"{self.path}: recording is closed")
        self._writing = True
        try:
            self._file.write(text.encode("utf-8"))
            self._file.flush()
        except OSError as exc:
            raise RecordingError(f"{self.path}: cannot write: {exc.strerror or exc}") from None
        self._writing = False
        self._last_flush = self._clock()

    def flush(self) -> None:
        """Write pending single samples now."""
        if self._pending:
            text, count = "".join(self._pending), self._pending_samples
            self._pending.clear()
            self._pending_samples = 0
            self._write(text)
            self.samples += count

    def write_samples(self, records: Iterable[SampleRecord]) -> int:
        """Append a batch of samples (one write, flushed); returns how many were written.

        A record that cannot be encoded (non-finite timestamp, unit not an integer, value of
        an unknown type) raises ValueError or TypeError and nothing of the batch is written.
        """
        self.flush()
        records = records if isinstance(records, (list, tuple)) else list(records)
        if records:
            self._write(encode_samples(records))
            self.samples += len(records)
        return len(records)

    def write_encoded(self, text: str, count: int) -> None:
        """Append ``count`` sample records already encoded as NDJSON lines (e.g. by
        :func:`~gadgetctl.monitor.records.encode_rows`), with one write."""
        self.flush()
        if text:
            self._write(text)
            self.samples += count

    def write_sample(self, record: SampleRecord) -> None:
        """Append one sample; written at the latest ``flush_interval`` after the previous write
        once another record arrives (call :meth:`flush` when sampling pauses)."""
        if self.closed:
            raise RecordingError(f"{self.path}: recording is closed")
        self._pending.append(encode_samples((record,)))
        self._pending_samples += 1
        if self._clock() - self._last_flush >= self.flush_interval:
            self.flush()

    def _write_record(self, record: Record) -> None:
        self.flush()
        self._write(encode_record(record))

    def write_marker(self, name: str, timestamp: float | None = None) -> MarkerRecord:
        """Append a marker (at ``clock()`` unless ``timestamp`` is given)."""
        marker = MarkerRecord(name, self._clock() if timestamp is None else timestamp)
        self._write_record(marker)
        self.markers += 1
        return marker

    def write_frame(self, frame: FrameRecord) -> None:
        """Append one frame record."""
        self._write_record(frame)
        self.frames += 1

    def write_status(self, record: StatusRecord) -> None:
        """Append an element status record."""
        self._write_record(record)

    def write_statuses(self, records: Sequence[StatusRecord]) -> None:
        """Append element status records with one write per megabyte of them (a
        configuration's start: 20,000 writes of one line each cost seconds while another
        thread held the GIL; all of them as one string were megabytes more at once). What
        cannot be encoded raises before its part is written (whole lines only)."""
        self.flush()
        for part in encode_status_parts(records):
            self._write(part)

    def write_stats(
        self, devices: Mapping[str, Mapping[str, object]], timestamp: float | None = None
    ) -> None:
        """Append a statistics snapshot (device name -> statistic -> value), written in
        parts of about a megabyte (one line all the same)."""
        record = StatsRecord(self._clock() if timestamp is None else timestamp, devices)
        # each part written as it is made (all of them at once were 6 MB more for 10,000
        # devices at the end of a monitor's run): a timestamp that cannot be encoded raises
        # before a write, a failure later leaves a line that close() ends
        parts = encode_stats_parts(record)
        first = next(parts)
        self.flush()
        for part in itertools.chain((first,), parts):
            self._write(part)
            self._writing = True  # until the line ends: close() ends a line cut short
        self._writing = False

    def close(self, reason: str = "closed") -> None:
        """Write pending samples and the end record, then close the file (idempotent)."""
        if self.closed:
            return
        try:
            if self._writing:  # a write was interrupted: end its partial line
                self._write("\n")
            self.flush()
            self._write(
                encode_record(
                    EndRecord(self._clock(), reason, self.samples, self.markers, self.frames)
                )
            )
        finally:
            self.closed = True
            if self._owns_file:
                self._close_file()

    def _close_file(self) -> None:
        try:
            self._file.close()
        except OSError as exc:  # buffered bytes that could not be written
            raise RecordingError(f"{self.path}: cannot write: {exc.strerror or exc}") from None


# --------------------------------------------------------------------------- reading


class RecordingProblem(NamedTuple):
    """A line of a recording that was skipped: ``severity`` is error, warning or info."""

    line: int
    severity: str
    message: str

    def __str__(self) -> str:
        return f"line {self.line}: {self.severity}: {self.message}"


class Recording(NamedTuple):
    """A recording being read: ``problems`` fills up while ``records`` is consumed."""

    header: HeaderRecord
    records: Iterator[Record]
    problems: list[RecordingProblem]
    path: Path


def _not_a_recording(path: Path, why: str) -> RecordingError:
    return RecordingError(f"{path}: not a gadgetctl recording ({why})")


def _read_header(path: Path) -> HeaderRecord:
    try:
        with open_regular(path) as f:
            first = f.readline(MAX_HEADER_BYTES)
            at_end = not f.read(1)
    except IsADirectoryError:
        raise RecordingError(f"{path}: is a directory, not a recording") from None
    except NotRegularFile as exc:
        raise RecordingError(f"{path}: {exc.strerror}") from None
    except OSError as exc:
        raise RecordingError(f"{path}: cannot read: {exc.strerror or exc}") from None
    if not first:
        raise _not_a_recording(path, "the file is empty")
    try:
        obj = json.loads(first.decode("utf-8"))
    except RecursionError:
        raise _not_a_recording(path, "the header nests deeper than JSON is read") from None
    except (UnicodeDecodeError, ValueError):
        if at_end and not first.endswith(b"\n") and first.startswith(b'{"v":'):
            raise RecordingError(
                f"{path}: the recording ends inside its header "
                "(the writer was stopped while starting)"
            ) from None
        raise _not_a_recording(path, "the first line is not a JSON header") from None
    if not isinstance(obj, dict) or obj.get("type") != "header" or obj.get("format") != FORMAT_NAME:
        raise _not_a_recording(path, f"the first line is not a {FORMAT_NAME!r} header")
    version = obj.get("v")
    if not isinstance(version, int) or isinstance(version, bool) or version < 1:
        raise _not_a_recording(path, f"invalid format version {version!r}")
    if version > FORMAT_VERSION:
        raise RecordingError(
            f"{path}: recording format version {version} is newer than this "
            f"gadgetctl reads ({FORMAT_VERSION}); upgrade gadgetctl"
        )
    try:
        header = decode_record(obj)
    except RecursionError:
        raise _not_a_recording(path, "the header nests deeper than JSON is read") from None
    except RecordFormatError as exc:
        raise _not_a_recording(path, f"invalid header: {exc}") from None
    assert isinstance(header, HeaderRecord)
    return header


def _looks_truncated(line: bytes) -> bool:
    return line.startswith(b"{") and not line.rstrip().endswith(b"}")


def _records(path: Path, problems: list[RecordingProblem]) -> Iterator[Record]:
    with open_regular(path) as f:
        f.readline(MAX_HEADER_BYTES)
        for number, line in enumerate(bounded_lines(f, MAX_RECORD_BYTES), start=2):
            if line is None:
                problems.append(
                    RecordingProblem(
                        number, "error", f"record longer than {MAX_RECORD_BYTES} bytes skipped"
                    )
                )
                continue
            last = not line.endswith(b"\n")
            if not line.strip():
                continue
            try:
                record = decode_line(line)
            except UnknownRecordType as exc:
                problems.append(RecordingProblem(number, "info", f"skipped: {exc}"))
                continue
            except RecordFormatError as exc:
                if last:
                    problems.append(
                        RecordingProblem(
                            number,
                            "warning",
                            "truncated last line ignored (the recording was interrupted)",
                        )
                    )
                elif _looks_truncated(line):
                    problems.append(
                        RecordingProblem(
                            number, "warning", "incomplete record ignored (a write was interrupted)"
                        )
                    )
                else:
                    problems.append(RecordingProblem(number, "error", f"malformed record: {exc}"))
                continue
            if isinstance(record, HeaderRecord):
                problems.append(RecordingProblem(number, "error", "unexpected second header"))
                continue
            yield record


def read_recording(path: str | Path) -> Recording:
    """Open a recording: the header is read now (raising :class:`RecordingError` for a file
    that is not a recording); records are read lazily, skipping and reporting bad lines."""
    path = Path(path)
    header = _read_header(path)
    problems: list[RecordingProblem] = []
    return Recording(header, _records(path, problems), problems, path)
