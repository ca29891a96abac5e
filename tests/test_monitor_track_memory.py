"""What a device's monitor track and sample store hold when there is nothing to hold: shared,
read-only empties (10,000 devices would otherwise hold 10,000 empty containers of each)."""

from __future__ import annotations

from types import MappingProxyType

import pytest

from gadgetctl.input import InputManager, ManagerOptions
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.samples import NO_CURRENT, SampleStore
from gadgetctl.jccl.configload import load_configuration
from gadgetctl.jccl.repository import default_repository
from gadgetctl.monitor.tracks import DeviceTrack

HEAD = (
    '<?xml version="1.0" encoding="UTF-8"?>\n<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
    '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="t">\n<elements>\n'
)


@pytest.fixture
def device(tmp_path):
    path = tmp_path / "w.jconf"
    path.write_text(
        HEAD + '<waveform_device name="W" version="1"><rate>10</rate>'
        "<analog_waveform>sine</analog_waveform><position_path>circle</position_path>"
        "</waveform_device>\n</elements>\n</configuration>\n"
    )
    manager = InputManager(
        default_repository(),
        ManagerOptions(start_devices=False, retry_interval=None, entry_points=False),
    )
    manager.configure(load_configuration([path]))
    yield manager.device("W")
    manager.shutdown()


def test_a_store_is_slotted_and_its_first_current_frame_is_the_shared_empty_one():
    store = SampleStore([DeviceKind.ANALOG])
    assert not hasattr(store, "__dict__")
    assert store.current is NO_CURRENT and isinstance(NO_CURRENT, MappingProxyType)
    assert len(NO_CURRENT) == 0
    store.add(DeviceKind.ANALOG, 1.0, (0.5,))
    store.swap()
    assert list(store.current) == [DeviceKind.ANALOG] and len(NO_CURRENT) == 0


def test_a_track_shares_empties_until_it_has_samples(device):
    track = DeviceTrack("W", device, history=8)
    assert track.frames is NO_CURRENT and track.analog_history == ()
    device.store.add_batch(DeviceKind.POSITION, [1.0], [[[[1.0] * 4] * 4]])
    device.store.swap()
    assert track.update() == 1
    assert track.analog_history == ()  # no analog value yet: no histories made
    assert list(track.frames) == [DeviceKind.POSITION]
    device.store.add(DeviceKind.ANALOG, 2.0, (0.25,))
    device.store.swap()
    track.update()
    assert type(track.analog_history) is list and len(track.analog_history) == 1
    assert list(track.analog_history[0]) == [device.normalize(0.25)]
    device.store.swap()  # a frame without samples
    track.update()
    assert len(track.frames) == 0


def test_tracks_that_saw_the_same_units_share_one_read_only_mapping(device):
    one, two = DeviceTrack("W", device, history=8), DeviceTrack("W", device, history=8)
    assert dict(one.units) == {} and one.units is two.units
    device.store.add_batch(DeviceKind.POSITION, [1.0], [[[[1.0] * 4] * 4]])
    device.store.swap()
    one.update()
    two.update()
    device.store.add(DeviceKind.ANALOG, 2.0, (0.25, 0.5))
    device.store.swap()
    one.update()
    assert dict(one.units) == {"position": 1, "analog": 2}  # in the order the kinds came
    assert dict(two.units) == {"position": 1}
    two.update()  # the same frame: the same units, the same mapping
    assert two.units is one.units and isinstance(one.units, MappingProxyType)
    device.store.add(DeviceKind.ANALOG, 4.0, (0.25,))  # fewer units: the most are kept
    device.store.swap()
    one.update()
    assert one.units is two.units


def test_statistics_make_their_ring_at_the_first_timestamps_they_consolidate():
    """Issue 27 goal 3: no ring per device before its statistics are read (10,000 devices'
    rings of 16 were 2 MB held through a run whose statistics are read at its end), then
    the first batch consolidated is the ring; the figures are those of a ring made at once,
    as it grows, and once it is full and wraps."""
    from gadgetctl.monitor.stats import INITIAL_RING, DeviceStats

    stats = DeviceStats("W", history=64)
    assert stats._ring.size == 0 and not stats._ring.flags.writeable
    assert DeviceStats("X")._ring is stats._ring  # one shared empty ring
    assert stats.recent_timestamps().size == 0 and stats.interval_stats() == (None, None, None)
    stats.add_timestamps([0.0, 0.1, 0.25])
    assert stats.recent_timestamps().tolist() == [0.0, 0.1, 0.25]
    assert stats._ring.size == 3  # the first batch itself
    stats.add_timestamps([0.3])
    assert stats.recent_timestamps().tolist() == [0.0, 0.1, 0.25, 0.3]
    assert stats._ring.size == INITIAL_RING
    stamps = [0.3 + 0.1 * i for i in range(1, 40)]
    stats.add_timestamps(stamps)
    assert stats.recent_timestamps().tolist() == [0.0, 0.1, 0.25, 0.3, *stamps]
    stats.add_timestamps([10.0 + i for i in range(64)])
    assert stats.recent_timestamps().tolist() == [10.0 + i for i in range(64)]
    stats.add_timestamps([80.0 + i for i in range(10)])  # the full ring wraps
    assert stats.recent_timestamps().tolist() == [
        *(10.0 + i for i in range(10, 64)),
        *(80.0 + i for i in range(10)),
    ]
    assert stats.max_gap == pytest.approx(80.0 - 73.0)


def test_a_waveform_device_keeps_no_instance_dict_and_its_blocks_share_no_events(device):
    """A waveform device's attributes stay in the instance's compact values (reading its
    ``__dict__`` made Python build a dict for each of 10,000 devices), and a block without
    events shares one empty tuple."""
    import gc

    from gadgetctl.input.device import DeviceState

    device.state = DeviceState.RUNNING  # what read the instance dict
    assert not any(type(r) is dict for r in gc.get_referents(device))
    block = device.compute(0, 8)
    assert block.events == () and device.compute(1, 8).events is block.events
    assert device.compute(8, 8).events == [(10, 1)]  # (its event period: a block with one)
