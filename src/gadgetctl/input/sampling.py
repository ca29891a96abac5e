"""Who calls a device's ``sample()``: its own thread, or a scheduler thread shared by many
cheap devices. Both keep the frame loop out of sampling (a device that blocks never delays
a frame), and both handle faults the same way.

Faults: when ``sample()`` raises, the device is marked FAULTED with the error kept,
``stop_sampling()`` releases what it holds, and after a back-off delay it is RECONNECTING
(``start_sampling()`` again) and then RUNNING. The delay grows by ``factor`` up to
``max_delay`` while restarts keep failing and returns to ``initial_delay`` after a good
sample. Other devices are not affected.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass

from gadgetctl.input.clock import now
from gadgetctl.input.device import DeviceState, Input
from gadgetctl.input.errors import describe


@dataclass(frozen=True)
class RestartPolicy:
    initial_delay: float = 0.1
    factor: float = 2.0
    # At most this long between two restart attempts, so a device that comes back (an
    # emulator restarted, a cable plugged in again) delivers samples within about a second
    # plus its own start-up time, however long it was away.
    max_delay: float = 1.0
    max_restarts: int | None = None  # None: keep trying

    def next_delay(self, delay: float) -> float:
        return min(delay * self.factor, self.max_delay)


class _Supervision:
    """Fault and restart bookkeeping shared by both runners."""

    __slots__ = ("delay", "device", "open", "policy")  # one per device

    def __init__(self, device: Input, policy: RestartPolicy) -> None:
        self.device = device
        self.policy = policy
        self.delay = policy.initial_delay
        self.open = False  # start_sampling succeeded and stop_sampling was not called since

    def start(self) -> None:
        """start_sampling() in the caller's thread; raises what it raises."""
        self.device.start_sampling()
        self.open = True
        self.device.state = DeviceState.RUNNING

    def close(self) -> str | None:
        """stop_sampling() once per successful start; returns its error, if any."""
        if not self.open:
            return None
        self.open = False
        try:
            self.device.stop_sampling()
        except Exception as err:
            return describe(err)
        return None

    def fault(self, error: BaseException) -> None:
        device = self.device
        device.faults += 1
        device.error = describe(error)
        device.error_at = time.time()
        device.state = DeviceState.FAULTED
        self.close()

    def may_restart(self) -> bool:
        limit = self.policy.max_restarts
        return limit is None or self.device.restarts < limit

    def restart(self) -> bool:
        """One restart attempt; on failure the device stays FAULTED with the new error."""
        device = self.device
        device.state = DeviceState.RECONNECTING
        try:
            device.start_sampling()
        except Exception as err:
            device.error = describe(err)
            device.error_at = time.time()  # the reason and the time of the last fault go together
            device.state = DeviceState.FAULTED
            self.delay = self.policy.next_delay(self.delay)
            return False
        self.open = True
        device.restarts += 1
        device.state = DeviceState.RUNNING
        return True

    def sampled(self) -> None:
        if self.delay != self.policy.initial_delay:
            self.delay = self.policy.initial_delay


class ThreadRunner:
    """Runs ``sample()`` in a loop in the device's own daemon thread."""

    def __init__(self, device: Input, policy: RestartPolicy) -> None:
        self.device = device
        self._sup = _Supervision(device, policy)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def start(self) -> None:
        self._sup.start()
        if self.device.samples_in_thread():
            self._thread = threading.Thread(
                target=self._loop, name=f"gadgetctl-sample-{self.device.name}", daemon=True
            )
            self._thread.start()

    def _loop(self) -> None:
        device, sup, stop = self.device, self._sup, self._stop
        interval = device.sample_interval
        while not stop.is_set():
            try:
                device.sample()
            except Exception as err:
                if stop.is_set():
                    break
                sup.fault(err)
                if not self._recover():
                    break
                continue
            sup.sampled()
            if interval > 0.0:
                stop.wait(interval)

    def _recover(self) -> bool:
        sup, stop = self._sup, self._stop
        while not stop.is_set():
            if not sup.may_restart():
                return False
            if stop.wait(sup.delay):
                return False
            if sup.restart():
                return True
        return False

    def stop(self, timeout: float) -> str | None:
        """Stop sampling and join the thread; returns a problem description, if any."""
        self._stop.set()
        thread = self._thread
        if thread is not None:
            thread.join(timeout)
        problem = self._sup.close()  # also unblocks a sample() stuck in I/O
        if thread is not None and thread.is_alive():
            thread.join(min(timeout, 0.5))
            if thread.is_alive():
                problem = f"sampling thread did not stop within {timeout:g} s"
        self.device.state = DeviceState.STOPPED
        return problem


_RUNNING = DeviceState.RUNNING


class ScheduledRunner:
    """A device served by a :class:`SharedScheduler` every ``sample_interval`` seconds."""

    __slots__ = ("_scheduler", "_sup", "device", "due", "interval")  # one per device

    def __init__(self, device: Input, policy: RestartPolicy, scheduler: SharedScheduler) -> None:
        self.device = device
        self._sup = _Supervision(device, policy)
        self._scheduler = scheduler
        self.interval = device.sample_interval if device.sample_interval > 0 else 0.002
        self.due = 0.0

    def start(self) -> None:
        self._sup.start()
        self._scheduler.add(self)

    def step(self, moment: float) -> None:
        """Called by the scheduler thread when ``due``."""
        device, sup = self.device, self._sup
        if device.state is _RUNNING:
            try:
                device.sample()
            except Exception as err:
                sup.fault(err)
                self.due = moment + sup.delay
                return
            if sup.delay != sup.policy.initial_delay:
                sup.sampled()
            due = moment + self.interval
            wanted = device.next_sample_due()
            self.due = wanted if wanted is not None and wanted > due else due
        elif not sup.may_restart():
            self.due = float("inf")
        elif sup.restart():
            self.due = moment
        else:
            self.due = moment + sup.delay

    def stop(self, timeout: float) -> str | None:
        self._scheduler.remove(self)
        problem = self._sup.close()
        self.device.state = DeviceState.STOPPED
        return problem


class SharedScheduler:
    """One daemon thread calling ``sample()`` of many non-blocking devices when due.

    The membership lock is held only to change or copy the set of runners and to mark the
    runner being stepped, never while a device samples: adding a runner never waits for a
    pass (holding the lock for whole passes made starting N devices wait N passes, O(N^2),
    Python's locks not being fair), and removing one waits for at most its own ``sample()``.
    """

    IDLE_WAKE = 0.1

    def __init__(self, clock: Callable[[], float] = now) -> None:
        self._clock = clock
        self._changed = threading.Condition(threading.Lock())
        self._wake = threading.Event()
        self._stop = threading.Event()
        self._members: dict[ScheduledRunner, None] = {}  # an insertion-ordered set
        self._order: tuple[ScheduledRunner, ...] | None = ()  # the runners of a pass; None: stale
        self._stepping: ScheduledRunner | None = None
        self._thread: threading.Thread | None = None
        self._held = 0  # hold() depth: no pass begins while it is above 0

    @contextlib.contextmanager
    def hold(self) -> Iterator[None]:
        """No device is stepped until the block ends (a pass under way stops after the
        device it is stepping): adding or removing many runners then costs one pass, not
        one per runner."""
        with self._changed:
            self._held += 1
        try:
            yield
        finally:
            with self._changed:
                self._held -= 1
            self._wake.set()

    def add(self, runner: ScheduledRunner) -> None:
        with self._changed:
            runner.due = self._clock()
            self._members[runner] = None
            self._order = None
            if self._thread is None or not self._thread.is_alive():
                self._stop.clear()
                self._thread = threading.Thread(
                    target=self._loop, name="gadgetctl-scheduler", daemon=True
                )
                self._thread.start()
        if not self._held:
            self._wake.set()

    def remove(self, runner: ScheduledRunner) -> None:
        """Take ``runner`` out; when this returns its device's sample() is not running."""
        with self._changed:
            if runner in self._members:
                del self._members[runner]
                self._order = None
            while self._stepping is runner and threading.current_thread() is not self._thread:
                self._changed.wait()

    def __len__(self) -> int:
        return len(self._members)

    def _loop(self) -> None:
        clock, changed, wake, stop, members = (
            self._clock,
            self._changed,
            self._wake,
            self._stop,
            self._members,
        )
        while not stop.is_set():
            if self._held:
                wake.wait(self.IDLE_WAKE)
                wake.clear()
                continue
            moment = clock()
            next_due = moment + self.IDLE_WAKE
            order = self._order
            if order is None:
                with changed:
                    order = self._order = tuple(members)
            for runner in order:
                if self._held or stop.is_set():
                    break  # resumed by the next pass
                if runner.due <= moment:
                    with changed:
                        if runner not in members:  # removed since the pass began
                            continue
                        self._stepping = runner
                    try:
                        runner.step(moment)
                    finally:
                        with changed:
                            self._stepping = None
                            changed.notify_all()
                if runner.due < next_due:
                    next_due = runner.due
            delay = next_due - clock()
            if delay > 0:
                wake.wait(delay)
                wake.clear()

    def shutdown(self, timeout: float = 1.0) -> None:
        self._stop.set()
        self._wake.set()
        thread = self._thread
        if thread is not None:
            thread.join(timeout)
        self._thread = None


class FrameRunner:
    """For devices without a sampling loop: start and stop only."""

    def __init__(self, device: Input, policy: RestartPolicy) -> None:
        self.device = device
        self._sup = _Supervision(device, policy)

    def start(self) -> None:
        self._sup.start()

    def stop(self, timeout: float) -> str | None:
        problem = self._sup.close()
        self.device.state = DeviceState.STOPPED
        return problem


Runner = ThreadRunner | ScheduledRunner | FrameRunner
