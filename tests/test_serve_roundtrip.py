"""Issue 11's round trip: `serve examples/waveform.jconf` -> a configuration of `vrpn`
elements (VRPN_drv) -> `monitor --format ndjson`. Positions equal the served ones, buttons
change exactly as served (and the receiving proxies toggle), analogs are normalised with the
receiving element's range, and the receiving side's proxies and aliases deliver. The
corpus's example.vrpn.jconf, with only its three server names changed, runs against serve."""

from __future__ import annotations

import json
import re
import subprocess
import sys

import numpy as np
import pytest

from conftest import CORPUS_CONFIGS, REPO, write
from serve_process import ServeProcess

RECEIVER = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="receiver">
   <elements>
      <input_manager name="Input Manager" version="2"><driver>VRPN_drv</driver></input_manager>
      <vrpn name="Remote Tracker" version="3">
         <tracker_server>Waveform_Tracker@tcp://127.0.0.1:{port}</tracker_server>
         <button_server></button_server><analog_server></analog_server>
         <tracker_count>3</tracker_count><button_count>0</button_count><analog_count>0</analog_count>
      </vrpn>
      <vrpn name="Remote Sticks" version="3">
         <tracker_server></tracker_server>
         <button_server>Waveform_Sticks@tcp://127.0.0.1:{port}</button_server>
         <analog_server>Waveform_Sticks@tcp://127.0.0.1:{port}</analog_server>
         <tracker_count>0</tracker_count><button_count>2</button_count><analog_count>2</analog_count>
         <min>-1.0</min><max>1.0</max>
      </vrpn>
      <vrpn name="Remote Aliases" version="3">
         <tracker_server>VJWand@127.0.0.1:{port}</tracker_server>
         <button_server>VJButton0@127.0.0.1:{port}</button_server>
         <analog_server>VJNoise@127.0.0.1:{port}</analog_server>
         <tracker_count>1</tracker_count><button_count>1</button_count><analog_count>1</analog_count>
         <min>0.0</min><max>1.0</max>
      </vrpn>
      <position_proxy name="RWand Proxy" version="1"><device>Remote Tracker</device><unit>0</unit></position_proxy>
      <digital_proxy name="RTrigger Proxy" version="1"><device>Remote Sticks</device><unit>0</unit></digital_proxy>
      <analog_proxy name="RStick Proxy" version="1"><device>Remote Sticks</device><unit>0</unit></analog_proxy>
      <position_proxy name="Far Wand Proxy" version="1"><device>Remote Aliases</device><unit>0</unit></position_proxy>
      <alias name="RVJWand" version="1"><proxy>RWand Proxy</proxy></alias>
      <alias name="RVJButton0" version="1"><proxy>RTrigger Proxy</proxy></alias>
      <alias name="RVJAnalog0" version="1"><proxy>RStick Proxy</proxy></alias>
      <alias name="FarWand" version="1"><proxy>Far Wand Proxy</proxy></alias>
   </elements>
</configuration>
"""


def records(text: str) -> list[dict]:
    return [json.loads(line) for line in text.splitlines() if line.strip()]


def unit_values(recs: list[dict], device: str, kind: str) -> dict[int, list]:
    units: dict[int, list] = {}
    for r in recs:
        if r.get("type") == "sample" and r["device"] == device and r["kind"] == kind:
            units.setdefault(r["unit"], []).append(r)
    return units


def changes(values: list) -> list:
    """The values with consecutive repeats removed."""
    out: list = []
    for v in values:
        if not out or not np.array_equal(np.asarray(out[-1]), np.asarray(v)):
            out.append(v)
    return out


def is_run_of(got: list, served: list, close) -> bool:
    """Whether ``got`` is a run of consecutive entries of ``served``."""
    for start in range(len(served) - len(got) + 1):
        if close(got[0], served[start]) and all(
            close(g, s) for g, s in zip(got, served[start:], strict=False)
        ):
            return True
    return False


def monitor(config, *names: str, duration: float = 4.0) -> subprocess.CompletedProcess:
    return subprocess.run(
        [
            sys.executable,
            "-m",
            "gadgetctl",
            "monitor",
            str(config),
            *names,
            "--duration",
            str(duration),
            "--format",
            "ndjson",
        ],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=90,
    )


@pytest.mark.timeout(180)
def test_serve_to_vrpn_elements_to_monitor(tmp_path):
    served_file = tmp_path / "served.ndjson"
    with ServeProcess(REPO / "examples" / "waveform.jconf", "--record", served_file) as serve:
        receiver = write(tmp_path / "receiver.jconf", RECEIVER.format(port=serve.port))
        result = monitor(receiver, "Remote*", "RVJWand", "RVJButton0", "RVJAnalog0", "FarWand")
        assert serve.stop() == 0, serve.stderr
    assert result.returncode == 0, result.stderr[-3000:]
    got, served = records(result.stdout), records(served_file.read_text())

    # positions: each received pose is a served one (doubles, 1e-9), in order, none missing
    served_poses = unit_values(served, "Waveform Tracker", "position")
    received_poses = unit_values(got, "Remote Tracker", "position")
    assert set(received_poses) == {0, 1, 2}
    for unit, rows in received_poses.items():
        mine = changes([r["value"] for r in rows])[1:]  # the first is the state before any report
        theirs = changes([r["value"] for r in served_poses[unit]])
        assert len(mine) > 50
        assert is_run_of(mine, theirs, lambda a, b: np.allclose(a, b, rtol=0, atol=1e-9)), unit

    # buttons: the same transitions, exactly; the receiving proxy and its alias toggle
    served_buttons = unit_values(served, "Waveform Sticks", "digital")
    received_buttons = unit_values(got, "Remote Sticks", "digital")
    for unit in (0, 1):
        mine = changes([r["value"] for r in received_buttons[unit]])
        theirs = changes([r["value"] for r in served_buttons[unit]])
        assert len(mine) >= 3 and is_run_of(mine[1:], theirs, lambda a, b: a == b)
    toggles = [r["value"] for r in got if r.get("device") == "RVJButton0"]
    presses = sum(
        1
        for a, b in zip(received_buttons[0], received_buttons[0][1:], strict=False)
        if a["value"] == 0 and b["value"] == 1
    )
    assert 2 in toggles and 3 in toggles  # toggle on, toggle off
    assert abs(toggles.count(2) - presses) <= 1

    # analogs: the raw values travel unchanged, normalised with the receiving element's range
    served_analog = unit_values(served, "Waveform Sticks", "analog")
    for unit, rows in unit_values(got, "Remote Sticks", "analog").items():
        raws = [r.get("raw", r["value"]) for r in rows][1:]
        assert is_run_of(
            changes(raws),
            changes([r.get("raw", r["value"]) for r in served_analog[unit]]),
            lambda a, b: a == b,
        )
        assert all(abs(r["value"] - (r.get("raw", r["value"]) + 1.0) / 2.0) < 1e-12 for r in rows)
    stick = [r for r in got if r.get("device") == "RVJAnalog0"]
    assert stick and all(0.0 <= r["value"] <= 1.0 for r in stick)

    # the served aliases (normalised VJNoise, VJWand's filtered pose) and the receiving side's
    # proxies and aliases deliver
    noise = unit_values(got, "Remote Aliases", "analog")[0][1:]
    assert noise and all(0.0 <= r.get("raw", r["value"]) <= 1.0 for r in noise)
    for name in ("RVJWand", "RVJButton0", "RVJAnalog0", "FarWand"):
        assert any(r.get("type") == "sample" and r["device"] == name for r in got), name
    states = {r["name"]: r["state"] for r in got if r.get("type") == "status"}
    assert states["RVJWand"] == states["FarWand"] == "active"
    assert all(
        states[n] == "running" for n in ("Remote Tracker", "Remote Sticks", "Remote Aliases")
    )


SERVED_AS_CORPUS = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="lab">
   <elements>
      <waveform_device name="Tracker0" version="1">
         <rate>100.0</rate><event_period>0.0</event_period>
         <position_path>circle</position_path><position_path>figure_eight</position_path>
      </waveform_device>
      <waveform_device name="Button0" version="1">
         <rate>100.0</rate><event_period>0.0</event_period>
         <button_period>0.4</button_period><button_period>0.6</button_period>
         <button_period>0.8</button_period><button_period>1.0</button_period>
      </waveform_device>
      <waveform_device name="Analog0" version="1">
         <rate>100.0</rate><event_period>0.0</event_period><analog_waveform>sine</analog_waveform>
      </waveform_device>
   </elements>
</configuration>
"""


@pytest.mark.timeout(180)
def test_the_corpus_vrpn_example_runs_against_serve(tmp_path):
    original = (CORPUS_CONFIGS / "example.vrpn.jconf").read_text()
    with ServeProcess(write(tmp_path / "lab.jconf", SERVED_AS_CORPUS)) as serve:
        # only the three server names change
        text, count = re.subn(
            r"(\w+)@alpha\.cs\.ucl\.ac\.uk", rf"\1@127.0.0.1:{serve.port}", original
        )
        assert count == 3
        config = write(tmp_path / "example.vrpn.jconf", text)
        result = monitor(config, duration=3.0)
        assert serve.stop() == 0
    assert result.returncode == 0, result.stderr[-3000:]
    got = records(result.stdout)
    states = {r["name"]: r["state"] for r in got if r.get("type") == "status"}
    proxies = [
        "HeadProxy",
        "WandProxy",
        "Button0Proxy",
        "Button1Proxy",
        "Button2Proxy",
        "Button3Proxy",
    ]
    aliases = ["VJHead", "VJWand", "VJButton0", "VJButton1", "VJButton2", "VJButton3"]
    assert states["Vrpn"] == "running"
    assert all(states[name] == "active" for name in proxies + aliases), states
    kinds = {r["kind"] for r in got if r.get("type") == "sample" and r["device"] == "Vrpn"}
    assert kinds == {"position", "digital"}
    pressed = {
        r["unit"]
        for r in got
        if r.get("type") == "sample"
        and r["device"] == "Vrpn"
        and r["kind"] == "digital"
        and r["value"] == 1
    }
    assert pressed == {0, 1, 2, 3}
