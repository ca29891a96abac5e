"""The input manager: pending reasons, reconfiguration, real VR Juggler configurations and
the bundled examples."""

from pathlib import Path

import pytest

from gadgetctl.input import Digital, DigitalState, InputManager, Key, ManagerOptions
from gadgetctl.input.definitions import repository_for
from gadgetctl.input.registry import DeviceRegistry
from gadgetctl.jccl.configload import load_configuration
from gadgetctl.jccl.repository import default_repository
from gadgetctl.jccl.schema import check_schema
from gadgetctl.jccl.searchpath import SearchPathEntry
from gadgetctl.jccl.xmlload import load_file
from gadgetctl.resources import examples_dir

CORPUS = Path("/work/shared/corpus/vrjuggler/modules/vrjuggler/data")
CORPUS_DEFINITIONS = CORPUS / "definitions"
CONFIGS = CORPUS / "configFiles"
PLUGINS = Path(__file__).parent / "data" / "plugins"
HEAD = (
    '<?xml version="1.0" encoding="UTF-8"?>\n<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
    '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="test">\n<elements>\n'
)
KEYBOARD = (
    '<keyboard_mouse_device name="KB" version="2"/>'
    '<keyboard_mouse_proxy name="KBP" version="1"><device>KB</device></keyboard_mouse_proxy>'
)
BUTTONS = (
    KEYBOARD
    + """
<simulated_digital_device name="Buttons" version="2">
  <keyboard_mouse_proxy>KBP</keyboard_mouse_proxy>
  <key_pair><key_modifier_pair name="a" version="1"><key>KEY_A</key></key_modifier_pair></key_pair>
</simulated_digital_device>
<digital_proxy name="A Proxy" version="1"><device>Buttons</device><unit>0</unit></digital_proxy>
<alias name="VJButton0" version="1"><proxy>A Proxy</proxy></alias>
"""
)
needs_corpus = pytest.mark.usefixtures("corpus")  # a missing corpus fails, never skips


@pytest.fixture(scope="module")
def repo():
    repo = default_repository([CORPUS_DEFINITIONS] if CORPUS_DEFINITIONS.is_dir() else [])
    directory = PLUGINS / "Button_drv"
    repo.load_entry(SearchPathEntry(raw=str(directory), path=directory, origin="test"))
    return repo


@pytest.fixture
def managers():
    made: list[InputManager] = []
    yield made
    for manager in made:
        manager.shutdown()


@pytest.fixture
def config(tmp_path):
    counter = [0]

    def write(body):
        counter[0] += 1
        path = tmp_path / f"test{counter[0]}.jconf"
        path.write_text(HEAD + body + "\n</elements>\n</configuration>\n")
        return load_configuration([path])

    return write


@pytest.fixture
def make(repo, config, managers):
    def build(body, registry=None, **options):
        options.setdefault("retry_interval", None)
        options.setdefault("entry_points", False)
        manager = InputManager(repo, ManagerOptions(**options), registry=registry)
        managers.append(manager)
        manager.configure(config(body))
        return manager

    return build


def reasons(manager):
    return {p.name: (p.code, p.message, p.hint) for p in manager.pending()}


# -- pending reasons ----------------------------------------------------------------------


def test_every_pending_element_has_its_reason(make):
    body = (
        BUTTONS
        + """
    <linux_joydev name="Stick" version="1"><port_name>/dev/input/js0</port_name></linux_joydev>
    <digital_device name="Abstract" version="1"/>
    <alias name="Double" version="1"><proxy>VJButton0</proxy></alias>
    <alias name="To Device" version="1"><proxy>Buttons</proxy></alias>
    <alias name="Nowhere" version="1"><proxy>Missing Proxy</proxy></alias>
    <digital_proxy name="A Proxy" version="1"><device>Buttons</device><unit>0</unit></digital_proxy>
    <gadget_logger name="Logger" version="1"/>
    <input_manager name="Old IM" version="1"><driver>/usr/lib/gadgeteer/drivers/Foo.so</driver></input_manager>
    <my_unknown_tracker name="Mystery" version="1"/>
    <simulated_relative_position name="Rel" version="1">
      <base_frame_proxy>Pending Proxy</base_frame_proxy><relative_proxy>A Proxy</relative_proxy>
    </simulated_relative_position>
    <user name="User" version="1"><head_position>VJButton0</head_position></user>
    """
    )
    m = make(body)
    found = reasons(m)
    assert (
        found["Stick"][0] == "DRV030"
        and "no loaded driver handles linux_joydev" in found["Stick"][1]
    )
    assert "LinuxJoydev_drv (bundled) provides linux_joydev" in found["Stick"][2]
    assert found["Abstract"][0] == "DRV030" and "abstract" in found["Abstract"][1]
    assert found["Double"][0] == "DRV039" and "alias 'VJButton0'" in found["Double"][1]
    assert found["To Device"][0] == "DRV039" and "device 'Buttons'" in found["To Device"][1]
    assert found["Nowhere"][0] == "DRV034" and "'Missing Proxy'" in found["Nowhere"][1]
    assert found["Logger"][0] == "DRV036"
    assert found["Old IM"][0] == "DRV037" and "version 2" in found["Old IM"][1]
    assert found["Mystery"][0] == "DRV040"
    assert found["Rel"][0] == "DRV034" and "base_frame_proxy" in found["Rel"][1]
    assert "User" not in found  # not an input element: not pending, simply not handled
    assert "A Proxy" not in found  # a later element of the same name replaces the earlier one
    statuses = {s.name: s for s in m.statuses()}
    assert statuses["Stick"].state == "pending" and statuses["Stick"].code == "DRV030"


def test_elements_waiting_for_pending_elements_quote_their_reason(make):
    body = (
        KEYBOARD
        + """
    <linux_joydev name="Stick" version="1"/>
    <input_window name="Window" version="2"><keyboard_mouse_device_name>Stick</keyboard_mouse_device_name></input_window>"""
    )
    m = make(body)
    code, message, _ = reasons(m)["Window"]
    assert code == "DRV035" and "which is pending: no loaded driver handles linux_joydev" in message


def test_driver_named_by_input_manager_and_failures_reported(make, tmp_path):
    body = f"""
    <input_manager name="IM" version="2">
      <driver_path>{PLUGINS}</driver_path>
      <driver>Button_drv</driver><driver>BrokenImport_drv</driver><driver>Missing_drv</driver>
    </input_manager>
    <button_device name="Button" version="1"><port>/dev/null</port></button_device>
    <digital_proxy name="BP" version="1"><device>Button</device><unit>0</unit></digital_proxy>
    <linux_joydev name="Stick" version="1"/>"""
    m = make(body)
    assert m.device("Button") is not None and m.device("Button").port == "/dev/null"
    codes = {d.code for d in m.diagnostics}
    assert {"DRV001", "DRV003"} <= codes
    missing = next(d for d in m.diagnostics if d.code == "DRV001")
    assert (
        "Missing_drv" in missing.message and missing.line is not None
    )  # points at the <driver> value
    assert "Missing_drv" in reasons(m)["Stick"][2]


def test_device_whose_driver_failed_to_load_is_pending_with_the_error(make):
    body = f"""
    <input_manager name="IM" version="2"><driver_path>{PLUGINS}</driver_path><driver>BrokenImport_drv</driver></input_manager>
    <broken_device name="Broken" version="1"/>"""
    m = make(body)
    # no definition of broken_device exists, so the element is reported for that first
    assert reasons(m)["Broken"][0] == "DRV040"


class Flaky(Digital):
    ELEMENT_TYPE = "button_device"
    SAMPLING = "frame"
    can_start = False

    def start_sampling(self):
        if not Flaky.can_start:
            raise OSError("no such device: /dev/button")


def test_start_failure_is_pending_with_the_error_and_retried(make):
    registry = DeviceRegistry.with_builtins()
    registry.register_device(Flaky)
    Flaky.can_start = False
    m = make(
        '<button_device name="B" version="1"/>'
        '<digital_proxy name="P" version="1"><device>B</device></digital_proxy>',
        registry,
    )
    code, message, _ = reasons(m)["B"]
    assert code == "DRV033" and "OSError: no such device: /dev/button" in message
    assert m.proxy("P").stupefied and "failed to start" in m.proxy("P").reason
    m.reconfigure()
    assert "B" in reasons(m)  # not retried on every pass
    Flaky.can_start = True
    assert m.retry_pending() == 1
    assert not m.pending() and not m.proxy("P").stupefied


def test_what_a_type_is_follows_definitions_and_drivers_added_later(config, managers):
    """What the manager knows of an element type (its kind, its definition's versions) is
    worked out once per type and kept while neither the repository nor the registry
    changes: a definition added, then a driver registered, are seen at the next retry."""
    repo = default_repository()
    registry = DeviceRegistry.with_builtins()
    m = InputManager(
        repo, ManagerOptions(retry_interval=None, entry_points=False), registry=registry
    )
    managers.append(m)
    m.configure(
        config(
            '<button_device name="B" version="1"/><button_device name="C" version="1"/>'
            '<digital_proxy name="P" version="1"><device>B</device></digital_proxy>'
        )
    )
    assert {name for name, (code, *_) in reasons(m).items() if code == "DRV040"} == {"B", "C"}
    directory = PLUGINS / "Button_drv"
    repo.load_entry(SearchPathEntry(raw=str(directory), path=directory, origin="test"))
    m.retry_pending()
    assert "no definition" not in reasons(m)["B"][1]  # a definition now: no driver yet
    assert reasons(m)["B"][:2] == reasons(m)["C"][:2]
    Flaky.can_start = True
    registry.register_device(Flaky)
    assert m.retry_pending() == 2
    assert not m.pending() and not m.proxy("P").stupefied
    # a type that is not about input is ignored, until a driver registers a class for it
    m.configure(config('<sound name="S1" version="1"/>'))
    assert m.status("S1") is None and not m.pending()
    registry.register_device(Flaky, "sound")
    m.configure(config('<sound name="S2" version="1"/>'))
    assert m.status("S2") is not None and "S2" in m.devices


def test_an_element_replaces_one_of_the_same_name_even_of_another_type(make):
    m = make(BUTTONS)
    m.add([load_alias_named("A Proxy")])  # as VR Juggler's Configuration::add: same name, replaced
    m.reconfigure()
    assert "A Proxy" not in m.proxies
    assert reasons(m)["A Proxy"][:2] == ("DRV039", "points at itself")
    assert reasons(m)["VJButton0"][0] == "DRV035"


def load_alias_named(name):
    from gadgetctl.jccl.configuration import ConfigElement, PropertyValue
    from gadgetctl.jccl.definitions import Location

    where = Location("<test>")
    element = ConfigElement("alias", name, "1", where)
    element.properties["proxy"] = [PropertyValue("A Proxy", where)]
    return element


# -- reconfiguration ----------------------------------------------------------------------


def test_removing_a_device_stupefies_its_proxies_and_adding_it_back_revives_them(make):
    m = make(BUTTONS)
    buttons = m.element("Buttons")
    m.events.press(Key.KEY_A)
    m.update()
    assert m.proxy("VJButton0").data == DigitalState.TOGGLE_ON
    m.remove(["Buttons"])
    m.update()
    proxy = m.proxy("VJButton0")
    assert proxy.stupefied and proxy.data == DigitalState.OFF
    assert "'Buttons' is not configured" in proxy.reason
    assert m.device("Buttons") is None and not m.pending()
    m.add([buttons])
    m.update()
    assert not proxy.stupefied
    assert m.proxy("VJButton0").data in (DigitalState.TOGGLE_ON, DigitalState.ON)


def test_removing_a_target_sends_its_dependents_back_to_pending(make):
    m = make(BUTTONS)
    keyboard_proxy = m.element("KBP")
    proxy = m.element("A Proxy")
    m.remove(["KBP", "A Proxy"])
    m.update()
    found = reasons(m)
    assert found["Buttons"][0] == "DRV034" and "'KBP'" in found["Buttons"][1]
    assert found["VJButton0"][0] == "DRV034"
    m.add([keyboard_proxy, proxy])
    m.update()
    assert not m.pending()
    m.events.tap(Key.KEY_A)
    m.update()
    assert m.proxy("VJButton0").data == DigitalState.TOGGLE_ON


def test_replacing_an_element_by_name_reconfigures_it(make, config):
    m = make(BUTTONS)
    replacement = config(BUTTONS.replace("KEY_A", "KEY_Z")).get("Buttons")
    m.add([replacement])
    m.update()
    m.events.tap(Key.KEY_Z)
    m.update()
    assert m.proxy("VJButton0").data == DigitalState.TOGGLE_ON


@pytest.mark.timeout(10)
def test_reconfiguration_from_another_thread_is_applied_at_the_next_frame(make):
    import threading

    m = make(BUTTONS)
    element = m.element("Buttons")
    thread = threading.Thread(target=m.remove, args=(["Buttons"],))
    thread.start()
    thread.join(5)
    assert m.device("Buttons") is not None  # queued, not applied yet
    m.update()
    assert m.device("Buttons") is None
    m.add([element])
    m.update()
    assert m.device("Buttons") is not None


# -- real configurations ------------------------------------------------------------------

SIM_SETS = [
    ["sim.base.jconf", "sim.wand.mixin.jconf"],
    ["sim.base.jconf", "sim.analog.mixin.jconf"],
    ["sim.base.jconf", "sim.glove.mixin.jconf"],
    ["sim.base.jconf", "sim.digital.glove.mixin.jconf"],
    ["sim.base.jconf", "sim.analog.wandmixin.jconf", "sim.wand.mixin.jconf"],
    ["simstandalone.jconf"],
]


@needs_corpus
@pytest.mark.parametrize("files", SIM_SETS, ids=lambda f: "+".join(f))
def test_vr_juggler_simulator_configurations_configure_completely(repo, managers, files):
    m = InputManager(repo, ManagerOptions(retry_interval=None, entry_points=False))
    managers.append(m)
    m.configure(load_configuration([CONFIGS / f for f in files]))
    assert not m.pending(), reasons(m)
    assert m.devices and m.proxies and m.aliases
    m.update()
    assert all(s.state in ("running", "active", "stupefied") for s in m.statuses())


@needs_corpus
def test_configurations_with_drivers_gadgetctl_lacks_give_the_reason(repo, managers):
    # Trackd_drv is bundled now: without the bundled drivers it is one gadgetctl lacks
    m = InputManager(
        repo, ManagerOptions(retry_interval=None, entry_points=False, bundled_drivers=False)
    )
    managers.append(m)
    m.configure(load_configuration([CONFIGS / "sim.trackd.jconf"]))
    found = reasons(m)
    assert set(found) == {"TrackdSensorDev", "TrackdControllerDev"}
    for code, message, hint in found.values():
        assert code == "DRV030" and "no loaded driver handles trackd_" in message
        assert "Trackd_drv" in hint
    m.configure(load_configuration([CONFIGS / "standalone.jconf"]))
    assert reasons(m)["Input Event Emitter"][0] == "DRV036"


@needs_corpus
def test_a_simulated_wand_moves_with_keys(repo, managers):
    m = InputManager(repo, ManagerOptions(retry_interval=None, entry_points=False))
    managers.append(m)
    m.configure(load_configuration([CONFIGS / "sim.base.jconf", CONFIGS / "sim.wand.mixin.jconf"]))
    m.update()
    before = m.proxy("VJHead").translation
    m.events.tap(Key.KEY_8)  # SimHeadPos: forward, global translation, 5 mm per press
    m.update()
    after = m.proxy("VJHead").translation
    assert after[2] == pytest.approx(before[2] - 0.005)


# -- bundled examples ---------------------------------------------------------------------

EXAMPLES = sorted(examples_dir().glob("*.jconf"))


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_examples_are_valid_configurations(path):
    doc = load_file(path)
    check_schema(doc)
    assert not [d for d in doc.diagnostics if d.severity.value == "error"], doc.diagnostics


@pytest.mark.timeout(20)
def test_examples_configure_with_nothing_pending_and_every_kind_reachable(managers):
    paths = [examples_dir() / "all_devices.jconf", examples_dir() / "waveform.jconf"]
    configuration = load_configuration(paths)
    m = InputManager(
        repository_for(configuration), ManagerOptions(retry_interval=None, entry_points=False)
    )
    managers.append(m)
    m.configure(configuration)
    assert not m.pending(), reasons(m)
    kinds = {type(p).__name__ for p in m.proxies.values()}
    assert kinds >= {
        "AnalogProxy",
        "DigitalProxy",
        "PositionProxy",
        "GloveProxy",
        "GestureProxy",
        "CommandProxy",
        "StringProxy",
        "HatProxy",
        "KeyboardMouseProxy",
    }
    m.update()
    assert not [
        p.name for p in m.proxies.values() if p.stupefied and p.reason and "unit" in p.reason
    ]
    for alias in m.aliases:
        assert m.proxy(alias) is not None


class Recorded(Digital):
    ELEMENT_TYPE = "button_device"
    SAMPLING = "frame"
    events: list[tuple[str, str]] = []

    def config(self, access):
        super().config(access)
        Recorded.events.append(("config", self.name))

    def start_sampling(self):
        Recorded.events.append(("start", self.name))


def test_a_configuration_starts_its_devices_after_configuring_them_all(make):
    """Issue 27: devices started one by one while the others were configured sampled (and
    the scheduler passed over them) for as long as configuring took, which grew with their
    number: 10,000 devices cost a quadratic amount of work before the first frame."""
    registry = DeviceRegistry.with_builtins()
    registry.register_device(Recorded)
    Recorded.events = []
    m = make(
        "".join(f'<button_device name="B{i}" version="1"/>' for i in range(3))
        + '<digital_proxy name="P" version="1"><device>B2</device></digital_proxy>',
        registry,
    )
    assert [e[0] for e in Recorded.events] == ["config"] * 3 + ["start"] * 3
    assert not m.pending() and not m.proxy("P").stupefied
    assert all(m.device(f"B{i}").state.value == "running" for i in range(3))
