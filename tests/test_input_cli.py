"""`gadgetctl config pending`: what the input manager would leave pending, and why."""

import json
from pathlib import Path

import pytest
import typer
from typer.testing import CliRunner

from gadgetctl.cli.pending_cmd import pending
from gadgetctl.resources import examples_dir

CONFIGS = Path("/work/shared/corpus/vrjuggler/modules/vrjuggler/data/configFiles")
CORPUS_DEFINITIONS = CONFIGS.parent / "definitions"
PLUGINS = Path(__file__).parent / "data" / "plugins"
needs_corpus = pytest.mark.usefixtures("corpus")  # a missing corpus fails, never skips


def run(*args):
    app = typer.Typer()

    @app.callback()
    def root() -> None:
        """Test root."""

    app.command("pending")(pending)
    extra = ["--definitions", str(CORPUS_DEFINITIONS)] if CORPUS_DEFINITIONS.is_dir() else []
    return CliRunner().invoke(app, ["pending", *args, *extra])


def test_examples_leave_nothing_pending():
    result = run(str(examples_dir() / "all_devices.jconf"), str(examples_dir() / "waveform.jconf"))
    assert result.exit_code == 0, result.output
    assert "0 pending, 0 stupefied proxies" in result.output


@needs_corpus
def test_simulator_configuration_reports_nothing(tmp_path):
    result = run(str(CONFIGS / "sim.base.jconf"), str(CONFIGS / "sim.wand.mixin.jconf"))
    assert result.exit_code == 0, result.output
    assert "0 pending" in result.output


@needs_corpus
def test_pending_elements_and_stupefied_proxies_with_reasons(tmp_path):
    # sim.trackd.jconf naming a driver gadgetctl lacks (Trackd_drv itself is bundled now)
    text = (CONFIGS / "sim.trackd.jconf").read_text()
    assert text.count("<driver>Trackd_drv</driver>") == 1
    config = tmp_path / "sim.trackd.jconf"
    config.write_text(text.replace("<driver>Trackd_drv</driver>", "<driver>TrackdShm_drv</driver>"))
    result = run(str(config), "--format", "json")
    assert result.exit_code == 1
    report = json.loads(result.output)
    pending = {p["name"]: p for p in report["pending"]}
    assert set(pending) == {"TrackdSensorDev", "TrackdControllerDev"}
    assert pending["TrackdSensorDev"]["code"] == "DRV030" and pending["TrackdSensorDev"]["line"]
    assert {s["name"] for s in report["stupefied"]} >= {"Wand Proxy", "Head Proxy"}
    assert any(
        d["code"] == "DRV001" and "TrackdShm_drv" in d["message"] for d in report["diagnostics"]
    )
    text = run(str(config)).output
    assert (
        "error DRV030 TrackdSensorDev (trackd_sensor) stays pending: no loaded driver handles trackd_sensor"
        in text
    )
    assert "TrackdShm_drv" in text


def test_driver_path_option_and_start(tmp_path):
    path = tmp_path / "button.jconf"
    path.write_text("""<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="b"><elements>
  <input_manager name="IM" version="2"><driver>Button_drv</driver><driver>Mismatch_drv</driver></input_manager>
  <button_device name="Button" version="1"/>
  <mismatch_device name="Odd" version="1"/>
</elements></configuration>
""")
    result = run(str(path), "--driver-path", str(PLUGINS), "--start", "--format", "json")
    assert result.exit_code == 1
    report = json.loads(result.output)
    assert [p["name"] for p in report["pending"]] == ["Odd"]
    assert report["pending"][0]["code"] == "DRV031"
    assert report["configured"] == {"device": 1, "input_manager": 1}


def test_missing_file_is_a_usage_error(tmp_path):
    result = run(str(tmp_path / "nope.jconf"))
    assert result.exit_code != 0
