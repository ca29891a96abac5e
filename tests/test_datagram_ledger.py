"""The one account every UDP driver keeps of its datagrams (``DatagramLedger``): each read
counted once as decoded or bad, the kernel's drops, and the ``undecodable`` state a device
shows instead of ``running`` when what arrives does not decode (issue 23, items 4 and 9)."""

from __future__ import annotations

import socket

import pytest

from gadgetctl.input import Digital
from gadgetctl.input.device import DeviceState
from gadgetctl.monitor.loss import decoded_nothing, lost_data, run_problems
from gadgetctl.transport.udp import MAX_ERROR_TEXT, DatagramLedger

pytestmark = pytest.mark.timeout(30)


def test_every_datagram_read_is_counted_once_as_decoded_or_bad() -> None:
    ledger = DatagramLedger()
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as rx:
        rx.bind(("127.0.0.1", 0))
        ledger.attach(rx)
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
            for payload in (b"good", b"junk", b"good", b"junk", b"junk"):
                tx.sendto(payload, rx.getsockname())
        for _ in range(5):
            if ledger.receive(100) == b"good":
                ledger.decoded()
            else:
                ledger.bad("not good")
        ledger.detach()
    assert ledger.counters() == {
        "datagrams": 5,
        "decoded": 2,
        "bad_datagrams": 3,
        "kernel_dropped": 0,
    }


def test_a_receiver_that_never_decoded_is_undecodable_from_its_first_bad_datagram() -> None:
    ledger = DatagramLedger()
    assert ledger.undecodable() is None  # nothing yet: not undecodable, just quiet
    ledger.bad("marker count 973541338 is outside 0..20")
    ledger.bad("another reason, not the first")
    assert ledger.undecodable() == (
        "2 bad datagrams, none decoded; first: marker count 973541338 is outside 0..20"
    )
    ledger.decoded()
    assert ledger.undecodable() is None and ledger.first_error is None


def test_bad_datagrams_among_good_ones_leave_a_receiver_decodable() -> None:
    ledger = DatagramLedger(undecodable_after=3600.0)
    ledger.decoded()
    ledger.bad("one bad")
    assert ledger.undecodable() is None and ledger.first_error == "one bad"


def test_only_bad_datagrams_for_longer_than_the_limit_make_it_undecodable_again() -> None:
    ledger = DatagramLedger(undecodable_after=0.0)
    ledger.decoded(3)
    ledger.bad("the sender changed its protocol")
    assert ledger.undecodable() == (
        "1 bad datagram since the last decoded one; first: the sender changed its protocol"
    )


def test_the_error_kept_is_bounded() -> None:
    ledger = DatagramLedger()
    ledger.bad("x" * 100_000)
    assert ledger.first_error is not None and len(ledger.first_error) == MAX_ERROR_TEXT


class Receiver(Digital):
    """A device with a datagram ledger, as a UDP driver's wrapper gives one."""

    ELEMENT_TYPE = "test_receiver"

    def __init__(self) -> None:
        super().__init__()
        self.ledger = DatagramLedger()

    def datagram_ledger(self) -> DatagramLedger:
        return self.ledger


def test_a_running_device_that_decodes_nothing_shows_undecodable_with_the_first_error() -> None:
    device = Receiver()
    device.state = DeviceState.RUNNING
    assert device.shown_state() == (DeviceState.RUNNING, None)
    device.ledger.datagrams = 1
    device.ledger.bad("type tag \x1b[2J is not OSC")  # text from the network
    state, reason = device.shown_state()
    assert state is DeviceState.UNDECODABLE and state.value == "undecodable"
    assert reason == "1 bad datagram, none decoded; first: type tag \\x1b[2J is not OSC"
    assert device.state is DeviceState.RUNNING  # shown, not stored
    health = device.health()
    assert health["bad_datagrams"] == 1 and health["decoded"] == 0
    assert health["decode_error"] == "type tag \x1b[2J is not OSC"
    device.state = DeviceState.FAULTED
    device.error = "no data"
    assert device.shown_state() == (DeviceState.FAULTED, "no data")


def test_the_run_problems_name_loss_unless_accepted_and_never_accept_decoding_nothing() -> None:
    quiet, junk = Receiver(), Receiver()
    quiet.state = junk.state = DeviceState.FAULTED  # not shown undecodable: said here instead
    junk.ledger.datagrams = 4
    junk.ledger.bad("not OSC", 4)
    assert decoded_nothing("Q", quiet) is None and lost_data("Q", quiet) is None
    assert (
        decoded_nothing("J", junk)
        == "J: decoded nothing: 4 datagrams received, 4 bad; first: not OSC"
    )
    junk.ledger.drops._current = 7  # what the kernel said it dropped
    assert lost_data("J", junk) == (
        "J: lost data: 7 datagrams dropped by the kernel (receive buffer full) "
        "(--accept-loss accepts loss)"
    )
    assert len(run_problems([("Q", quiet), ("J", junk)])) == 2
    assert run_problems([("J", junk)], accept_loss=True) == [decoded_nothing("J", junk)]


class Scanner(Digital):
    """A serial device whose driver counts as the record scanners do."""

    ELEMENT_TYPE = "test_scanner"

    def __init__(self) -> None:
        super().__init__()
        self.counters = {"records": 0, "bad_records": 0, "skipped_bytes": 0}


def test_a_serial_device_that_reads_only_junk_shows_undecodable_until_a_record_decodes() -> None:
    device = Scanner()
    device.state = DeviceState.RUNNING
    assert device.shown_state() == (DeviceState.RUNNING, None)  # nothing read yet
    device.counters.update(bad_records=3, skipped_bytes=57)
    assert device.shown_state() == (
        DeviceState.UNDECODABLE,
        "57 bytes of junk skipped (3 runs), no record decoded",
    )
    device.counters["records"] = 1
    assert device.shown_state() == (DeviceState.RUNNING, None)
