"""Waveform devices written alike (but for their names and seeds) read their properties once:
every device gets the values it reads on its own, errors are still each device's own."""

from __future__ import annotations

import pytest

from gadgetctl.input import InputManager, ManagerOptions, waveform
from gadgetctl.jccl.access import ElementAccess
from gadgetctl.jccl.configload import load_configuration
from gadgetctl.jccl.repository import default_repository

HEAD = (
    '<?xml version="1.0" encoding="UTF-8"?>\n<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
    '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="t">\n<elements>\n'
)
ALIKE = (
    "<rate>25</rate><analog_waveform>sine</analog_waveform><analog_waveform>square</analog_waveform>"
    "<analog_frequency>3</analog_frequency><button_period>0.5</button_period>"
    "<position_path>figure_eight</position_path><position_radius>0.25</position_radius>"
    "<position_center>1</position_center><event_period>0.5</event_period>"
)
WRITTEN = {
    "A": ALIKE,
    "B": ALIKE,
    "C": ALIKE.replace("<rate>25</rate>", "<rate>26</rate>"),
    "D": "<rate>10</rate><position_path>circle</position_path>",
    "E": "<rate>10</rate><position_path>circle</position_path>",
    "F": "<rate>-1</rate>",
    "G": "<rate>-1</rate>",
    "H": "<rate>10</rate><position_path>square</position_path>",
}
READ = ("rate", "analog", "button_periods", "positions", "center", "event_period")


@pytest.fixture
def configured(tmp_path):
    body = "".join(
        f'<waveform_device name="{name}" version="1"><seed>{seed}</seed>{text}</waveform_device>\n'
        for seed, (name, text) in enumerate(WRITTEN.items())
    )
    path = tmp_path / "w.jconf"
    path.write_text(HEAD + body + "</elements>\n</configuration>\n")
    configuration = load_configuration([path])
    repo = default_repository()
    made = []

    def configure():
        manager = InputManager(
            repo, ManagerOptions(start_devices=False, retry_interval=None, entry_points=False)
        )
        made.append(manager)
        manager.configure(configuration)
        return manager

    waveform._READ.clear()
    yield configure
    for manager in made:
        manager.shutdown()
    waveform._READ.clear()


def values(device) -> tuple:
    return tuple(getattr(device, field) for field in READ)


def test_devices_written_alike_read_what_each_reads_alone(configured):
    together = configured()
    alone = {}
    for name in WRITTEN:
        waveform._READ.clear()  # nothing read before: each device reads its properties itself
        alone[name] = configured().device(name)
    for name in "ABCDE":
        device = together.device(name)
        assert values(device) == values(alone[name])
        assert device.seed == alone[name].seed == list(WRITTEN).index(name)
    # the lists read once are shared, read-only (issue 27 goal 3: a copy each was 1.7 MB for
    # 10,000 devices); a device written otherwise has its own
    assert together.device("A").analog is together.device("B").analog
    assert together.device("C").analog is not together.device("A").analog
    assert values(together.device("C")) != values(together.device("A"))
    assert together.device("D").center == (0.0, 1.5, 0.0)  # the default, written nowhere


def test_errors_are_each_devices_own(configured):
    manager = configured()
    for name in "FGH":
        assert manager.device(name) is None
        status = manager.status(name)
        assert status is not None and status.reason
    assert "rate" in manager.status("G").reason
    assert "position_path" in manager.status("H").reason


def test_written_texts_of_some_properties(tmp_path):
    path = tmp_path / "w.jconf"
    path.write_text(
        HEAD + f'<waveform_device name="A" version="1"><seed>4</seed>{ALIKE}</waveform_device>\n'
        "</elements>\n</configuration>\n"
    )
    (element,) = load_configuration([path]).elements
    access = ElementAccess(element, default_repository())
    assert access.written({"rate", "analog_waveform", "seed"}) == (
        ("seed", ("4",)),
        ("rate", ("25",)),
        ("analog_waveform", ("sine", "square")),
    )
    assert access.written(set()) == ()
    assert access.definitions is access.repo.property_map("waveform_device")
    compact = access.written({"rate", "analog_waveform", "seed"})
    assert "rate" in element.properties  # (asked for, the compact form becomes a dict)
    assert element._names is None
    assert access.written({"rate", "analog_waveform", "seed"}) == compact


def test_no_written_texts_for_an_embedded_element(tmp_path):
    path = tmp_path / "w.jconf"
    path.write_text(
        HEAD + '<waveform_device name="A" version="1"><rate>5</rate><position_filters>'
        '<position_transform_filter name="Up" version="1"><pre_translate>0</pre_translate>'
        "</position_transform_filter></position_filters></waveform_device>\n"
        "</elements>\n</configuration>\n"
    )
    (element,) = load_configuration([path]).elements
    access = ElementAccess(element, default_repository())
    assert access.written({"rate", "position_filters"}) is None
    assert access.written({"rate"}) == (("rate", ("5",)),)
    assert "rate" in element.properties  # (the dict form)
    assert access.written({"rate", "position_filters"}) is None
    assert access.written({"rate"}) == (("rate", ("5",)),)
