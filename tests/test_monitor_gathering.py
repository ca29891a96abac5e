"""The frame gatherer on its own, as a session uses it: the watched names are the selected
ones and what they lead to, and gathering with statistics (every device noted in its track)
or without (frame groups' windows handed out as they are) gives the same samples by device,
frame by frame, and counts them alike: also when the devices' first frames are their own
(the scheduler published for them before frames began)."""

from __future__ import annotations

import time

import pytest

from gadgetctl.input.manager import InputManager
from gadgetctl.input.testing import wait_until
from gadgetctl.monitor.gather import frame_timestamps
from gadgetctl.monitor.gathering import FrameGatherer

from jccl_samples import jconf

pytestmark = pytest.mark.timeout(60)


@pytest.fixture
def manager(tmp_path):
    body = "".join(
        f'<waveform_device name="W{i}" version="1"><rate>200</rate>'
        "<position_path>circle</position_path></waveform_device>\n"
        for i in range(4)
    )
    body += (
        '<position_proxy name="Head" version="1"><device>W2</device><unit>0</unit>'
        "</position_proxy>\n"
        '<alias name="Look" version="1"><proxy>Head</proxy></alias>\n'
    )
    path = tmp_path / "g.jconf"
    path.write_text(jconf(body))
    manager, configuration = InputManager.from_files([path])
    manager.configure(configuration)
    yield manager
    manager.shutdown()


def test_the_watched_names_are_the_selected_ones_and_what_they_lead_to(manager):
    gatherer = FrameGatherer(manager, history=8)
    assert gatherer.watch_names(["W0", "Look"]) == ["W0", "Look", "Head", "W2"]
    selected = ["W0", "Look"]
    gatherer.gather(manager.update(), selected, renewed=True)
    assert gatherer.watch == ["W0", "Look", "Head", "W2"]
    assert gatherer.watched(selected) is gatherer.watch  # found by the frame: not again
    assert gatherer.watched(["W1"]) == ["W1"]  # another selection: found for it
    assert set(gatherer.tracks) == {"W0", "W2"}  # devices only


@pytest.mark.parametrize("stood_in", [False, True], ids=["frames-from-start", "stood-in-first"])
def test_gathering_with_and_without_statistics_gives_the_same_samples(manager, stood_in):
    selected = ["W0", "W1", "W3", "Look"]
    if stood_in:  # no frame yet: the scheduler publishes into each store, swapped on its own
        devices = [manager.devices[f"W{i}"] for i in range(4)]
        assert wait_until(lambda: all(d.store.total() > 0 for d in devices), timeout=10)
    noting = FrameGatherer(manager, history=8, statistics=True)
    handing = FrameGatherer(manager, history=8, statistics=False)
    seen: dict[str, int] = {}
    deadline = time.monotonic() + 20
    while len(seen) < 4 or min(seen.values()) < 20:
        assert time.monotonic() < deadline, f"devices delivered too little: {seen}"
        frame = manager.update()
        first = noting.gather(frame, selected, renewed=frame == 1, every=True)
        second = handing.gather(frame, selected, renewed=frame == 1, every=False)
        assert first == second
        assert set(noting.gathered) == set(handing.gathered)
        for name in noting.gathered:
            mine = {k: list(s.timestamps()) for k, s in noting.gathered[name].items()}
            theirs = {k: list(s.timestamps()) for k, s in handing.gathered[name].items()}
            assert mine == theirs, name
            seen[name] = seen.get(name, 0) + len(frame_timestamps(noting.gathered[name]))
    # the track noted every sampling instant it handed out, frame after frame
    for name, count in seen.items():
        assert noting.tracks[name].stats.count == count
    assert set(seen) == {"W0", "W1", "W2", "W3"}
