"""`validate` and the run time agree about a device whose driver is never loaded (issue 25
item 2): a linux_joydev element in a configuration whose input_manager loads only DTrack_drv
is pending for the input manager (DRV030) and for validate (CFG041, an error), with the same
reason from gadgetctl.input.unloaded."""

from __future__ import annotations

import pytest

from conftest import write

TEMPLATE = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="joy">
  <elements>
    <input_manager name="Input Manager" version="2">
      {drivers}
    </input_manager>
    <linux_joydev name="Gamepad" version="1">
      <port_name>/dev/input/js0</port_name>
    </linux_joydev>
    <digital_proxy name="Fire" version="1"><device>Gamepad</device><unit>0</unit></digital_proxy>
  </elements>
</configuration>
"""
REASON = "no loaded driver handles linux_joydev"
HINT = "add <driver>LinuxJoydev_drv</driver> to an input_manager element"


def config(tmp_path, drivers: str):
    return write(tmp_path / "joy.jconf", TEMPLATE.format(drivers=drivers))


@pytest.mark.parametrize("together", [True, False])
def test_validate_says_what_the_input_manager_says(cli, tmp_path, together):
    path = config(tmp_path, "<driver>DTrack_drv</driver>")
    validated = cli("validate", *(["--together"] if together else []), path)
    assert validated.exit_code == 1
    findings = [line for line in validated.stdout.splitlines() if " CFG041 " in line]
    assert findings == [
        f"{path}:8:5: error CFG041 linux_joydev 'Gamepad' would stay pending: {REASON} "
        f"(plug-in LinuxJoydev_drv (bundled) provides linux_joydev: {HINT})"
    ]
    pending = cli("config", "pending", path)
    assert pending.exit_code == 1
    assert f"{path}:8:5: error DRV030 Gamepad (linux_joydev) stays pending: {REASON}" in (
        pending.stdout
    )
    assert HINT in pending.stdout


def test_loading_the_driver_clears_both(cli, tmp_path):
    path = config(tmp_path, "<driver>DTrack_drv</driver><driver>LinuxJoydev_drv</driver>")
    validated = cli("validate", "--together", path)
    assert "CFG041" not in validated.stdout, validated.stdout
    pending = cli("config", "pending", path)
    assert "DRV030" not in pending.stdout, pending.stdout


def test_a_scanned_directory_is_left_to_the_run_time(cli, tmp_path):
    (tmp_path / "plugins").mkdir()
    path = config(tmp_path, "<driver_scan_path>plugins</driver_scan_path>")
    validated = cli("validate", path)
    assert REASON not in validated.stdout


def test_the_builtin_types_are_those_of_the_builtin_devices():
    from gadgetctl.input.builtin import BUILTIN_DEVICES
    from gadgetctl.input.unloaded import BUILTIN_TYPES

    assert {cls.ELEMENT_TYPE for cls in BUILTIN_DEVICES} == BUILTIN_TYPES
