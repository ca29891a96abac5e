"""The waveform device: exact schedule, deterministic signals, batches, configuration
errors; and every built-in device class agreeing with its definition."""

import itertools
import math
import time
from pathlib import Path

import numpy as np
import pytest

from gadgetctl.input import InputManager, ManagerOptions
from gadgetctl.input.clock import now
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.registry import DeviceRegistry, kind_disagreements
from gadgetctl.input.samples import SampleBatch
from gadgetctl.jccl.configload import load_configuration
from gadgetctl.jccl.repository import default_repository
from gadgetctl.resources import definitions_dir

CORPUS_DEFINITIONS = Path("/work/shared/corpus/vrjuggler/modules/vrjuggler/data/definitions")
HEAD = (
    '<?xml version="1.0" encoding="UTF-8"?>\n<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
    '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="test">\n<elements>\n'
)
WAVE = """<waveform_device name="{name}" version="1">
  <rate>{rate}</rate><seed>{seed}</seed>
  <analog_waveform>sine</analog_waveform><analog_waveform>triangle</analog_waveform>
  <analog_waveform>square</analog_waveform><analog_waveform>noise</analog_waveform>
  <analog_frequency>2.0</analog_frequency><analog_frequency>1.0</analog_frequency><analog_frequency>4.0</analog_frequency>
  <min>0.0</min><max>10.0</max>
  <button_period>0.1</button_period>
  <position_path>circle</position_path><position_path>spin</position_path><position_path>figure_eight</position_path>
  <position_period>1.0</position_period><position_period>1.0</position_period><position_period>1.0</position_period>
  <position_radius>0.5</position_radius>
  <event_period>0.25</event_period>
</waveform_device>"""


@pytest.fixture(scope="module")
def repo():
    return default_repository([CORPUS_DEFINITIONS] if CORPUS_DEFINITIONS.is_dir() else [])


@pytest.fixture
def make(repo, tmp_path):
    managers = []

    def build(body, **options):
        path = tmp_path / f"test{len(managers)}.jconf"
        path.write_text(HEAD + body + "\n</elements>\n</configuration>\n")
        manager = InputManager(
            repo, ManagerOptions(retry_interval=None, entry_points=False, **options)
        )
        managers.append(manager)
        manager.configure(load_configuration([path]))
        return manager

    yield build
    for manager in managers:
        manager.shutdown()


def test_the_definition_is_ours_and_has_the_three_required_parents(repo):
    definition = repo.get("waveform_device")
    assert (definitions_dir() / "waveform_device.jdef").is_file()
    assert {"analog_device", "digital_device", "positional_device"} <= set(definition.parents)
    assert repo.is_a("waveform_device", "input_device")


def test_every_builtin_device_agrees_with_its_definition(repo):
    for registration in DeviceRegistry.with_builtins():
        assert registration.element_type in repo
        assert kind_disagreements(registration.element_type, registration.kinds, repo) == []


def test_signals_are_deterministic_for_a_seed_and_independent_of_batching(make):
    m = make(
        WAVE.format(name="A", rate=1000.0, seed=7)
        + WAVE.format(name="B", rate=1000.0, seed=7)
        + WAVE.format(name="C", rate=1000.0, seed=8),
        start_devices=False,
    )
    a, b, c = m.device("A"), m.device("B"), m.device("C")
    whole = a.compute(0, 300).data
    parts = [b.compute(0, 120).data, b.compute(120, 180).data]
    for kind in (DeviceKind.ANALOG, DeviceKind.DIGITAL, DeviceKind.POSITION, DeviceKind.HAT):
        np.testing.assert_array_equal(whole[kind], np.concatenate([p[kind] for p in parts]))
    other = c.compute(0, 300).data[DeviceKind.ANALOG]
    np.testing.assert_array_equal(
        other[:, :3], whole[DeviceKind.ANALOG][:, :3]
    )  # only noise depends on the seed
    assert not np.array_equal(other[:, 3], whole[DeviceKind.ANALOG][:, 3])


def test_wave_shapes_buttons_and_paths(make):
    m = make(WAVE.format(name="W", rate=1000.0, seed=0), start_devices=False)
    device = m.device("W")
    block = device.compute(0, 1000)  # one second
    analog = block.data[DeviceKind.ANALOG]
    t = np.arange(1000) / 1000.0
    np.testing.assert_allclose(analog[:, 0], 5.0 + 5.0 * np.sin(2 * np.pi * 2.0 * t), atol=1e-9)
    assert analog[250, 1] == pytest.approx(10.0) and analog[0, 1] == pytest.approx(
        5.0
    )  # triangle, 1 Hz
    assert set(np.round(analog[:, 2], 9)) == {0.0, 10.0}  # square
    assert (
        analog[:, 3].min() >= 0.0 and analog[:, 3].max() <= 10.0 and analog[:, 3].std() > 1.0
    )  # noise
    buttons = block.data[DeviceKind.DIGITAL][:, 0]
    assert list(buttons[:100]) == [1] * 50 + [0] * 50  # on for the first half of each 0.1 s period
    positions = block.data[DeviceKind.POSITION]
    radius = np.linalg.norm(positions[:, 0, [0, 2], 3] - [0.0, 0.0], axis=1)
    np.testing.assert_allclose(radius, 0.5)  # circle around the default center (0, 1.5, 0)
    np.testing.assert_allclose(positions[:, 0, 1, 3], 1.5)
    spin = positions[:, 1]
    np.testing.assert_allclose(spin[:, :3, 3], np.tile([0.0, 1.5, 0.0], (1000, 1)))
    np.testing.assert_allclose(spin[250, :3, :3] @ spin[250, :3, :3].T, np.eye(3), atol=1e-12)
    assert spin[250, 0, 2] == pytest.approx(1.0)  # a quarter turn about +Y
    eight = positions[:, 2, :3, 3]
    assert eight[0] == pytest.approx([0.0, 1.5, 0.0]) and eight[500] == pytest.approx(
        [0.0, 1.5, 0.0], abs=1e-12
    )
    assert list(block.data[DeviceKind.HAT][::250, 0]) == [0, 1, 2, 4]
    assert block.events == [(250, 1), (500, 2), (750, 3)]


@pytest.mark.timeout(20)
def test_samples_follow_the_devices_own_schedule_exactly(make):
    m = make(WAVE.format(name="W", rate=1000.0, seed=0))
    device = m.device("W")
    stamps = []
    batches = 0
    start = time.perf_counter()
    while time.perf_counter() - start < 0.4:
        time.sleep(0.02)
        m.update()
        frame = device.store.frame(DeviceKind.POSITION)
        batches += sum(isinstance(c, SampleBatch) for c in frame.chunks)
        stamps.extend(frame.timestamps())
    elapsed = time.perf_counter() - device.t0
    assert batches > 0 and len(stamps) > 300
    np.testing.assert_allclose(
        np.diff(stamps), 1e-3, rtol=0, atol=1e-9
    )  # exact spacing, nothing lost
    np.testing.assert_allclose(stamps[0], device.t0, atol=1e-9)
    assert stamps[-1] <= time.perf_counter()  # never a sample from the future
    assert abs(len(stamps) - elapsed * 1000) < 50
    commands = [int(s.values[0]) for s in device.store.frame(DeviceKind.COMMAND)]
    assert all(isinstance(c, int) for c in commands)


@pytest.mark.timeout(20)
def test_rates_up_to_and_beyond_one_kilohertz(make):
    m = make(WAVE.format(name="Fast", rate=5000.0, seed=0))
    device = m.device("Fast")
    m.update()
    time.sleep(0.2)
    m.update()
    frame = device.store.frame(DeviceKind.ANALOG)
    assert len(frame) >= 800
    np.testing.assert_allclose(np.diff(frame.timestamps()), 1 / 5000.0, atol=1e-9)


@pytest.mark.parametrize(
    "body, message",
    [
        (
            "<analog_waveform>sawtooth</analog_waveform>",
            "analog_waveform 'sawtooth' is not one of sine, triangle, square, noise",
        ),
        ("<rate>0</rate>", "rate must be greater than 0"),
        (
            "<position_path>circle</position_path><position_period>-1</position_period>",
            "position_period must be greater than 0",
        ),
    ],
)
def test_configuration_errors_leave_the_device_pending_with_the_reason(make, body, message):
    m = make(f'<waveform_device name="Bad" version="1">{body}</waveform_device>')
    pending = {p.name: p for p in m.pending()}
    assert pending["Bad"].code == "DRV032" and message in pending["Bad"].message


def test_defaults_give_one_unit_per_listed_channel(make):
    m = make(
        '<waveform_device name="D" version="1"><analog_waveform>sine</analog_waveform>'
        "<analog_waveform>sine</analog_waveform><analog_frequency>3.0</analog_frequency></waveform_device>",
        start_devices=False,
    )
    device = m.device("D")
    assert [c.frequency for c in device.analog] == [3.0, 1.0]  # the second takes the default
    assert device.rate == 100.0 and device.event_period == 1.0 and device.positions == []
    assert math.isclose(device.analog_min, -1.0) and math.isclose(device.analog_max, 1.0)


@pytest.mark.timeout(30)
def test_a_frame_carries_every_sample_due_at_its_swap(make):
    # frames publish before they swap: the newest sample of a frame is the last one whose
    # time had come when the frame swapped, whatever the scheduler did meanwhile
    m = make(WAVE.format(name="Now", rate=1000.0, seed=0))
    device = m.device("Now")
    checked = 0
    for _ in range(50):
        time.sleep(0.003)
        before = now()
        m.update()
        frame = device.store.frame(DeviceKind.POSITION)
        if not frame:
            continue
        newest = frame.newest.timestamp
        assert newest <= device.store.swapped_at  # never a sample from the future
        # every sample due before the frame began is in it (the next one was not yet due)
        assert newest > before - 1e-3 - 1e-9
        checked += 1
    assert checked >= 40


@pytest.mark.timeout(30)
def test_without_frames_the_scheduler_still_publishes_and_nothing_is_lost(make):
    from gadgetctl.input import waveform
    from gadgetctl.input.testing import wait_until

    m = make(WAVE.format(name="Alone", rate=1000.0, seed=0))
    device = m.device("Alone")
    m.update()  # a frame published: the scheduler stands back for FRAME_GRACE
    published = device.store.total(DeviceKind.POSITION)
    # no more frames: after the grace the scheduler publishes what comes due
    assert wait_until(
        lambda: device.store.total(DeviceKind.POSITION) > published + 50,
        timeout=waveform.FRAME_GRACE + 10,
    )
    m.update()
    stamps = device.store.frame(DeviceKind.POSITION).timestamps()
    np.testing.assert_allclose(np.diff(stamps), 1e-3, rtol=0, atol=1e-9)
    assert device.store.dropped() == 0


def test_waveform_devices_are_updated_together_at_one_instant_and_fault_alone(make):
    """The manager updates the waveform devices of a frame as one group (one clock reading
    for all of them): each swaps once per frame at the same instant with every sample due by
    then; one whose own frame update raises (its frame is its own when an event comes due)
    is faulted while the others go on delivering."""
    body = "\n".join(WAVE.format(name=f"Group {i}", rate=1000.0, seed=i) for i in range(4))
    m = make(body)
    devices = [m.device(f"Group {i}") for i in range(4)]

    def broken(moment: float) -> None:
        raise RuntimeError("broken on purpose")

    checked = 0
    for frame in range(30):
        time.sleep(0.003)
        before = now()
        if frame == 20:
            devices[3]._update_at = broken  # from now on this device's frame update raises
        m.update()
        working = devices[:3] if frame >= 20 else devices
        instants = {d.store.swapped_at for d in working}
        assert len(instants) == 1  # one instant for the whole group
        instant = instants.pop()
        for device in working:
            frame_samples = device.store.frame(DeviceKind.POSITION)
            if frame_samples:
                assert before - 1e-3 - 1e-9 < frame_samples.newest.timestamp <= instant
                checked += 1
    assert checked >= 60
    # its frame is its own (where the update raises) when its next event comes due, within an
    # event period (0.25 s): frames go on until then
    deadline = now() + 5.0
    while devices[3].state.value != "faulted" and now() < deadline:
        time.sleep(0.003)
        m.update()
    assert devices[3].state.value == "faulted" and "broken on purpose" in devices[3].error
    assert all(d.state.value == "running" for d in devices[:3])


def test_a_backlog_is_computed_in_one_block(make):
    """Issue 27: the first frame after a long start-up (or a stalled frame loop) computed a
    block per half second of backlog; 10,000 devices paid for each second of start-up."""
    from gadgetctl.input.device import DeviceState

    m = make(
        '<waveform_device name="W" version="1"><rate>1000</rate>'
        "<position_path>circle</position_path><event_period>0</event_period></waveform_device>",
        start_devices=False,
    )
    device = m.device("W")
    device.start_sampling()
    device.state = DeviceState.RUNNING
    device.t0 -= 2.0  # two seconds of samples due at once: four blocks' worth
    computed = []
    real = device.compute
    device.compute = lambda start, count: computed.append(count) or real(start, count)
    device.update_data()
    frame = device.store.frame(DeviceKind.POSITION)
    assert len(computed) == 1 and computed[0] >= frame.count >= 2000
    stamps = np.concatenate([np.asarray(c.timestamps) for c in frame.chunks])
    assert np.array_equal(stamps, device.t0 + np.arange(frame.count) / 1000.0)
    assert frame.count == device.next_index


def test_standing_in_for_frames_backs_off_when_it_costs_more_than_its_share():
    """Issue 27: with 10,000 devices a pass standing in for frames cost about a second; a
    pass every FRAME_GRACE while a long first frame was written slowed that frame (the
    scheduler held the GIL), which let more passes in. Publishing is now paid from a budget
    that fills at STAND_IN_SHARE of a second per second, and the grid of looks widens while
    the looks cost more than that share, and comes back once they are cheap."""
    from gadgetctl.input import waveform

    stand_in = waveform._StandIn()
    assert stand_in.spacing == waveform.FRAME_GRACE
    # a burst is allowed at once, then the budget runs out within the same instant
    moment = 100.0
    published = 0
    while stand_in.may_publish(moment):
        stand_in.spent(moment, 0.001, published=True)
        published += 1
    assert published == round(waveform.STAND_IN_BURST / 0.001)
    # it fills at the share allowed (0.3 s later: 0.03 s of publishing), up to the burst
    moment += 0.3
    again = 0
    while stand_in.may_publish(moment):
        stand_in.spent(moment, 0.001, published=True)
        again += 1
    assert again == pytest.approx(0.3 * waveform.STAND_IN_SHARE / 0.001, abs=1)
    moment += 1000.0
    assert stand_in.may_publish(moment) and stand_in.budget == waveform.STAND_IN_BURST
    # looks that take a whole spacing (a full core) widen the grid by the share over
    stand_in = waveform._StandIn()
    for _ in range(10):
        stand_in.spent(moment, waveform.FRAME_GRACE / 10, published=False)
        moment += waveform.FRAME_GRACE / 10
    assert stand_in.spacing == pytest.approx(waveform.FRAME_GRACE / waveform.STAND_IN_SHARE)
    # the next look of a device is on the wider grid: one pass, not one per FRAME_GRACE
    look = stand_in.next_look(moment)
    assert look - moment >= stand_in.spacing
    assert look / stand_in.spacing == pytest.approx(round(look / stand_in.spacing))
    # the spacing never grows past the cap, whatever a look costs
    stand_in.spent(moment + stand_in.spacing, 100.0, published=False)
    assert stand_in.spacing == waveform.STAND_IN_MAX_SPACING
    # cheap looks bring it back to FRAME_GRACE
    moment += 200.0
    for _ in range(5):
        moment += stand_in.spacing
        stand_in.spent(moment, 1e-4, published=False)
    assert stand_in.spacing == waveform.FRAME_GRACE


def test_before_the_first_frame_the_scheduler_waits_a_grace_before_standing_in(make):
    """A device's start counts as its last frame: the scheduler does not publish sample by
    sample while a large configuration is still being set up around it."""
    from gadgetctl.input import waveform

    m = make(WAVE.format(name="Early", rate=1000.0, seed=0))
    device = m.device("Early")
    assert device.next_sample_due() >= device.t0 + waveform.FRAME_GRACE


def test_each_input_manager_has_its_own_stand_in(make):
    """A manager of 10,000 devices that widened its grid and spent its budget leaves another
    manager's devices (a test after a large one, a second configuration) as they were."""
    from gadgetctl.input import waveform

    first = make(WAVE.format(name="One", rate=100.0, seed=0)).device("One")
    second = make(WAVE.format(name="Two", rate=100.0, seed=0)).device("Two")
    assert first._stand_in is not second._stand_in
    first._stand_in.spacing = waveform.STAND_IN_MAX_SPACING
    first._stand_in.budget = -1.0
    assert second._stand_in.spacing == waveform.FRAME_GRACE
    assert second._stand_in.may_publish(waveform.now())


def test_a_running_device_sets_few_enough_attributes_to_share_its_classs_keys(make):
    """Issue 27: a waveform device with more than 29 instance attributes has a dictionary of
    its own keys (CPython shares one key table per class up to that many): 1,600 bytes
    instead of 300, 12 MB for 10,000 devices. What only a fault sets is a class default."""
    m = make(WAVE.format(name="Wave", rate=1000.0, seed=1))
    device = m.device("Wave")
    for _ in range(5):
        time.sleep(0.002)
        m.update()
    assert device.store.total(DeviceKind.ANALOG) > 0
    assert device._noise_streams  # its noise channel made them
    assert len(vars(device)) <= 29
    assert (device.faults, device.restarts, device.error, device.error_at) == (0, 0, None, None)


def test_devices_without_position_filters_share_the_empty_chain(make):
    """Issue 27: each device and proxy without filters had a chain of its own (1.8 MB for
    10,000 of each); the empty chain is one, and leaves positions as they are."""
    from gadgetctl.input.filters import NO_FILTERS

    body = "\n".join(WAVE.format(name=f"Shared {i}", rate=100.0, seed=i) for i in range(2))
    m = make(body, start_devices=False)
    chains = [m.device(f"Shared {i}").position_filters for i in range(2)]
    assert chains[0] is chains[1] is NO_FILTERS and not NO_FILTERS
    matrices = np.arange(32.0).reshape(2, 4, 4)
    assert NO_FILTERS.apply(matrices) is matrices


def test_devices_configured_alike_share_their_channel_lists(make):
    """Issue 27 goal 3: devices written alike (the seed aside) share the lists of their
    analog channels, button periods and position paths (a copy each was 1.7 MB for 10,000
    devices); a device written otherwise has its own, and the shared ones stay as they were."""
    body = "\n".join(WAVE.format(name=f"Alike {i}", rate=100.0, seed=i) for i in range(3))
    other = WAVE.replace("<button_period>0.1</button_period>", "").replace(
        "<position_path>spin</position_path>", ""
    )
    body += "\n" + other.format(name="Other", rate=100.0, seed=7)
    m = make(body, start_devices=False)
    alike = [m.device(f"Alike {i}") for i in range(3)]
    different = m.device("Other")
    for name in ("analog", "button_periods", "positions"):
        lists = [getattr(d, name) for d in alike]
        assert lists[0] is lists[1] is lists[2]
    assert len(alike[0].analog) == len(different.analog) == 4
    assert (len(alike[0].button_periods), len(different.button_periods)) == (1, 0)
    assert (len(alike[0].positions), len(different.positions)) == (3, 2)
    assert [d.seed for d in alike] == [0, 1, 2]
    first = alike[0].compute(0, 8).items
    again = make(WAVE.format(name="Alone", rate=100.0, seed=0), start_devices=False)
    alone = again.device("Alone").compute(0, 8).items
    for (kind, values), (kind_alone, values_alone) in zip(first, alone, strict=True):
        assert kind is kind_alone and np.array_equal(values, values_alone)


@pytest.mark.parametrize(
    "rate, period", [(10.0, 1.0), (1000.0, 0.25), (7.3, 0.3), (120.0, 2.0), (3.0, 1.0 / 3.0)]
)
def test_every_event_is_in_exactly_one_block_however_the_samples_are_split(make, rate, period):
    """Event n falls on the first sample at or after n * event_period; split into blocks
    anywhere (a block may start on an event's sample: rate 10, period 1, a block from sample
    10 holds event 1), the blocks hold every event once, at its sample."""
    body = (
        f'<waveform_device name="E" version="1"><rate>{rate}</rate>'
        f"<event_period>{period}</event_period></waveform_device>"
    )
    device = make(body, start_devices=False).device("E")
    total = int(rate * period * 12) + 5
    expected = [
        (math.ceil(n * period * rate - 1e-9), n)
        for n in range(1, total)
        if math.ceil(n * period * rate - 1e-9) < total
    ]
    assert expected  # the oracle is the definition above, not the device's own arithmetic
    for cuts in (
        [],
        [expected[0][0]],  # a block starting on the first event's sample
        [index for index, _ in expected],  # every block starting on an event's sample
        [index + 1 for index, _ in expected],  # every block starting just after one
        list(range(1, total)),  # one sample a block
    ):
        bounds = [0, *sorted(set(c for c in cuts if 0 < c < total)), total]
        found = [
            event
            for start, stop in itertools.pairwise(bounds)
            for event in device.compute(start, stop - start).events
        ]
        assert found == expected, cuts


def test_with_an_event_period_a_frame_is_a_devices_own_only_when_an_event_comes_due(make):
    """The group's usual frame (its shared windows) takes every window without an event; a
    device's frame is its own when one of its events comes due, and then publishes it: every
    event once, in order, none lost, while most frames stay the group's (a block holding an
    event made every frame of that block the device's own)."""
    body = "\n".join(
        f'<waveform_device name="Ev {i}" version="1"><rate>1000</rate>'
        f"<position_path>circle</position_path><event_period>0.05</event_period>"
        f"</waveform_device>"
        for i in range(3)
    )
    m = make(body)
    devices = [m.device(f"Ev {i}") for i in range(3)]
    own = dict.fromkeys(range(3), 0)
    for index, device in enumerate(devices):
        update = device._update_at

        def counted(moment, update=update, index=index):
            own[index] += 1
            update(moment)

        device._update_at = counted
    received: dict[int, list[int]] = {i: [] for i in range(3)}
    frames = 0
    deadline = now() + 10.0
    while min(len(r) for r in received.values()) < 8 and now() < deadline:
        time.sleep(0.002)
        m.update()
        frames += 1
        for index, device in enumerate(devices):
            for sample in device.store.frame(DeviceKind.COMMAND):
                received[index].append(int(sample.values[0]))
    for index in range(3):
        events = received[index]
        assert len(events) >= 8
        assert events == list(range(1, len(events) + 1))  # each once, in order, none lost
        # a frame of its own for each event (and a few more: a block's end, the first frame)
        assert own[index] < frames / 2, (own, frames)
