"""A frame group renews together the blocks of devices configured alike whose block ran out
(or who have none yet, in the first frame): no device's frame is its own for that, and every
sample is the one the device computes alone, exactly once and in order, events included."""

from __future__ import annotations

import time

import numpy as np
import pytest

from gadgetctl.input import InputManager, ManagerOptions, waveform
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.waveform import _SIGNALS
from gadgetctl.jccl.configload import load_configuration
from gadgetctl.jccl.repository import default_repository

pytestmark = pytest.mark.timeout(60)

HEAD = (
    '<?xml version="1.0" encoding="UTF-8"?>\n<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
    '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="t">\n<elements>\n'
)


@pytest.fixture
def make(tmp_path):
    managers = []

    def build(bodies: dict[str, str]) -> InputManager:
        text = "".join(
            f'<waveform_device name="{name}" version="1">{body}</waveform_device>\n'
            for name, body in bodies.items()
        )
        path = tmp_path / f"w{len(managers)}.jconf"
        path.write_text(HEAD + text + "</elements>\n</configuration>\n")
        manager = InputManager(
            default_repository(), ManagerOptions(retry_interval=None, entry_points=False)
        )
        managers.append(manager)
        manager.configure(load_configuration([path]))
        return manager

    _SIGNALS.clear()
    yield build
    for manager in managers:
        manager.shutdown()
    _SIGNALS.clear()


def count_own_frames(devices) -> dict[str, int]:
    own = dict.fromkeys((d.name for d in devices), 0)
    for device in devices:
        update = device._update_at

        def counted(moment, update=update, name=device.name):
            own[name] += 1
            update(moment)

        device._update_at = counted
    return own


def frames_of(manager, devices, frames: int, kinds) -> dict[str, dict[DeviceKind, list]]:
    """Every sample of ``kinds`` each device delivered over ``frames`` frames, as
    (timestamp, values) pairs."""
    got = {d.name: {kind: [] for kind in kinds} for d in devices}
    for _ in range(frames):
        time.sleep(0.002)
        manager.update()  # (no work ahead between frames: every block runs out in a frame)
        for device in devices:
            for kind in kinds:
                for chunk in device.store.frame(kind).chunks:
                    if isinstance(chunk, tuple):  # a single sample
                        got[device.name][kind].append((chunk.timestamp, np.asarray(chunk.values)))
                    else:
                        for stamp, values in zip(chunk.timestamps, chunk.values, strict=True):
                            got[device.name][kind].append((float(stamp), values))
    return got


def test_blocks_of_devices_alike_are_renewed_together_with_the_samples_computed_alone(
    make, monkeypatch
):
    monkeypatch.setattr(waveform, "BLOCK_SECONDS", 0.02)  # a block every few frames
    body = (
        "<rate>1000</rate><position_path>figure_eight</position_path><event_period>0</event_period>"
    )
    manager = make({f"A{i}": body for i in range(6)})
    devices = [manager.device(f"A{i}") for i in range(6)]
    own = count_own_frames(devices)
    renewed = []
    real = waveform._FrameGroup._renew
    monkeypatch.setattr(
        waveform._FrameGroup,
        "_renew",
        lambda group, slots, ends: renewed.append(len(slots)) or real(group, slots, ends),
    )
    got = frames_of(manager, devices, 40, [DeviceKind.POSITION])
    assert own == dict.fromkeys(own, 0)  # never a frame of its own: its blocks were renewed
    assert renewed[0] == 6 and len(renewed) > 5  # the first blocks, then the next ones
    for device in devices:
        samples = got[device.name][DeviceKind.POSITION]
        count = len(samples)
        assert count > 60 and count == device.next_index
        alone = device._compute(0, count)  # the device's own arithmetic, one block
        stamps = np.array([stamp for stamp, _ in samples])
        assert stamps.tobytes() == alone.timestamps.tobytes()  # each once, in order
        values = np.stack([values for _, values in samples])
        assert values.tobytes() == alone.data[DeviceKind.POSITION].tobytes()


def test_devices_with_events_or_values_of_their_own(make, monkeypatch):
    """Devices with an event period get their blocks renewed together too (a frame whose
    window holds an event is still the device's own, which publishes it); devices with values
    of their own (noise) compute each block alone, in a frame of their own, as before."""
    monkeypatch.setattr(waveform, "BLOCK_SECONDS", 0.02)
    events = (
        "<rate>1000</rate><position_path>circle</position_path><event_period>0.03</event_period>"
    )
    noise = "<rate>1000</rate><seed>{}</seed><analog_waveform>noise</analog_waveform><event_period>0</event_period>"
    bodies = {f"E{i}": events for i in range(3)} | {f"N{i}": noise.format(i) for i in range(2)}
    manager = make(bodies)
    devices = [manager.device(name) for name in bodies]
    own = count_own_frames(devices)
    kinds = [DeviceKind.POSITION, DeviceKind.COMMAND, DeviceKind.ANALOG]
    got = frames_of(manager, devices, 60, kinds)
    for device in devices[:3]:
        positions = got[device.name][DeviceKind.POSITION]
        alone = device._compute(0, len(positions))
        assert np.array([s for s, _ in positions]).tobytes() == alone.timestamps.tobytes()
        assert (
            np.stack([v for _, v in positions]).tobytes()
            == alone.data[DeviceKind.POSITION].tobytes()
        )
        numbers = [int(values[0]) for _, values in got[device.name][DeviceKind.COMMAND]]
        assert numbers == [number for _, number in alone.events]  # each once, in order
        assert len(numbers) >= 2
        assert own[device.name] <= len(numbers) + 1  # its own frames: its events' (and one)
    for device in devices[3:]:
        # values of its own: each block runs out into a frame of its own (20 samples a block)
        assert own[device.name] >= 3
        analog = got[device.name][DeviceKind.ANALOG]
        alone = device._compute(0, len(analog))
        assert np.stack([v for _, v in analog]).tobytes() == alone.data[DeviceKind.ANALOG].tobytes()
