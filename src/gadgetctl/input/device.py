"""The base class of every input device, and what the input manager gives a device.

A driver's device class derives from one or more device-type classes of
:mod:`gadgetctl.input.devicetypes` (``class Joystick(Digital, Analog)``) and implements:

* ``config(access)``: call ``super().config(access)`` first, then read the element's own
  properties; raise :class:`DeviceConfigError` with the reason when it cannot work;
* ``start_sampling()``: open the device (raise to report a start failure);
* ``sample()``: read what the device has and add it with the ``add_*_sample`` methods; it
  is called in a loop by the input manager, never by the driver itself;
* ``stop_sampling()``: close the device; it may be called again after a restart;
* ``update_data()``: called once per frame; the default swaps the sample buffers.

``SAMPLING`` says who calls ``sample()``: its own thread (the default, for drivers whose
reads block), a shared scheduler thread at ``sample_interval`` (cheap non-blocking
devices), or nobody (devices that compute their data in ``update_data``).
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import TYPE_CHECKING, ClassVar, Protocol

from gadgetctl.diagnostics import Diagnostic
from gadgetctl.input.clock import now
from gadgetctl.input.errors import describe
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.samples import DEFAULT_CAP, SampleStore
from gadgetctl.safetext import printable
from gadgetctl.wording import counted

if TYPE_CHECKING:
    from gadgetctl.input.events import EventSource
    from gadgetctl.jccl.access import ElementAccess
    from gadgetctl.jccl.configuration import ConfigElement
    from gadgetctl.transport.udp import DatagramLedger


class SamplingMode(StrEnum):
    THREAD = "thread"  # sample() runs in a loop in the device's own thread; it may block
    SCHEDULED = "scheduled"  # a shared thread calls sample() every sample_interval; must not block
    FRAME = "frame"  # no sampling thread: update_data() produces the samples


class DeviceState(StrEnum):
    CONFIGURED = "configured"  # configured, not started (dry runs)
    RUNNING = "running"
    FAULTED = "faulted"  # sample() raised; a restart is scheduled
    RECONNECTING = "reconnecting"  # start_sampling() is being retried after a fault
    STOPPED = "stopped"
    #: Shown, never stored: a RUNNING device that receives data but decodes none of it
    #: (:meth:`Input.shown_state`); ``state`` itself stays RUNNING.
    UNDECODABLE = "undecodable"


@dataclass(frozen=True, slots=True)
class DeviceStats:
    """Counters of one device, for `gadgetctl monitor`."""

    samples: int
    dropped: int
    faults: int
    restarts: int
    last_error: str | None


class DeviceContext(Protocol):
    """What the input manager offers a device."""

    @property
    def frame(self) -> int: ...

    @property
    def events(self) -> EventSource: ...

    def proxy(self, name: str) -> object | None:
        """The proxy called ``name`` (or the one an alias of that name points at), updated
        for the current frame: a :mod:`gadgetctl.input.proxies` object, which the device
        checks with ``isinstance`` (this module does not import the proxies, which build on
        it)."""


class Input:
    """Base of every device. Subclasses set ``ELEMENT_TYPE`` and mix in device types."""

    #: The definition token this class configures (Gadgeteer's getElementType()).
    ELEMENT_TYPE: ClassVar[str] = ""
    #: Who calls sample(); see :class:`SamplingMode`.
    SAMPLING: ClassVar[SamplingMode] = SamplingMode.THREAD
    #: Set by each device-type class to the kind of data it provides.
    KIND: ClassVar[DeviceKind | None] = None

    #: THREAD: pause between two sample() calls (0 = none, for reads that block);
    #: SCHEDULED: period at which the shared scheduler calls sample().
    sample_interval: float = 0.0

    # What a fault sets: class defaults until then, so that a device's instance dictionary
    # stays small (a class's instances share their attribute names while they have at most
    # 29 of them: 300 bytes each instead of 1,600, 12 MB for 10,000 waveform devices).
    error: str | None = None
    error_at: float | None = None  # wall-clock time (time.time()) of the last fault
    faults: int = 0
    restarts: int = 0

    def __init__(self) -> None:
        self.name = type(self).__name__
        self.element_type = self.ELEMENT_TYPE
        self.context: DeviceContext | None = None
        self.store = SampleStore(self.kinds(), DEFAULT_CAP)
        self.state = DeviceState.CONFIGURED
        self.diagnostics: list[Diagnostic] = []
        # its element, whose location (a line and column looked up in the file) is made only
        # for a warning: most devices never warn (10,000 location objects made for nothing)
        self._element: ConfigElement | None = None
        self._updated_frame = -1

    @classmethod
    def kinds(cls) -> tuple[DeviceKind, ...]:
        """The kinds of data this class provides, in base-class order (worked out once per
        class: every proxy asks its device when it binds)."""
        known = cls.__dict__.get("_kinds_of_class")
        if known is not None:
            return known
        seen: list[DeviceKind] = []
        for klass in cls.__mro__:
            kind = klass.__dict__.get("KIND")
            if kind is not None and kind not in seen:
                seen.append(kind)
        cls._kinds_of_class = tuple(seen)
        return cls._kinds_of_class

    def configured_kinds(self) -> tuple[DeviceKind, ...]:
        """The kinds this device may deliver as configured (every kind of its class unless a
        driver knows better): what a consumer that cannot wait for sporadic data, such as
        strings and commands, may expect."""
        return self.kinds()

    # -- what drivers implement ----------------------------------------------------------

    def config(self, access: ElementAccess) -> None:
        """Read the element. Subclasses call ``super().config(access)`` first."""
        self.name = access.name
        self.element_type = access.element.type
        self._element = access.element

    def start_sampling(self) -> None:
        """Open the device. Raise to report that it cannot start."""

    def sample(self) -> None:
        """Read available data and add it with the ``add_*_sample`` methods."""

    def stop_sampling(self) -> None:
        """Close the device. Called after a fault too, so it must tolerate a half-open device."""

    def update_data(self) -> None:
        """Once per frame: make the samples since the previous frame current."""
        self.store.swap()

    def next_sample_due(self) -> float | None:
        """SCHEDULED devices: when the next sample comes due, so the scheduler can sleep
        until then (but wakes at most every ``sample_interval``). None: no idea."""
        return None

    # -- services for subclasses -------------------------------------------------------

    @staticmethod
    def now() -> float:
        """The time a sample taken now carries."""
        return now()

    def warn(self, code: str, message: str, *, hint: str | None = None) -> None:
        """Record a diagnostic about this device's configuration (shown by `config pending`)."""
        loc = None if self._element is None else self._element.location
        path, line, column = (None, None, None) if loc is None else (loc.path, loc.line, loc.column)
        self.diagnostics.append(
            Diagnostic.make(code, f"{self.name}: {message}", path, line, column, hint=hint)
        )

    # -- used by the input manager -----------------------------------------------------

    @classmethod
    def samples_in_thread(cls) -> bool:
        """Whether the manager must call sample(): the class overrides it and is not FRAME."""
        return cls.SAMPLING is not SamplingMode.FRAME and cls.sample is not Input.sample

    def update_for_frame(self, frame: int) -> None:
        """Run update_data() once per frame, whoever asks first (proxies, other devices)."""
        if self._updated_frame == frame:
            return
        self._updated_frame = frame
        try:
            self.update_data()
        except Exception as err:  # a faulty driver must not stop the frame loop
            self.frame_fault(err)
        else:
            if self.state is DeviceState.FAULTED and self.SAMPLING is SamplingMode.FRAME:
                self.state = DeviceState.RUNNING

    def frame_fault(self, err: Exception) -> None:
        """Record that the frame's update of this device raised ``err`` (FAULTED)."""
        self.faults += 1
        self.error = describe(err)
        self.error_at = time.time()
        self.state = DeviceState.FAULTED

    #: Whether the input manager updates this class's devices together, once per frame, by
    #: :meth:`update_frame_group` (set by a class that overrides it).
    FRAME_GROUP: ClassVar[bool] = False

    @classmethod
    def update_frame_group(cls, devices: Sequence[Input], frame: int) -> None:
        """:meth:`update_for_frame` of each of ``devices`` (all of this class, in name
        order): with :attr:`FRAME_GROUP`, the input manager calls this once per frame instead,
        so that a class can do together what each device would do alone (one clock reading,
        one pass over their arrays). Each device is still updated once per frame, and a
        device that raises is faulted alone."""
        for device in devices:
            device.update_for_frame(frame)

    @classmethod
    def prepare_frame_group(cls, devices: Sequence[Input]) -> None:
        """Between frames (after the frame's consumers, before the pause): work a class with
        :attr:`FRAME_GROUP` can do ahead for ``devices`` so that the frames need not (the
        default: nothing)."""

    def datagram_ledger(self) -> DatagramLedger | None:
        """The :class:`~gadgetctl.transport.udp.DatagramLedger` of a device that receives UDP
        datagrams (None for the others). From it the base class reports, for every such
        driver alike: the kernel's drops (:meth:`transport_dropped`), ``datagrams``,
        ``decoded``, ``bad_datagrams`` and ``kernel_dropped`` in :meth:`health`, and the
        ``undecodable`` state (:meth:`shown_state`)."""
        return None

    def transport_dropped(self) -> int:
        """What the transport lost before the driver could read it (a UDP socket's receive
        buffer overflowing, counted by the kernel), added to the dropped samples. The
        datagram ledger's count by default; a driver with another transport may override."""
        ledger = self.datagram_ledger()
        return ledger.kernel_dropped if ledger is not None else 0

    def undecodable(self) -> str | None:
        """Why the device receives data but decodes none of it; None when it decodes what it
        gets (or gets nothing). The datagram ledger's verdict; for a driver without one whose
        ``counters`` follow the record scanners' names (``records``, ``bad_records``,
        ``skipped_bytes``), bytes of junk read while no record has decoded yet."""
        ledger = self.datagram_ledger()
        if ledger is not None:
            return ledger.undecodable()
        counters = getattr(self, "counters", None)
        if not isinstance(counters, Mapping) or counters.get("records") != 0:
            return None
        junk, bad = counters.get("skipped_bytes") or 0, counters.get("bad_records") or 0
        if not junk:  # a byte stream's junk (a shared-memory segment's bad header is not)
            return None
        return f"{junk} bytes of junk skipped ({counted(bad, 'run')}), no record decoded"

    def shown_state(self) -> tuple[DeviceState, str | None]:
        """The state to show and its reason: the fault's error while FAULTED or
        RECONNECTING, UNDECODABLE (with the first decoding error) while RUNNING on data that
        does not decode, else ``state`` without a reason."""
        state = self.state
        if state in (DeviceState.FAULTED, DeviceState.RECONNECTING):
            return state, self.error
        if state is DeviceState.RUNNING:
            why = self.undecodable()
            if why:
                return DeviceState.UNDECODABLE, printable(why)
        return state, None

    def health(self) -> dict[str, int | float | str]:
        """The driver's health, one API for every device: the counters its driver keeps
        (``counters``: bad packets or records, bytes skipped, resynchronisations, kernel
        drops... as the driver names them; a datagram ledger's ``datagrams``, ``decoded``,
        ``bad_datagrams`` and ``kernel_dropped``, and ``decode_error``, the first error of
        the bad datagrams since the last good one), ``faults``, ``reconnects`` (restarts
        after a fault), ``dropped`` (samples over the per-frame cap and the kernel's drops)
        and, after a fault, ``last_fault`` (its reason) and ``last_fault_at`` (wall-clock
        time)."""
        counters = getattr(self, "counters", None)
        found: dict[str, int | float | str] = {}
        if isinstance(counters, Mapping):
            found = {
                str(k): v
                for k, v in counters.items()
                if isinstance(v, int | float) and not isinstance(v, bool)
            }
        ledger = self.datagram_ledger()
        if ledger is not None:
            found.update(ledger.counters())
            if ledger.first_error is not None:
                found["decode_error"] = ledger.first_error
        # (the ``dropped`` of :attr:`stats`, without counting the samples as it does too)
        dropped = self.store.dropped() + self.transport_dropped()
        found.update(faults=self.faults, reconnects=self.restarts, dropped=dropped)
        if self.error:
            found["last_fault"] = self.error
            if self.error_at is not None:
                found["last_fault_at"] = round(self.error_at, 3)
        return found

    @property
    def stats(self) -> DeviceStats:
        dropped = self.store.dropped() + self.transport_dropped()
        return DeviceStats(self.store.total(), dropped, self.faults, self.restarts, self.error)
