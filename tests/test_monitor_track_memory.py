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
