"""Sampling threads, the shared scheduler, faults and restarts, blocking devices, stopping
and Ctrl-C."""

import threading
import time
from pathlib import Path

import numpy as np
import pytest

from gadgetctl.input import Command, Digital, InputManager, ManagerOptions, RestartPolicy
from gadgetctl.input.device import DeviceState, SamplingMode
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.registry import DeviceRegistry
from gadgetctl.jccl.configload import load_configuration
from gadgetctl.jccl.repository import default_repository
from gadgetctl.jccl.searchpath import SearchPathEntry

CORPUS_DEFINITIONS = Path("/work/shared/corpus/vrjuggler/modules/vrjuggler/data/definitions")
PLUGINS = Path(__file__).parent / "data" / "plugins"
HEAD = (
    '<?xml version="1.0" encoding="UTF-8"?>\n<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
    '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="test">\n<elements>\n'
)
FAST_RESTART = RestartPolicy(initial_delay=0.005, factor=1.0, max_delay=0.005)


@pytest.fixture(scope="module")
def repo():
    repo = default_repository([CORPUS_DEFINITIONS] if CORPUS_DEFINITIONS.is_dir() else [])
    directory = PLUGINS / "Button_drv"
    repo.load_entry(SearchPathEntry(raw=str(directory), path=directory, origin="test"))
    return repo


@pytest.fixture
def make(repo, tmp_path):
    managers = []

    def build(body, devices=(), **options):
        registry = DeviceRegistry.with_builtins()
        for element_type, device_class in devices:
            registry.register_device(device_class, element_type)
        options.setdefault("retry_interval", None)
        options.setdefault("entry_points", False)
        path = tmp_path / f"test{len(managers)}.jconf"
        path.write_text(HEAD + body + "\n</elements>\n</configuration>\n")
        manager = InputManager(repo, ManagerOptions(**options), registry=registry)
        managers.append(manager)
        manager.configure(load_configuration([path]))
        assert not manager.pending(), [(p.name, p.message) for p in manager.pending()]
        return manager

    yield build
    for manager in managers:
        manager.shutdown()


def wait_for(predicate, timeout=5.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.005)
    return predicate()


class Counter(Command):
    """A threaded driver adding sequence numbers, so lost samples show as gaps."""

    sample_interval = 0.001

    def __init__(self):
        super().__init__()
        self.sequence = 0

    def sample(self):
        self.sequence += 1
        self.add_command_sample([self.sequence])


class EveryThirdFails(Digital):
    """Raises on every third sample; counts its restarts."""

    sample_interval = 0.001

    def __init__(self):
        super().__init__()
        self.calls = 0
        self.starts = 0
        self.stops = 0

    def start_sampling(self):
        self.starts += 1

    def sample(self):
        self.calls += 1
        if self.calls % 3 == 0:
            raise OSError("device unplugged")
        self.add_digital_sample([self.calls % 2])

    def stop_sampling(self):
        self.stops += 1


class ScheduledEveryThirdFails(EveryThirdFails):
    SAMPLING = SamplingMode.SCHEDULED
    sample_interval = 0.002


@pytest.mark.timeout(20)
@pytest.mark.parametrize(
    "faulty", [EveryThirdFails, ScheduledEveryThirdFails], ids=["thread", "scheduler"]
)
def test_a_faulting_device_is_restarted_and_the_others_lose_no_samples(make, faulty):
    body = """
    <command_device name="Counter" version="1"/>
    <button_device name="Faulty" version="1"/>
    <waveform_device name="Wave" version="1"><rate>500.0</rate><button_period>0.1</button_period><event_period>0.0</event_period></waveform_device>
    <digital_proxy name="Faulty Proxy" version="1"><device>Faulty</device><unit>0</unit></digital_proxy>"""
    m = make(
        body, devices=[("command_device", Counter), ("button_device", faulty)], restart=FAST_RESTART
    )
    faulty_device, counter, wave = m.device("Faulty"), m.device("Counter"), m.device("Wave")
    sequence, stamps = [], []
    deadline = time.monotonic() + 10
    while (faulty_device.restarts < 5 or len(stamps) < 200) and time.monotonic() < deadline:
        m.update()
        sequence.extend(s.values[0] for s in counter.store.frame(DeviceKind.COMMAND))
        stamps.extend(wave.store.frame(DeviceKind.DIGITAL).timestamps())
        time.sleep(0.01)
    status = {s.name: s for s in m.statuses()}["Faulty"]
    m.shutdown()  # the counters below are read once the sampling threads are gone
    assert faulty_device.restarts >= 5
    assert faulty_device.faults >= faulty_device.restarts
    assert faulty_device.error == "OSError: device unplugged"
    assert (
        faulty_device.stops >= faulty_device.restarts
        and faulty_device.starts == faulty_device.restarts + 1
    )
    assert sequence == list(range(1, len(sequence) + 1))  # the threaded neighbour lost nothing
    assert np.allclose(np.diff(stamps), 1 / 500.0)  # nor did the scheduled one
    assert counter.store.dropped() == 0 and wave.store.dropped() == 0
    assert status.stats.faults >= 5 and status.stats.last_error == "OSError: device unplugged"


class GivesUp(Digital):
    sample_interval = 0.001

    def sample(self):
        raise OSError("gone for good")


@pytest.mark.timeout(10)
def test_restarts_stop_at_the_policys_limit_and_the_status_keeps_the_error(make):
    m = make(
        '<button_device name="Dead" version="1"/>',
        devices=[("button_device", GivesUp)],
        restart=RestartPolicy(initial_delay=0.001, factor=2.0, max_delay=0.01, max_restarts=3),
    )
    device = m.device("Dead")
    assert wait_for(lambda: device.restarts == 3 and device.faults == 4)
    time.sleep(0.05)
    assert device.restarts == 3 and device.state is DeviceState.FAULTED
    status = {s.name: s for s in m.statuses()}["Dead"]
    assert (
        status.state == "faulted"
        and status.reason == "OSError: gone for good"
        and status.code == "DRV042"
    )


class Blocking(Digital):
    """A driver whose read blocks until the device is closed."""

    def __init__(self):
        super().__init__()
        self.unblock = threading.Event()

    def sample(self):
        self.unblock.wait(30)

    def stop_sampling(self):
        self.unblock.set()  # like closing the socket a read waits on


class Stubborn(Digital):
    """A driver that ignores being stopped: its read ends only when the test lets it go
    (or after 10 s), not when the device is closed."""

    released = threading.Event()

    def sample(self):
        Stubborn.released.wait(10.0)


@pytest.mark.timeout(20)
def test_a_blocking_device_never_delays_a_frame_and_stops_within_the_timeout(make):
    m = make(
        '<button_device name="Slow" version="1"/><command_device name="Counter" version="1"/>',
        devices=[("button_device", Blocking), ("command_device", Counter)],
        stop_timeout=0.2,
    )
    worst = 0.0
    for _ in range(20):
        start = time.perf_counter()
        m.update()
        worst = max(worst, time.perf_counter() - start)
        time.sleep(0.005)
    assert worst < 1.0  # the blocked read lasts 30 s: a frame that waited for it would show
    assert m.device("Counter").store.total() > 0
    start = time.perf_counter()
    m.shutdown()
    assert time.perf_counter() - start < 2.0
    assert m.device("Slow").state is DeviceState.STOPPED


@pytest.mark.timeout(20)
def test_a_thread_that_does_not_stop_is_reported_and_abandoned(make):
    Stubborn.released.clear()
    m = make(
        '<button_device name="Stubborn" version="1"/>',
        devices=[("button_device", Stubborn)],
        stop_timeout=0.1,
    )
    time.sleep(0.05)
    start = time.perf_counter()
    m.shutdown()
    try:
        assert time.perf_counter() - start < 5.0  # not the 10 s the stubborn read lasts
        assert any(
            d.code == "DRV041" and "did not stop within 0.1 s" in d.message for d in m.diagnostics
        )
    finally:
        Stubborn.released.set()  # the abandoned thread ends now, not during later tests


@pytest.mark.timeout(20)
def test_ctrl_c_in_the_frame_loop_stops_everything(make):
    m = make(
        '<button_device name="Slow" version="1"/><command_device name="Counter" version="1"/>'
        '<waveform_device name="Wave" version="1"/>',
        devices=[("button_device", Blocking), ("command_device", Counter)],
    )
    threads_before = {t for t in threading.enumerate() if t.name.startswith("gadgetctl-")}
    assert threads_before

    def interrupt(manager):
        if manager.frame == 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        m.run(100.0, on_frame=interrupt)
    assert all(d.state is DeviceState.STOPPED for d in m.devices.values())
    assert wait_for(lambda: not any(t.is_alive() for t in threads_before), 3.0)


@pytest.mark.timeout(30)
def test_run_paces_frames_at_the_rate_and_stops_on_request(make):
    """Frames are paced from run()'s start: the k-th frame never begins before k - 1
    periods have passed (a loaded machine may make frames late, never early), and a stop
    requested during a frame ends the run before the next one, without waiting out the
    period. (Judged by order and lower bounds only, which no load can break.)"""
    m = make('<waveform_device name="Wave" version="1"><rate>1000.0</rate></waveform_device>')
    times: list[float] = []
    before = time.perf_counter()
    frames = m.run(50.0, frames=15, on_frame=lambda manager: times.append(time.perf_counter()))
    assert frames == len(times) == 15
    assert all(t - before >= k / 50 for k, t in enumerate(times))

    stop = threading.Event()
    seen: list[int] = []

    def stop_at_the_fifth(manager) -> None:
        seen.append(manager.frame)
        if len(seen) == 5:
            stop.set()

    assert m.run(20.0, stop=stop, on_frame=stop_at_the_fifth) == 5 == len(seen)


@pytest.mark.timeout(20)
def test_threaded_plugin_device_samples_between_frames(repo, tmp_path):
    path = tmp_path / "button.jconf"
    path.write_text(
        HEAD
        + f"""
    <input_manager name="IM" version="2"><driver_path>{PLUGINS}</driver_path><driver>Button_drv</driver></input_manager>
    <button_device name="Button" version="1"/>
    <digital_proxy name="P" version="1"><device>Button</device><unit>0</unit></digital_proxy>
    </elements></configuration>"""
    )
    with InputManager(repo, ManagerOptions(retry_interval=None, entry_points=False)) as m:
        m.configure(load_configuration([path]))
        device = m.device("Button")
        assert device is not None and device.state is DeviceState.RUNNING
        time.sleep(0.1)
        m.update()
        assert len(device.store.frame(DeviceKind.DIGITAL)) >= 5  # every sample since the last frame
        assert device.opened == 1
    assert device.closed == 1 and device.state is DeviceState.STOPPED
