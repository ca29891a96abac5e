"""Start-up of the input manager is linear in the number of elements (issue 12 item 2).

The timings live in `bench/bench_startup.py`; these tests pin the structure that makes
start-up linear: how often the per-element work runs, and that starting a device never
waits for the shared scheduler to finish a pass over the others.
"""

from __future__ import annotations

import threading
from pathlib import Path

import pytest

from gadgetctl.input import Digital, InputManager, ManagerOptions, RestartPolicy
from gadgetctl.input.device import SamplingMode
from gadgetctl.input.proxies import Proxy
from gadgetctl.input.sampling import ScheduledRunner, SharedScheduler
from gadgetctl.input.testing import wait_until
from gadgetctl.jccl.configload import load_configuration
from gadgetctl.jccl.repository import default_repository
from gadgetctl.monitor.session import MonitorSession

HEAD = (
    '<?xml version="1.0" encoding="UTF-8"?>\n<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
    '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="scale">\n<elements>\n'
)
GROUP = """<alias name="Alias {i}" version="1"><proxy>Wave {i} Position</proxy></alias>
<position_proxy name="Wave {i} Position" version="1"><device>Wave {i}</device><unit>0</unit></position_proxy>
<digital_proxy name="Wave {i} Button" version="1"><device>Wave {i}</device><unit>0</unit></digital_proxy>
<waveform_device name="Wave {i}" version="1"><rate>30.0</rate><button_period>0.5</button_period><position_path>circle</position_path></waveform_device>
"""


def write_groups(path: Path, groups: int) -> Path:
    """``groups`` x (alias, two proxies, device), each written before what it points at."""
    path.write_text(
        HEAD + "".join(GROUP.format(i=i) for i in range(groups)) + "</elements>\n</configuration>\n"
    )
    return path


@pytest.fixture(scope="module")
def repo():
    return default_repository()


@pytest.mark.timeout(120)
def test_configuring_works_on_each_element_a_bounded_number_of_times(repo, tmp_path, monkeypatch):
    groups = 300
    configuration = load_configuration([write_groups(tmp_path / "groups.jconf", groups)])
    refreshes = tries = 0
    real_refresh, real_try = Proxy.refresh, InputManager._try

    def counted_refresh(self, *args, **kwargs):
        nonlocal refreshes
        refreshes += 1
        return real_refresh(self, *args, **kwargs)

    def counted_try(self, element):
        nonlocal tries
        tries += 1
        return real_try(self, element)

    monkeypatch.setattr(Proxy, "refresh", counted_refresh)
    monkeypatch.setattr(InputManager, "_try", counted_try)
    manager = InputManager(
        repo, ManagerOptions(start_devices=False, retry_interval=None, entry_points=False)
    )
    try:
        manager.configure(configuration)
        assert not manager.pending(), [p.message for p in manager.pending()[:3]]
        assert len(manager.devices) == groups and len(manager.proxies) == 2 * groups
        assert len(manager.aliases) == groups
        proxies, elements = 2 * groups, 4 * groups
        # Each proxy is bound when configured, when its device arrives and once at the end of
        # the reconfiguration; rebinding every proxy for every device made this 2 * groups^2.
        assert refreshes <= 3 * proxies, refreshes
        # Each element is tried at most twice (an alias before its proxy, then after it).
        assert tries <= 2 * elements, tries
        position = manager.proxy("Alias 7")
        assert position is not None and position.device is manager.device("Wave 7")
        assert manager.proxy("Wave 7 Button").device is manager.device("Wave 7")
    finally:
        manager.shutdown()


@pytest.mark.timeout(120)
def test_status_of_one_element_is_looked_up_not_searched(repo, tmp_path, monkeypatch):
    configuration = load_configuration([write_groups(tmp_path / "groups.jconf", 50)])
    manager = InputManager(
        repo, ManagerOptions(start_devices=False, retry_interval=None, entry_points=False)
    )
    try:
        manager.configure(configuration)
        expected = {s.name: s for s in manager.statuses()}
        monkeypatch.setattr(
            InputManager, "statuses", lambda self: pytest.fail("status() built every status")
        )
        for name, status in expected.items():
            assert manager.status(name) == status
        assert manager.status("Nobody") is None
    finally:
        manager.shutdown()


class Held(Digital):
    """A scheduled device whose sample() waits until the test releases it."""

    SAMPLING = SamplingMode.SCHEDULED
    sample_interval = 0.001

    def __init__(
        self, entered: threading.Event | None = None, release: threading.Event | None = None
    ) -> None:
        super().__init__()
        self.entered = entered
        self.release = release
        self.samples = 0

    def sample(self) -> None:
        if self.entered is not None and self.release is not None:
            self.entered.set()
            self.release.wait(30)
        self.samples += 1
        self.add_digital_sample([self.samples % 2])


@pytest.mark.timeout(60)
def test_starting_a_device_never_waits_for_the_scheduler_to_sample_the_others():
    scheduler = SharedScheduler()
    entered, release = threading.Event(), threading.Event()
    held = ScheduledRunner(Held(entered, release), RestartPolicy(), scheduler)
    fresh = ScheduledRunner(Held(), RestartPolicy(), scheduler)
    added, removed = threading.Event(), threading.Event()
    try:
        held.start()
        assert entered.wait(10), "the scheduler never sampled the held device"
        # While one device is inside sample(), adding another returns at once (it used to
        # wait for the whole pass, so N devices waited N passes to start).
        threading.Thread(target=lambda: (fresh.start(), added.set()), daemon=True).start()
        assert added.wait(20), "adding a device waited for another device's sample()"
        # Removing the held device waits for its sample() to return, never longer.
        threading.Thread(
            target=lambda: (scheduler.remove(held), removed.set()), daemon=True
        ).start()
        assert not removed.wait(0.2)
        release.set()
        assert removed.wait(20)
        assert len(scheduler) == 1
        sampled = fresh.device.samples
        assert wait_until(lambda: fresh.device.samples > sampled + 3, timeout=20)
    finally:
        release.set()
        scheduler.shutdown()


@pytest.mark.timeout(60)
def test_a_held_scheduler_steps_no_device_until_released():
    scheduler = SharedScheduler()
    runner = ScheduledRunner(Held(), RestartPolicy(), scheduler)
    try:
        runner.start()
        assert wait_until(lambda: runner.device.samples > 3, timeout=20)
        with scheduler.hold():
            held_at = runner.device.samples  # a pass under way ends after this device
            later = ScheduledRunner(Held(), RestartPolicy(), scheduler)
            later.start()  # added while held: not stepped either
            assert not threading.Event().wait(0.3)
            assert runner.device.samples <= held_at + 1 and later.device.samples == 0
        assert wait_until(lambda: later.device.samples > 3, timeout=20)
    finally:
        scheduler.shutdown()


@pytest.mark.timeout(300)
def test_a_large_configuration_starts_and_runs_its_first_frame(tmp_path):
    """A hang guard: 1,500 devices with 3,000 proxies and 1,500 aliases (6,000 elements) took
    about half a minute before; every proxy and alias is bound by the first frame."""
    groups = 1500
    path = write_groups(tmp_path / "large.jconf", groups)
    manager, configuration = InputManager.from_files(
        [path], options=ManagerOptions(retry_interval=None, entry_points=False)
    )
    session = MonitorSession(manager, configuration)
    try:
        assert len(session.start()) == 4 * groups
        frame = session.step()
        assert frame.number == 1
        assert not manager.pending()
        view = session.element_view(f"Alias {groups - 1}")
        assert view.state == "active" and view.target == f"Wave {groups - 1} Position"
    finally:
        manager.shutdown()
