"""The shared resynchronising record scanner and the counters carried across reconnections
(`gadgetctl.transport.records`), on a toy protocol: ``#`` and three digits."""

from __future__ import annotations

import threading
from dataclasses import dataclass

import pytest

from gadgetctl.input.testing import wait_until
from gadgetctl.transport.records import (
    SCANNER_COUNTERS,
    CarriedCounters,
    CarriedCounts,
    ResyncScanner,
    ScannedDevice,
)
from gadgetctl.transport.serialline import LineDriver, SerialLine


@dataclass
class Digits(ResyncScanner[int]):
    HEAD = b"#"
    SIZE = 4

    def decode(self, record: bytes) -> int | None:
        body = record[1:]
        return int(body) if body.isdigit() else None


@dataclass
class Bounded(Digits):
    MAX_BUFFER = 2

    def restart_within(self, buffer: bytearray, start: int) -> int | None:
        cut = buffer.find(b"#", start + 1)
        return None if cut < 0 else cut


def test_records_come_whole_across_feeds_and_junk_runs_count_once() -> None:
    scanner = Digits()
    assert scanner.feed(b"#12") == []  # cut short: kept for later
    assert scanner.feed(b"3#456") == [123, 456]
    assert scanner.feed(b"xyzzy#789junk#0") == [789]
    # one junk run before 789 (5 bytes), one after (4 bytes); "#0" waits
    assert (scanner.records, scanner.bad_records, scanner.skipped_bytes) == (3, 2, 9)
    assert bytes(scanner.buffer) == b"#0"
    assert scanner.feed(b"01") == [1]


def test_a_head_that_does_not_decode_is_junk_and_the_search_goes_on() -> None:
    scanner = Digits()
    assert scanner.feed(b"#ab#123##99#555") == [123, 555]
    # "#ab" (3 bytes) is a run; "#" before "#99#" and "#99" are one more run of 4
    assert (scanner.records, scanner.bad_records, scanner.skipped_bytes) == (2, 2, 7)


def test_fields_of_a_driver_come_first_and_counters_are_keywords() -> None:
    @dataclass
    class Scaled(Digits):
        scale: int = 1

        def decode(self, record: bytes) -> int | None:
            value = super().decode(record)
            return None if value is None else value * self.scale

    assert Scaled(10).feed(b"#004") == [40]
    assert Scaled(scale=2, records=5).records == 5


def test_a_head_inside_a_cut_record_ends_it_and_the_buffer_is_bounded() -> None:
    scanner = Bounded()
    assert scanner.feed(b"#1#") == []  # "#1" was cut off by the next head: junk at once
    assert (scanner.bad_records, scanner.skipped_bytes) == (1, 2)
    assert scanner.feed(b"234") == [234]
    assert Digits().feed(b"#1#") == []  # without restart_within it waits
    assert scanner.feed(b"#12") == []  # three bytes wait: more than MAX_BUFFER
    assert bytes(scanner.buffer) == b"" and scanner.skipped_bytes == 5


class Source:
    def __init__(self) -> None:
        self.records = 0
        self.bad_records = 0


def test_carried_counts_add_closed_connections_to_the_open_one() -> None:
    counts = CarriedCounts(("records", "bad_records"))
    first = Source()
    counts.attach(first)
    first.records, first.bad_records = 10, 1
    assert counts.snapshot() == {"records": 10, "bad_records": 1}
    assert counts.detach() is first
    first.records = 99  # what a closed connection counts later is not added
    second = Source()
    counts.attach(second)
    second.records = 5
    assert counts.get("records") == 15 and counts.get("bad_records") == 1
    assert counts.detach() is second and counts.detach() is None
    assert counts.snapshot() == {"records": 15, "bad_records": 1}
    assert counts.names == ("records", "bad_records")


def test_carried_counts_never_lose_or_double_a_count_while_read() -> None:
    counts = CarriedCounts(("records",))
    seen: list[int] = []
    stop = threading.Event()

    def read() -> None:
        while not stop.is_set():
            seen.append(counts.get("records"))

    reader = threading.Thread(target=read)
    reader.start()
    try:
        for _ in range(200):
            source = Source()
            source.records = 1
            counts.attach(source)
            counts.detach()
    finally:
        stop.set()
        reader.join(10)
    assert counts.get("records") == 200
    assert seen == sorted(seen)  # never a count that goes back (lost between detach and keep)


def test_a_scanned_device_opens_closes_and_shows_its_scanners_counters() -> None:
    class Device(ScannedDevice):
        def __init__(self) -> None:
            self.scanner = Digits()
            self.opened = self.closed = 0

        def open(self) -> None:
            self.opened += 1

        def close(self) -> None:
            self.closed += 1

    with Device() as device:
        assert device.opened == 1 and device.closed == 0
        device.scanner.feed(b"??#001#002")
    assert device.closed == 1
    assert (device.records, device.bad_records, device.skipped_bytes) == (2, 1, 2)


def test_a_line_driver_turns_a_closed_or_lost_line_into_its_own_errors() -> None:
    class Gone(Exception):
        pass

    class Closed(Exception):
        pass

    class Driver(LineDriver):
        LOST, CLOSED, CLOSED_TEXT = Gone, Closed, "the toy is not open"

    driver = Driver()
    with pytest.raises(Closed, match="the toy is not open"):
        driver._read_some()
    line = SerialLine("loop://", poll_interval=0.05).open()
    driver._line = line
    got = bytearray()

    def gather() -> None:
        got.extend(driver._read_some())

    driver._write(b"#123")
    assert wait_until(lambda: bytes(got) == b"#123", step=gather, timeout=5)
    driver._write(b"junk")
    assert wait_until(lambda: line._port.in_waiting == 4, timeout=5)
    driver._flush_input()
    driver._write(b"#456")
    got.clear()
    assert wait_until(lambda: bytes(got) == b"#456", step=gather, timeout=5)
    line._port.close()  # the adapter goes away under the driver
    for action in (driver._read_some, driver._flush_input, lambda: driver._write(b"x")):
        with pytest.raises(Gone):
            action()


def test_carried_counters_give_a_wrapper_its_counters_over_every_connection() -> None:
    class Wrapper(CarriedCounters):
        def __init__(self) -> None:
            self.counts = CarriedCounts(SCANNER_COUNTERS)

    wrapper = Wrapper()
    for fed in (b"#001", b"xx#002#003"):
        device = Digits()
        wrapper.counts.attach(device)
        device.feed(fed)
        wrapper.counts.detach()
    assert (wrapper.records, wrapper.bad_records, wrapper.skipped_bytes) == (3, 1, 2)
    assert wrapper.counters == {"records": 3, "bad_records": 1, "skipped_bytes": 2}


def test_complete_takes_optional_trailing_bytes_and_waits_for_the_byte_that_tells() -> None:
    from dataclasses import dataclass

    from gadgetctl.transport.records import ResyncScanner

    @dataclass
    class Trailing(ResyncScanner[bytes]):
        """Records ``#xy``, optionally followed by one ``!``."""

        HEAD = b"#"
        SIZE = 3

        def decode(self, record: bytes) -> bytes | None:
            return record

        def complete(self, record, buffer, end, quiet):
            if end == len(buffer):
                return (record, 0) if quiet else None
            return (record + b"!", 1) if buffer[end : end + 1] == b"!" else (record, 0)

    scanner = Trailing()
    assert scanner.feed(b"#ab!#cd#ef") == [b"#ab!", b"#cd"]  # #ef: is a ! coming?
    assert scanner.feed(b"!") == [b"#ef!"]
    assert scanner.feed(b"#gh") == [] and scanner.feed(b"", quiet=True) == [b"#gh"]
    assert scanner.records == 4 and scanner.skipped_bytes == 0
