"""Waveform devices configured alike share the values of their first samples (computed once,
read-only): every block is the one the device computes on its own, events included."""

from __future__ import annotations

import random

import numpy as np
import pytest

from gadgetctl.input import InputManager, ManagerOptions
from gadgetctl.input.waveform import _SIGNALS, WaveformDevice
from gadgetctl.jccl.configload import load_configuration
from gadgetctl.jccl.repository import default_repository

HEAD = (
    '<?xml version="1.0" encoding="UTF-8"?>\n<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
    '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="t">\n<elements>\n'
)
BODIES = {
    "sticks": "<rate>200</rate><analog_waveform>sine</analog_waveform>"
    "<analog_waveform>triangle</analog_waveform><analog_waveform>square</analog_waveform>"
    "<analog_frequency>0.5</analog_frequency><analog_frequency>0.25</analog_frequency>"
    "<min>-1</min><max>1</max><button_period>1.0</button_period>"
    "<button_period>2.5</button_period><event_period>0.0</event_period>",
    "tracker": "<rate>120</rate><position_path>circle</position_path>"
    "<position_path>spin</position_path><position_path>figure_eight</position_path>"
    "<position_period>4</position_period><position_period>6</position_period>"
    "<position_period>8</position_period><position_radius>0.5</position_radius>"
    "<position_radius>0</position_radius><position_radius>0.4</position_radius>"
    "<event_period>2.0</event_period>",
    "circle": "<rate>10</rate><position_path>circle</position_path>",
    "odd": "<rate>7.3</rate><analog_waveform>sine</analog_waveform>"
    "<position_path>spin</position_path><button_period>0.3</button_period>",
    "fast": "<rate>1000</rate><position_path>figure_eight</position_path>"
    "<position_center>1</position_center><position_center>2</position_center>"
    "<position_center>3</position_center><event_period>0.01</event_period>",
}
OWN = {
    "noise": "<rate>50</rate><seed>{seed}</seed><analog_waveform>noise</analog_waveform>",
    "filtered": "<rate>50</rate><position_path>circle</position_path><position_filters>"
    '<position_transform_filter name="Up" version="1"><pre_translate>0</pre_translate>'
    "<pre_translate>0.1</pre_translate><pre_translate>0</pre_translate>"
    "</position_transform_filter></position_filters>",
}


@pytest.fixture
def devices(tmp_path):
    body = "".join(
        f'<waveform_device name="{name}{copy}" version="1">{text.format(seed=copy)}</waveform_device>\n'
        for name, text in {**BODIES, **OWN}.items()
        for copy in (1, 2)
    )
    path = tmp_path / "w.jconf"
    path.write_text(HEAD + body + "</elements>\n</configuration>\n")
    manager = InputManager(
        default_repository(),
        ManagerOptions(start_devices=False, retry_interval=None, entry_points=False),
    )
    manager.configure(load_configuration([path]))
    _SIGNALS.clear()
    yield {name: manager.device(name) for name in manager.devices}
    manager.shutdown()
    _SIGNALS.clear()


def same_block(a, b) -> None:
    assert (a.start, a.end, a.events) == (b.start, b.end, b.events)
    assert a.timestamps.tobytes() == b.timestamps.tobytes()
    assert [kind for kind, _ in a.items] == [kind for kind, _ in b.items]
    for (_, x), (_, y) in zip(a.items, b.items, strict=True):
        assert (x.shape, x.dtype, x.tobytes()) == (y.shape, y.dtype, y.tobytes())


def test_every_block_is_the_one_computed_alone(devices):
    chance = random.Random(5)
    for name in BODIES:
        device = devices[f"{name}1"]
        assert isinstance(device, WaveformDevice) and device.signal_key() is not None
        for _ in range(150):
            start = chance.randrange(0, _SIGNALS.SHARED_SAMPLES + 50)
            count = chance.randrange(1, 120)
            same_block(device.compute(start, count), device._compute(start, count))


def test_devices_configured_alike_share_read_only_values(devices):
    one, two = devices["tracker1"], devices["tracker2"]
    a, b = one.compute(0, 20), two.compute(3, 20)
    for (_, x), (_, y) in zip(a.items, b.items, strict=True):
        assert np.shares_memory(x, y)
        assert not x.flags.writeable
        with pytest.raises(ValueError):
            x[0] = 0
    assert not np.shares_memory(a.timestamps, b.timestamps)  # each device's own start time
    other = devices["circle1"].compute(0, 20)  # another configuration: values of its own
    assert not np.shares_memory(dict(other.items)[next(iter(dict(other.items)))], a.items[0][1])


def test_values_of_their_own_are_not_shared(devices):
    for name in OWN:
        one, two = devices[f"{name}1"], devices[f"{name}2"]
        assert one.signal_key() is None
        a, b = one.compute(0, 20), two.compute(0, 20)
        for (_, x), (_, y) in zip(a.items, b.items, strict=True):
            assert not np.shares_memory(x, y)
    noise1 = devices["noise1"].compute(0, 20).items[0][1]
    noise2 = devices["noise2"].compute(0, 20).items[0][1]
    assert not np.array_equal(noise1, noise2)  # seeded per device


def test_samples_past_the_shared_ones_are_computed_alone(devices):
    device = devices["circle1"]
    start = _SIGNALS.SHARED_SAMPLES - 5
    block = device.compute(start, 10)
    assert all(values.flags.writeable for _, values in block.items)
    same_block(block, device._compute(start, 10))


def test_the_shared_values_are_read_only_where_they_are_owned(devices):
    block = devices["tracker1"].compute(0, 20)
    for _, values in block.items:
        owner = values if values.base is None else values.base
        assert not owner.flags.writeable  # no view anywhere can write them


def test_a_position_proxy_keeps_a_view_of_shared_values_and_copies_writable_ones(tmp_path):
    from gadgetctl.input.proxies import PositionProxy

    body = (
        '<waveform_device name="W" version="1"><rate>10</rate><position_path>circle</position_path>'
        '</waveform_device><position_proxy name="P" version="1"><device>W</device><unit>0</unit>'
        "</position_proxy>"
    )
    path = tmp_path / "p.jconf"
    path.write_text(HEAD + body + "</elements>\n</configuration>\n")
    manager = InputManager(default_repository(), ManagerOptions(retry_interval=None))
    try:
        manager.configure(load_configuration([path]))
        device, proxy = manager.device("W"), manager.proxy("P")
        block = device.compute(0, 4)
        shared = dict(block.items)[next(iter(dict(block.items)))]
        proxy.take(shared[2][0], device)
        assert np.shares_memory(proxy.matrix, shared)  # a view, not a copy
        assert not proxy.matrix.flags.writeable
        np.testing.assert_array_equal(proxy.matrix, shared[2][0])
        assert isinstance(proxy, PositionProxy)
        mine = np.eye(4)  # the caller may change it afterwards: copied, read-only
        proxy.take(mine, device)
        mine[0, 3] = 5.0
        assert proxy.matrix[0, 3] == 0.0 and not proxy.matrix.flags.writeable
        view = mine[None][0]  # read-only itself, writable where it is owned: copied too
        view.flags.writeable = False
        proxy.take(view, device)
        assert not np.shares_memory(proxy.matrix, mine)
    finally:
        manager.shutdown()


def test_devices_alike_share_the_cuts_their_blocks_are_made_of(devices, monkeypatch):
    """Issue 27 goal 3: blocks of devices alike over the same samples share their (kind,
    view) pairs and events, not only the arrays under them; each keeps its own timestamps.
    The cuts kept are bounded, and a block made after they were dropped is the same."""
    one, two = devices["tracker1"], devices["tracker2"]
    a, b = one.compute(0, 20), two.compute(0, 20)
    assert a.items is b.items and a.events is b.events
    assert a.timestamps is not b.timestamps
    c = two.compute(3, 20)
    assert c.items is not a.items
    same_block(c, two._compute(3, 20))
    monkeypatch.setattr(_SIGNALS, "SHARED_CUTS", 4)
    _SIGNALS.clear()
    for start in range(10):
        one.compute(start, 5)
    assert len(_SIGNALS._cuts) <= 4
    same_block(two.compute(0, 20), two._compute(0, 20))


def test_devices_alike_share_windows_past_the_first_samples(devices):
    """Issue 27 goal 2: past the first SHARED_SAMPLES samples, devices alike share the values
    in windows (a hundred 1 kHz devices alike computed a hundred copies of every block);
    every block is still the one the device computes on its own, events included."""
    chance = random.Random(7)
    past = _SIGNALS.SHARED_SAMPLES
    for name in BODIES:
        one, two = devices[f"{name}1"], devices[f"{name}2"]
        for _ in range(60):
            start = chance.randrange(past - 30, 4 * past)
            count = chance.randrange(1, _SIGNALS.WINDOW_STRIDE + 1)
            a, b = one.compute(start, count), two.compute(start, count)
            same_block(a, one._compute(start, count))
            same_block(b, two._compute(start, count))
    one, two = devices["fast1"], devices["fast2"]
    a, b = one.compute(past + 100, 500), two.compute(past + 100, 500)
    assert a.items is b.items  # the same cut of one window
    for _, values in a.items:
        assert not values.flags.writeable and not values.base.flags.writeable
    assert a.timestamps is not b.timestamps


def test_a_device_alone_computes_its_own_blocks_past_the_first_samples(devices):
    device = devices["tracker1"]
    start = 3 * _SIGNALS.SHARED_SAMPLES
    for _ in range(3):  # asked again and again, by itself only: no window is made
        block = device.compute(start, 10)
        assert all(values.flags.writeable for _, values in block.items)
    assert not _SIGNALS._windows


def test_windows_are_bounded_and_blocks_beyond_the_bounds_are_computed_alone(devices, monkeypatch):
    real = WaveformDevice._compute
    one, two = devices["fast1"], devices["fast2"]
    past, stride = _SIGNALS.SHARED_SAMPLES, _SIGNALS.WINDOW_STRIDE
    one.compute(past, 10)  # first asker
    for step in range(12):
        two.compute(past + step * stride, 10)
        kept = [first for key, first in _SIGNALS._windows if key == two.signal_key()]
        assert len(kept) <= _SIGNALS.WINDOWS_KEPT
    two.compute(past + 4 * stride, 10)  # in a window kept: used last, dropped last
    two.compute(past + 12 * stride, 10)
    kept = [first for key, first in _SIGNALS._windows if key == two.signal_key()]
    assert past + 4 * stride in kept and past + 5 * stride not in kept
    assert _SIGNALS._window_bytes == sum(
        t.nbytes + sum(v.nbytes for v in data.values())
        for _, t, data, _, _ in _SIGNALS._windows.values()
    )
    # a block that reaches past the end of the window its first sample is in
    block = two.compute(past + stride - 1, stride + 2)
    assert all(values.flags.writeable for _, values in block.items)
    same_block(block, two._compute(past + stride - 1, stride + 2))
    monkeypatch.setattr(_SIGNALS, "WINDOW_BYTES", 1000)  # no window fits
    _SIGNALS.clear()
    one.compute(10 * past, 10)
    block = two.compute(10 * past, 10)
    assert all(values.flags.writeable for _, values in block.items)
    assert not _SIGNALS._windows and _SIGNALS._window_bytes == 0
    same_block(block, two._compute(10 * past, 10))
    computed = []
    monkeypatch.setattr(
        WaveformDevice, "_compute", lambda self, *a: computed.append(a) or real(self, *a)
    )
    block = two.compute(10 * past + 20, 10)  # no window computed again just to be dropped
    assert computed == [(10 * past + 20, 10)]
    same_block(block, real(two, 10 * past + 20, 10))
