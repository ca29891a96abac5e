"""The sampling life cycle of a device fed by a UDP receiver, shared by the DTrack, TUIO and
OptiTrack wrappers: one receiver for the device's life (its counters add up over restarts),
an OS-chosen port kept for restarts, and a restart after a loss that succeeds only when data
comes again.

A device class puts :class:`ReceiverSampling` first among its bases, sets the class
attributes that name its error and its data, and implements :meth:`_new_receiver` and
:meth:`_add`; the other ``_`` methods are hooks with defaults.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, ClassVar, Generic, Protocol, TypeVar

from gadgetctl.input.device import Input

if TYPE_CHECKING:
    from gadgetctl.transport.udp import DatagramLedger


class Receiver(Protocol):
    """What :class:`ReceiverSampling` uses of a driver's standalone receiver."""

    receive_timeout: float
    peer_timeout: Any
    ledger: DatagramLedger

    @property
    def port(self) -> int: ...

    def open(self) -> Any: ...

    def close(self) -> None: ...

    def sample_all(self, limit: int) -> Sequence[Any]: ...


R = TypeVar("R", bound=Receiver)


class ReceiverSampling(Input, Generic[R]):
    """start_sampling(), sample() and stop_sampling() of a device whose receiver returns what
    arrived with ``sample_all(limit)`` (an empty batch after ``receive_timeout`` of silence)."""

    #: Raised by sample() on a closed receiver and by a restart that gets no data.
    DISCONNECTED: ClassVar[type[Exception]] = ConnectionError
    #: What a restart that gets no data says is missing: "still no {DATA_NAME} on UDP port N".
    DATA_NAME: ClassVar[str] = "data"
    #: The receiver's attribute with the port asked for (0: the OS chooses, and the chosen
    #: one is kept there for restarts).
    PORT_ATTRIBUTE: ClassVar[str] = "requested_port"

    sample_interval = 0.0  # sample() waits for datagrams itself

    #: Seconds one sample() call waits for a datagram.
    receive_timeout = 0.1
    #: After a loss, seconds a restart waits for the first data.
    probe_timeout = 0.25
    #: What one sample() call reads at most (datagrams or frames), so samples flow even
    #: under overload.
    batch_limit = 100

    #: Seconds without a datagram after which the receiver raises (set by the device).
    peer_timeout: float

    def __init__(self) -> None:
        super().__init__()
        self._receiver: R | None = None
        self._open = False
        self._started = False

    # -- what a device implements -------------------------------------------------------------

    def _new_receiver(self) -> R:
        """The device's receiver, made at its first start."""
        raise NotImplementedError

    def _add(self, batch: Any) -> None:
        """Add the samples of a batch ``sample_all()`` returned (never empty)."""
        raise NotImplementedError

    def _first_start(self, driver: R) -> None:
        """At the first start, after opening: nothing by default."""

    def _after_sample(self, batch: Any) -> None:
        """After sample() added a batch: nothing by default."""

    def _silence(self, driver: R) -> Exception:
        """The error of a restart that got no data (naming why datagrams did not decode)."""
        why = driver.ledger.undecodable()
        return self.DISCONNECTED(
            f"still no {self.DATA_NAME} on UDP port {driver.port}"
            + (f" (undecodable: {why})" if why else "")
        )

    # -- the life cycle -------------------------------------------------------------------------

    def _driver(self) -> R:
        """One receiver for the device's life, so its counters add up over reconnections."""
        if self._receiver is None:
            self._receiver = self._new_receiver()
        self._receiver.peer_timeout = self.peer_timeout
        return self._receiver

    def start_sampling(self) -> None:
        driver = self._driver()
        driver.open()
        self._open = True
        port = getattr(driver, self.PORT_ATTRIBUTE)
        if isinstance(port, int) and port == 0:
            setattr(driver, self.PORT_ATTRIBUTE, driver.port)  # kept for restarts
        if self._started:
            self._probe(driver)
        else:
            self._first_start(driver)
        self._started = True

    def _probe(self, driver: R) -> None:
        """After a loss, succeed only when data comes again."""
        driver.receive_timeout = self.probe_timeout
        try:
            batch = driver.sample_all(self.batch_limit)
            if not batch:
                raise self._silence(driver)
        except BaseException:
            self.stop_sampling()
            raise
        finally:
            driver.receive_timeout = self.receive_timeout
        self._add(batch)

    def sample(self) -> None:
        driver = self._receiver
        if driver is None or not self._open:
            raise self.DISCONNECTED("the receiver is closed")
        batch = driver.sample_all(self.batch_limit)
        if batch:
            self._add(batch)
            self._after_sample(batch)

    def stop_sampling(self) -> None:
        if self._receiver is not None and self._open:
            self._open = False
            self._receiver.close()

    def datagram_ledger(self) -> DatagramLedger | None:
        """The receiver's account of its datagrams: decoded, bad, dropped by the kernel."""
        return self._receiver.ledger if self._receiver is not None else None
