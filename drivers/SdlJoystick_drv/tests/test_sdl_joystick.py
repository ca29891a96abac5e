"""The SDL joystick driver against SDL's own virtual joysticks, in this process (they exist
nowhere else): axes, buttons and hats through proxies, impossible hat values counted, a
joystick that goes and comes back, rumble, two devices sharing SDL, the corpus's
example.sdl_joystick.jconf under `gadgetctl monitor --format ndjson`, doctor's SDL check, the
emulator's one-process demonstration, and a one-line DRV003 without PySDL2."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from SdlJoystick_drv.emulator import IMPOSSIBLE_HATS, SdlJoystickEmulator, main, normalised
from SdlJoystick_drv.standalone import SdlJoystickLost, SdlJoystickReader

from gadgetctl.doctor import DoctorOptions, Status, diagnose, render_text
from gadgetctl.doctor.sdl import check_sdl
from gadgetctl.input import DeviceKind, DigitalState, HatState, InputManager, ManagerOptions
from gadgetctl.input.testing import frames_until, wait_until
from gadgetctl.input.testing.configs import configuration, corpus_file, proxy
from gadgetctl.input.testing.fixtures import managers_fixture
from gadgetctl.transport.sdl import hub

pytestmark = pytest.mark.timeout(60)

ROOT = Path(__file__).resolve().parents[3]
PRESSED = (DigitalState.ON, DigitalState.TOGGLE_ON)
RELEASED = (DigitalState.OFF, DigitalState.TOGGLE_OFF)


def joystick(name: str, index: int) -> str:
    return f'<sdl_joystick name="{name}" version="2"><device>{index}</device></sdl_joystick>\n'


build = managers_fixture(
    "SdlJoystick_drv",
    name="build",
    ready=True,
    options=ManagerOptions(retry_interval=0.2, entry_points=False),
)


@pytest.fixture(autouse=True)
def sdl_released() -> Iterator[None]:
    """Every test leaves SDL as it found it: no hub user, no virtual joystick attached."""
    yield
    assert hub()._users == 0, "a test left the SDL hub held"


# -- values through proxies --------------------------------------------------------------------


def test_axes_buttons_and_hats_reach_the_proxies_normalised(build) -> None:
    with SdlJoystickEmulator(scenario="idle", axes=5, buttons=3, hats=2) as emu:
        body = joystick("Pad", emu.index)
        body += "".join(proxy("analog", f"A{i}", "Pad", i) for i in range(5))
        body += "".join(proxy("digital", f"B{i}", "Pad", i) for i in range(3))
        body += proxy("hat", "H0", "Pad", 0) + proxy("hat", "H1", "Pad", 1)
        manager = build(body)
        raw = (-32768, -32767, 0, 16384, 32767)
        for axis, value in enumerate(raw):
            assert emu.set_axis(axis, value)
        emu.set_button(1, 1)
        emu.set_hat(0, 1 | 2)  # up and right
        emu.set_hat(1, 8)
        frames_until(manager, lambda: manager.proxy("H1").data == HatState.LEFT, timeout=10.0)
        expected = (0.0, 0.0, 0.5, (16384 + 32767) / 65534, 1.0)
        for axis, value in enumerate(expected):
            assert manager.proxy(f"A{axis}").data == pytest.approx(value, abs=1e-9)
            assert normalised(raw[axis]) == pytest.approx(value, abs=1e-9)
        assert manager.proxy("B1").data in PRESSED
        assert manager.proxy("B0").data in RELEASED and manager.proxy("B2").data in RELEASED
        assert manager.proxy("H0").data == HatState.UP | HatState.RIGHT
        latest = manager.device("Pad").store.latest(DeviceKind.ANALOG).values
        assert tuple(latest) == raw  # the device keeps SDL's raw values; proxies normalise
        emu.set_button(1, 0)
        frames_until(manager, lambda: manager.proxy("B1").data in RELEASED, timeout=10.0)


@pytest.mark.parametrize("scenario", ["motion", "buttons", "hats"])
def test_each_scenario_moves_what_it_names(build, scenario: str) -> None:
    with SdlJoystickEmulator(scenario=scenario, rate=50.0, axes=2, buttons=4, hats=1) as emu:
        manager = build(
            joystick("Pad", emu.index)
            + proxy("analog", "X", "Pad", 0)
            + proxy("digital", "B0", "Pad", 0)
            + proxy("hat", "H", "Pad", 0)
        )
        axes, buttons, hats = set(), set(), set()

        def seen_enough() -> bool:
            if manager.proxy("X").timestamp is not None:  # 0.0 before the first sample
                axes.add(round(manager.proxy("X").data, 3))
            buttons.add(manager.proxy("B0").data in PRESSED)
            hats.add(int(manager.proxy("H").data))
            return {
                "motion": len(axes) > 5,
                "buttons": buttons == {True, False},
                "hats": len(hats) >= 4,
            }[scenario]

        frames_until(manager, seen_enough, timeout=20.0)
        assert hats <= {0, 1, 2, 3, 4, 6, 8, 9, 12}
        assert manager.device("Pad").counters["bad_hats"] == 0
        if scenario != "motion":
            assert axes == {0.5}  # centred
        if scenario != "hats":
            assert hats == {0}


# -- garbage and disconnection ----------------------------------------------------------------


def test_impossible_hat_values_are_counted_and_read_centred(build) -> None:
    with SdlJoystickEmulator(scenario="idle", axes=1, buttons=1, hats=1) as emu:
        manager = build(joystick("Pad", emu.index) + proxy("hat", "H", "Pad", 0))
        dev = manager.device("Pad")
        for step, bad in enumerate(IMPOSSIBLE_HATS, start=1):
            emu.set_hat(0, bad)
            frames_until(manager, lambda step=step: dev.counters["bad_hats"] == step, timeout=10.0)
            assert manager.proxy("H").data == HatState.CENTERED
            emu.set_hat(0, 4)  # a real direction in between
            frames_until(manager, lambda: manager.proxy("H").data == HatState.DOWN, timeout=10.0)
        assert dev.counters["bad_hats"] == len(IMPOSSIBLE_HATS)
        assert manager.status("Pad").state == "running" and dev.faults == 0


def test_the_garbage_scenario_is_counted_without_a_fault(build) -> None:
    with SdlJoystickEmulator(
        scenario="garbage", rate=100.0, axes=2, buttons=2, hats=1, max_ticks=200
    ) as emu:
        manager = build(joystick("Pad", emu.index) + proxy("hat", "H", "Pad", 0))
        dev = manager.device("Pad")
        frames_until(manager, lambda: emu.finished.is_set(), timeout=30.0)
        polls = dev.counters["polls"]
        frames_until(manager, lambda: dev.counters["polls"] > polls + 2, timeout=10.0)
    assert emu.error is None and emu.garbage_sent == 50
    assert 0 < dev.counters["bad_hats"] <= emu.garbage_sent
    assert dev.faults == 0 and dev.health()["bad_hats"] == dev.counters["bad_hats"]


def test_a_joystick_that_goes_away_faults_and_returns(build) -> None:
    with SdlJoystickEmulator(scenario="motion", rate=100.0, axes=2, buttons=2, hats=1) as emu:
        manager = build(joystick("Pad", emu.index) + proxy("analog", "X", "Pad", 0))
        dev = manager.device("Pad")
        frames_until(manager, lambda: dev.store.total() > 10, timeout=10.0)
        emu.detach()
        frames_until(
            manager,
            lambda: manager.status("Pad").state in ("faulted", "reconnecting"),
            timeout=10.0,
        )
        # the fault's reason, or (when a restart was tried already) why it cannot open yet
        assert re.search(r"was disconnected|no SDL joystick", dev.error or ""), dev.error
        count = dev.store.total()
        emu.attach()  # VR Juggler's driver never noticed; here the device opens it again
        frames_until(manager, lambda: dev.store.total() > count + 5, timeout=20.0)
        frames_until(manager, lambda: manager.status("Pad").state == "running", timeout=10.0)
    assert dev.restarts >= 1 and dev.faults >= 1


def test_the_disconnect_scenario_comes_back_by_itself(build) -> None:
    with SdlJoystickEmulator(
        scenario="motion", rate=100.0, axes=1, buttons=1, hats=0, disconnect_after=30, down_time=0.3
    ) as emu:
        manager = build(joystick("Pad", emu.index) + proxy("analog", "X", "Pad", 0))
        dev = manager.device("Pad")
        emu.ticks_attached = 0
        emu.scenario = "disconnect"  # only now: the device opened the joystick first
        frames_until(manager, lambda: emu.detaches >= 1 and dev.faults >= 1, timeout=20.0)
        frames_until(manager, lambda: emu.attaches >= 2 and dev.restarts >= 1, timeout=20.0)
        count = dev.store.total()
        frames_until(manager, lambda: dev.store.total() > count + 5, timeout=20.0)
    assert emu.error is None and "SDL joystick" in (dev.error or "")  # gone, or not back yet


def test_a_missing_index_leaves_the_device_pending_with_the_reason(tmp_path: Path) -> None:
    path = tmp_path / "missing.jconf"
    path.write_text(configuration("SdlJoystick_drv", joystick("Pad", 7)))
    manager, loaded = InputManager.from_files(
        [path], options=ManagerOptions(retry_interval=None, entry_points=False)
    )
    try:
        manager.configure(loaded)
        (entry,) = manager.pending()
        assert entry.code == "DRV033" and "no SDL joystick 7" in entry.message
    finally:
        manager.shutdown()


# -- rumble and sharing SDL ----------------------------------------------------------------------


def test_rumble_reaches_the_joystick_and_stops_after_its_duration(build) -> None:
    with SdlJoystickEmulator(scenario="idle", axes=1, buttons=1, hats=0) as emu:
        rumble = '<rumble_proxy name="R" version="1"><device>Pad</device></rumble_proxy>\n'
        manager = build(joystick("Pad", emu.index) + rumble)
        frames_until(manager, lambda: manager.proxy("R").data, timeout=10.0)  # can rumble
        assert manager.status("R").state == "active"
        assert manager.proxy("R").rumble(0.5, 1.0, 0.05)
        assert wait_until(lambda: (0, 0) in emu.rumbles, timeout=10.0)  # SDL ends it
        assert emu.rumbles[0] == (32768, 65535)
        assert manager.device("Pad").rumble(0.0, 0.25, 1.0)
        assert wait_until(lambda: emu.rumbles[-1] == (0, 16384), timeout=10.0)


def test_rumble_takes_any_duration_and_refuses_nan(build) -> None:
    """An endless duration rumbles as long as SDL takes (it raised OverflowError); a NaN
    strength or duration is refused without reaching SDL (issue 24 item 14)."""
    with SdlJoystickEmulator(scenario="idle", axes=1, buttons=1, hats=0) as emu:
        manager = build(joystick("Pad", emu.index))
        pad = manager.device("Pad")
        frames_until(manager, lambda: pad.has_rumble, timeout=10.0)
        nan = float("nan")
        for low, high, duration in ((nan, 0.5, 1.0), (0.5, nan, 1.0), (0.5, 0.5, nan)):
            assert not pad.rumble(low, high, duration)
        assert emu.rumbles == []
        assert pad.rumble(0.5, 0.5, float("inf"))
        assert pad.rumble(0.25, 0.25, 1e300)
        assert pad.rumble(0.25, 0.25, -float("inf"))  # no duration: the motors stop

        def changes() -> list[tuple[int, int]]:  # SDL may send a rumble again after a while
            return [r for i, r in enumerate(emu.rumbles) if i == 0 or r != emu.rumbles[i - 1]]

        assert wait_until(lambda: len(changes()) >= 3, timeout=10.0)
        assert changes()[:3] == [(32768, 32768), (16384, 16384), (0, 0)]


def test_a_joystick_without_motors_does_not_rumble(build) -> None:
    with SdlJoystickEmulator(scenario="idle", axes=1, buttons=1, hats=0, rumble=False) as emu:
        rumble = '<rumble_proxy name="R" version="1"><device>Pad</device></rumble_proxy>\n'
        manager = build(joystick("Pad", emu.index) + rumble)
        frames_until(manager, lambda: manager.device("Pad").store.total() > 0, timeout=10.0)
        assert not manager.proxy("R").data and not manager.proxy("R").rumble(1.0, 1.0, 0.1)
        assert emu.rumbles == []


def test_two_devices_share_sdl_and_one_stopping_leaves_the_other(build) -> None:
    with (
        SdlJoystickEmulator(scenario="motion", axes=1, buttons=1, hats=0, name="one") as one,
        SdlJoystickEmulator(scenario="idle", axes=1, buttons=1, hats=0, name="two") as two,
    ):
        manager = build(
            joystick("P1", one.index) + joystick("P2", two.index) + proxy("analog", "X", "P1", 0)
        )
        frames_until(manager, lambda: manager.device("P2").store.total() > 3, timeout=10.0)
        manager.remove(["P2"])  # upstream called SDL_Quit here, for both devices
        frames_until(manager, lambda: manager.lookup("P2") is None, timeout=10.0)
        dev = manager.device("P1")
        count = dev.store.total()
        frames_until(manager, lambda: dev.store.total() > count + 10, timeout=10.0)
        assert manager.status("P1").state == "running"


# -- the corpus example under monitor, doctor, the emulator's command line -----------------------


def run_cli(capsys, *args: str) -> tuple[int, str, str]:
    from gadgetctl.cli.main import main as cli_main

    capsys.readouterr()
    try:
        cli_main(list(args))
        code = 0
    except SystemExit as exit_:
        code = exit_.code if isinstance(exit_.code, int) else 0 if exit_.code is None else 2
    out = capsys.readouterr()
    return code, out.out, out.err


def test_the_corpus_example_runs_under_monitor_ndjson(tmp_path: Path, capsys) -> None:
    text = corpus_file("example.sdl_joystick.jconf").read_text()
    with SdlJoystickEmulator(scenario="motion", rate=100.0, axes=10, buttons=16, hats=1) as emu:
        changed = re.sub(
            r"<device>0</device>(\s*</sdl_joystick>)",
            rf"<device>{emu.index}</device>\1",
            text,
            count=1,
        )
        assert changed.count(f"<device>{emu.index}</device>") >= 1
        path = tmp_path / "example.sdl_joystick.jconf"
        path.write_text(changed)
        code, out, err = run_cli(
            capsys, "monitor", str(path), "--duration", "1", "--format", "ndjson"
        )
    assert code == 0, err[-2000:]
    records = [json.loads(line) for line in out.splitlines() if line.strip()]
    kinds = {
        r["kind"] for r in records if r.get("type") == "sample" and r.get("device") == "Joystick0"
    }
    assert {"digital", "analog", "hat"} <= kinds
    active = {
        r["name"] for r in records if r.get("type") == "status" and r.get("state") == "active"
    }
    assert {f"Joystick0_d{i}" for i in range(16)} | {f"Joystick0_a{i}" for i in range(10)} <= active
    axis0 = [
        r
        for r in records
        if r.get("type") == "sample"
        and r.get("device") == "Joystick0"
        and r.get("kind") == "analog"
        and r.get("unit") == 0
    ]
    assert len({r["raw"] for r in axis0}) > 5  # the axis moved
    for r in axis0:  # recorded normalised as Gadgeteer's proxies read it, with SDL's raw value
        assert r["value"] == pytest.approx(normalised(r["raw"]), abs=1e-9)


def test_our_example_delivers_through_its_alias(tmp_path: Path, capsys) -> None:
    text = (ROOT / "drivers" / "SdlJoystick_drv" / "example.jconf").read_text()
    with SdlJoystickEmulator(scenario="buttons", rate=50.0, axes=2, buttons=2, hats=1) as emu:
        path = tmp_path / "example.jconf"
        path.write_text(text.replace("<device>0</device>", f"<device>{emu.index}</device>"))
        code, out, err = run_cli(
            capsys, "monitor", str(path), "VJButton0", "--duration", "1", "--format", "ndjson"
        )
    assert code == 0, err[-2000:]
    records = [json.loads(line) for line in out.splitlines() if line.strip()]
    values = {
        r["value"] for r in records if r.get("type") == "sample" and r.get("device") == "VJButton0"
    }
    # TOGGLE_ON (2) and TOGGLE_OFF (3): pressed and released, read through the alias
    assert {int(DigitalState.TOGGLE_ON), int(DigitalState.TOGGLE_OFF)} <= values, out[-2000:]


def test_doctor_checks_the_sdl_index(tmp_path: Path) -> None:
    with SdlJoystickEmulator(scenario="idle", axes=1, buttons=1, hats=0, name="doctor pad") as emu:
        found = check_sdl(emu.index)
        assert found.status is Status.OK and "doctor pad" in found.detail
        missing = check_sdl(emu.index + 5, emulator="SdlJoystick_drv")
        assert missing.status is Status.PROBLEM and missing.code == "DRV100"
        assert "doctor pad" in (missing.hint or "")
        path = tmp_path / "doctor.jconf"
        path.write_text(
            configuration(
                "SdlJoystick_drv", joystick("Pad", emu.index) + joystick("Far", emu.index + 5)
            )
        )
        report = diagnose([path], DoctorOptions())
        checks = {d.name: d.checks for d in report.devices}
        assert [c.status for c in checks["Pad"]] == [Status.OK]
        assert [(c.code, c.prop) for c in checks["Far"]] == [("DRV100", "device")]
        assert report.exit_code == 1
        overview = diagnose([], DoctorOptions())
        assert (emu.index, "doctor pad") in overview.sdl_joysticks
        assert "doctor pad" in render_text(overview)
    assert check_sdl(-1).code == "DRV106"


def test_the_emulator_command_is_a_one_process_demonstration(capsys) -> None:
    assert main(["--scenario", "motion", "--duration", "1.5", "--axes", "2", "--buttons", "3"]) == 0
    out = capsys.readouterr().out
    assert "exists only in this process" in out
    lines = [line for line in out.splitlines() if line.startswith("axes ")]
    assert lines and "buttons 000" in lines[-1]


@pytest.mark.parametrize("how", [signal.SIGTERM, signal.SIGINT])
def test_the_demonstration_stops_cleanly_on_a_signal(how) -> None:
    """SDL is told to leave SIGINT and SIGTERM alone, so the emulator's own handling stops it."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "gadgetctl", "emulate", "SdlJoystick_drv", "--scenario", "buttons"],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    try:
        seen = ""
        while "axes " not in seen:
            line = proc.stdout.readline()
            assert line, f"the demonstration ended early: {seen!r} {proc.stderr.read()!r}"
            seen += line
        proc.send_signal(how)
        _out, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 0, err
    assert "Traceback" not in err


def test_without_pysdl2_the_plugin_fails_with_one_line() -> None:
    script = (
        "import sys; sys.modules['sdl2'] = None; "
        "from gadgetctl.cli.main import main; sys.argv = ['gadgetctl'] + sys.argv[1:]; main()"
    )

    def gadgetctl(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run(
            [sys.executable, "-c", script, *args], capture_output=True, text=True, timeout=60
        )

    loaded = gadgetctl("drivers", "load", "SdlJoystick_drv", "--format", "json")
    assert loaded.returncode == 1 and "Traceback" not in loaded.stderr
    (plugin,) = json.loads(loaded.stdout)["plugins"]
    (diagnostic,) = plugin["diagnostics"]
    assert diagnostic["code"] == "DRV003" and "\n" not in diagnostic["message"]
    assert "pip install PySDL2 pysdl2-dll" in diagnostic["message"]
    listed = json.loads(gadgetctl("drivers", "list", "--format", "json").stdout)["plugins"]
    assert "SdlJoystick_drv" in {p["name"] for p in listed}  # still listed, from its metadata


def test_the_reader_says_when_its_joystick_goes() -> None:
    with SdlJoystickEmulator(scenario="idle", axes=1, buttons=1, hats=0, name="leaving") as emu:
        reader = SdlJoystickReader(emu.index)
        reader.open()
        try:
            emu.detach()
            with pytest.raises(SdlJoystickLost, match=r"\(leaving\) was disconnected"):
                wait_until(lambda: reader.read(0.05) and False, timeout=10.0)
        finally:
            reader.close()


def test_the_reader_counts_its_polls() -> None:
    with SdlJoystickEmulator(scenario="idle", axes=1, buttons=1, hats=1) as emu:
        reader = SdlJoystickReader(emu.index, rate=200.0)
        reader.open()
        try:
            got: list = []
            assert wait_until(lambda: got.extend(reader.read(0.05)) or len(got) >= 10, timeout=10.0)
            assert reader.polls == len(got) and reader.counts == (1, 1, 1)
            assert got[-1].axes == (0,) and got[-1].hats == (0,)
        finally:
            reader.close()
