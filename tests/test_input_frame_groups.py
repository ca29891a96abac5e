"""Waveform devices updated as one frame group through shared windows
(:class:`gadgetctl.input.samples.SharedWindows`): each device's frames, totals and newest
samples are exactly what it would have on its own; a device that raises is faulted alone;
the monitor session gathering without statistics (as `serve` does) reads the shared arrays
and still gives every consumer, proxy and alias the device's own frames."""

from __future__ import annotations

import time

import numpy as np
import pytest

from gadgetctl.input import InputManager, ManagerOptions
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.samples import FEW_SLOTS
from gadgetctl.input.testing import frames_until
from gadgetctl.jccl.configload import load_configuration
from gadgetctl.jccl.repository import default_repository
from gadgetctl.monitor.session import MonitorSession

HEAD = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
    '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="t">\n'
    "<elements>\n"
)
# no events: the usual frame of these devices is one window of their block
POSES = """<waveform_device name="{name}" version="1"><rate>1000</rate><seed>{seed}</seed>
  <event_period>0.0</event_period>
  <position_path>circle</position_path><position_path>spin</position_path>
</waveform_device>"""
MIXED = """<waveform_device name="{name}" version="1"><rate>1000</rate><seed>{seed}</seed>
  <event_period>0.0</event_period>
  <analog_waveform>sine</analog_waveform><analog_waveform>noise</analog_waveform>
  <button_period>0.01</button_period><position_path>figure_eight</position_path>
</waveform_device>"""
PROXIES = """<position_proxy name="Head Proxy" version="1"><device>Poses 0</device><unit>1</unit>
         <position_filters>
            <position_transform_filter name="Lift" version="1">
               <pre_translate>0</pre_translate>
               <pre_translate>1.0</pre_translate>
               <pre_translate>0</pre_translate>
               <pre_rotation>0</pre_rotation>
               <pre_rotation>0</pre_rotation>
               <pre_rotation>0</pre_rotation>
               <custom_scale>1.0</custom_scale>
               <device_units>Meters</device_units>
               <post_translate>0</post_translate>
               <post_translate>0</post_translate>
               <post_translate>0</post_translate>
               <post_rotation>0</post_rotation>
               <post_rotation>0</post_rotation>
               <post_rotation>0</post_rotation>
            </position_transform_filter>
         </position_filters>

</position_proxy>
<alias name="VJHead" version="1"><proxy>Head Proxy</proxy></alias>
<analog_proxy name="Knob" version="1"><device>Mixed 0</device><unit>1</unit></analog_proxy>"""


@pytest.fixture
def make(tmp_path):
    repo = default_repository([])
    managers = []

    def build(body: str) -> InputManager:
        path = tmp_path / f"g{len(managers)}.jconf"
        path.write_text(HEAD + body + "\n</elements>\n</configuration>\n")
        manager = InputManager(repo, ManagerOptions(retry_interval=None, entry_points=False))
        managers.append(manager)
        manager.configure(load_configuration([path]))
        return manager

    yield build
    for manager in managers:
        manager.shutdown()


def _config(poses: int = 4, mixed: int = 2, extra: str = "") -> str:
    return "\n".join(
        [POSES.format(name=f"Poses {i}", seed=i) for i in range(poses)]
        + [MIXED.format(name=f"Mixed {i}", seed=10 + i) for i in range(mixed)]
        + [extra]
    )


def _expected(device, first: int, stop: int):
    """What the device's own computation gives for samples first .. stop - 1."""
    return device.compute(first, stop - first)


@pytest.mark.timeout(60)
@pytest.mark.parametrize(
    "ahead", [False, True], ids=["blocks-at-the-frame", "blocks-computed-ahead"]
)
@pytest.mark.parametrize(
    "poses", [4, FEW_SLOTS + 2], ids=["few-devices-one-by-one", "many-devices-with-numpy"]
)
def test_a_group_frame_gives_each_device_exactly_its_own_samples(make, ahead, poses):
    """With or without the next blocks computed between frames (InputManager.prepare), and
    with frames that bring nothing new (two at once), every device's frames hold exactly
    its samples, in order, once each; in a group of a few devices (the usual frame taken
    slot by slot) as in a larger one (with numpy over all of them)."""
    m = make(_config(poses=poses))
    devices = [m.device(f"Poses {i}") for i in range(poses)] + [
        m.device(f"Mixed {i}") for i in range(2)
    ]
    seen = {d.name: 0 for d in devices}  # the next sample number each device must deliver
    shared_frames = switches = empties = 0
    generations = {}
    kept = {d.name: [] for d in devices}  # per frame: first sample number, stamps, values

    def check() -> None:  # cheap, so that two frames can follow at once
        nonlocal shared_frames, switches, empties
        # the counts readers of every slot go by (serve's feed, the session's gathering)
        # are those of the slots' marks: fresh, emptied (never both), the fresh samples
        windows = devices[0].store.shared[0]
        fresh, emptied = windows.fresh, windows.emptied
        assert not (fresh & emptied).any()
        assert windows.fresh_slots == np.count_nonzero(fresh)
        assert windows.emptied_slots == np.count_nonzero(emptied)
        assert windows.fresh_samples == int((windows.stops - windows.starts)[fresh].sum())
        for device in devices:
            store = device.store
            place = store.shared
            assert place is not None  # grouped: usual frames come from the shared windows
            windows, slot = place
            shared_frames += bool(windows.fresh[slot])
            empties += bool(windows.emptied[slot])
            generation = int(windows.generation[slot])
            switches += (
                bool(windows.fresh[slot]) and generations.get(device.name, generation) != generation
            )
            generations[device.name] = generation
            frames = store.current
            if not frames:
                continue
            stamps = frames[DeviceKind.POSITION].timestamps()
            assert stamps[-1] <= store.swapped_at  # never a sample from the future
            values = {}
            for kind, frame in frames.items():
                values[kind] = np.concatenate([np.asarray(c.values) for c in frame.chunks])
                newest = store.latest(kind)
                assert newest.timestamp == stamps[-1]
                np.testing.assert_array_equal(newest.values, values[kind][-1])
            kept[device.name].append((seen[device.name], stamps, values))
            seen[device.name] += len(stamps)
            # more when the scheduler stood in for frames late by over FRAME_GRACE (load):
            # they wait for the next frame
            assert store.total(DeviceKind.POSITION) >= seen[device.name]

    for count in range(400):  # across the end of the first (shorter) blocks
        time.sleep(0.0015)
        for _ in range(1 if count % 7 else 2):  # two frames at once: the second brings little
            m.update()
            if ahead:
                m.prepare()
            check()
    m.shutdown()  # nothing publishes any more; a last frame takes what waits
    m.update()
    check()
    for device in devices:
        assert device.store.total(DeviceKind.POSITION) == device.next_index == seen[device.name]
        assert device.store.dropped() == 0
    for device in devices:  # what the device's own computation gives for those samples
        block = _expected(device, 0, seen[device.name])
        for first, stamps, values in kept[device.name]:
            stop = first + len(stamps)
            np.testing.assert_array_equal(stamps, block.timestamps[first:stop])
            for kind, got in values.items():
                np.testing.assert_array_equal(got, block.data[kind][first:stop])
    assert shared_frames > 1000  # most frames were the shared usual ones
    assert empties > 0  # frames right after another brought nothing new
    if ahead:  # the frames reaching past a block took the window from the next one, usual
        assert switches >= len(devices)
    assert all(seen[device.name] > 300 for device in devices)


@pytest.mark.timeout(60)
def test_frames_skipped_by_readers_still_count_and_the_newest_stays_latched(make):
    m = make(_config(poses=2, mixed=0))
    device = m.device("Poses 1")
    frames_until(m, lambda: device.store.total(DeviceKind.POSITION) > 50)
    for _ in range(30):  # nobody reads the store during these frames
        time.sleep(0.0015)
        m.update()
    m.shutdown()  # nothing publishes any more; a last frame takes what waits
    m.update()
    total = device.store.total(DeviceKind.POSITION)
    newest = device.store.latest(DeviceKind.POSITION)
    assert total == device.next_index  # every published sample counted, read or not
    assert newest.timestamp == device.t0 + (total - 1) / 1000.0
    m.update()  # nothing new: the frame is empty and the newest stays
    assert not device.store.frame(DeviceKind.POSITION)
    assert device.store.latest(DeviceKind.POSITION).timestamp == newest.timestamp


@pytest.mark.timeout(60)
def test_a_grouped_device_that_raises_is_faulted_alone(make):
    m = make(_config(poses=4, mixed=0))
    devices = [m.device(f"Poses {i}") for i in range(4)]
    frames_until(m, lambda: all(d.store.total() > 0 for d in devices))
    broken = devices[2]

    def compute(start: int, count: int):
        raise RuntimeError("broken on purpose")

    broken.compute = compute  # its next block fails (its usual frames go on until then)
    frames_until(m, lambda: broken.state.value == "faulted", timeout=10)
    assert "broken on purpose" in broken.error
    totals = [d.store.total() for d in devices]
    frames_until(
        m,
        lambda: all(
            d.store.total() > t + 20
            for d, t in zip(devices, totals, strict=True)
            if d is not broken
        ),
    )
    assert all(d.state.value == "running" for d in devices if d is not broken)


@pytest.mark.timeout(60)
def test_gathering_without_statistics_reads_shared_windows_and_proxies_see_filtered_values(make):
    m = make(_config(extra=PROXIES))
    session = MonitorSession(m, None, rate=500.0, statistics=False)
    session.start()
    seen: list[dict] = []

    def consumer(session, moment):  # what a consumer gets: each device's own frames
        gathered = session.gathered
        names = list(gathered)
        assert len(names) == len(gathered)
        record = {}
        for name in [n for n in session.watched if m.device(n) is not None]:
            device = m.device(name)
            frames = session.frame_samples(name)
            assert dict(frames) == dict(device.store.current)
            assert (name in gathered) == bool(frames) == (name in names)
            if frames:
                record[name] = frames[DeviceKind.POSITION].timestamps()
        seen.append(record)

    session.add_consumer(consumer)
    list(session.frames(frames=150))
    devices = [n for n in session.watched if m.device(n) is not None]
    groups = session.gathered.groups
    assert len(groups) == 1 and sorted(groups[0].names) == sorted(devices) and len(devices) == 6
    assert sum(len(r) for r in seen) > 300
    for name in devices:  # frame after frame, every sample once, in order
        stamps = np.concatenate([r[name] for r in seen if name in r])
        np.testing.assert_allclose(np.diff(stamps), 1e-3, rtol=0, atol=1e-9)
    # proxies and aliases read the devices' stores: the newest sample, filtered
    head = m.proxy("VJHead")
    assert head is m.proxy("Head Proxy") and not head.stupefied
    newest = m.device("Poses 0").store.latest(DeviceKind.POSITION)
    assert head.timestamp == newest.timestamp
    np.testing.assert_allclose(
        head.data[:3, 3], newest.values[1][:3, 3] + [0.0, 1.0, 0.0], atol=1e-12
    )
    knob = m.proxy("Knob")
    raw = m.device("Mixed 0").store.latest(DeviceKind.ANALOG)
    assert knob.timestamp == raw.timestamp
    assert knob.data == pytest.approx(m.device("Mixed 0").normalize(float(raw.values[1])))


@pytest.mark.timeout(60)
def test_the_newest_sample_is_read_from_the_shared_windows_as_the_frame_would_give_it(make):
    """A store whose frame is a window of its group's shared arrays gives its newest sample
    of each kind without making that frame (proxies read it every frame): the sample the
    frame gives once made, for the kinds of the window and for the others (the newest of an
    earlier frame, or none)."""
    events = "".join(  # (their commands come in frames of their own, between windows)
        f'<waveform_device name="Events {i}" version="1"><rate>1000</rate>'
        "<position_path>circle</position_path><event_period>0.01</event_period>"
        "</waveform_device>"
        for i in range(2)
    )
    m = make(_config(poses=3, mixed=2, extra=events))
    devices = (
        [m.device(f"Poses {i}") for i in range(3)]
        + [m.device(f"Mixed {i}") for i in range(2)]
        + [m.device(f"Events {i}") for i in range(2)]
    )
    kinds = [
        DeviceKind.POSITION,
        DeviceKind.ANALOG,
        DeviceKind.DIGITAL,
        DeviceKind.HAT,
        DeviceKind.COMMAND,
    ]
    read_before = latched = 0
    for _ in range(60):
        time.sleep(0.002)
        m.update()
        for device in devices:
            store = device.store
            shared, slot = store.shared
            pending = shared.serial != store._synced and bool(shared.fresh[slot])
            before = [store.latest(kind) for kind in kinds]  # (read first: nothing made yet)
            assert (shared.serial != store._synced) == pending  # reading made nothing
            store.sync()
            after = [store.latest(kind) for kind in kinds]
            for kind, one, other in zip(kinds, before, after, strict=True):
                assert (one is None) == (other is None), kind
                if one is not None:
                    assert one.timestamp == other.timestamp
                    assert np.asarray(one.values).tobytes() == np.asarray(other.values).tobytes()
            read_before += pending
            latched += pending and before[-1] is not None
    assert read_before > 100  # most frames were read from the windows
    assert devices[0].store.latest(DeviceKind.ANALOG) is None  # (a kind it never had)
    assert devices[3].store.latest(DeviceKind.DIGITAL) is not None
    assert latched > 20  # a command of an earlier frame, read from a window without one
