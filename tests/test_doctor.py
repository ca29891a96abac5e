"""`gadgetctl doctor`: device files, FIFOs, symlinks, permissions, UDP ports, TCP probes,
missing drivers, the system overview and the JSON shape. Loopback only; nothing mocked."""

from __future__ import annotations

import grp
import json
import os
import re
import socket
import stat
import time
from pathlib import Path

import pytest
from test_emulate import Emulation

from gadgetctl.doctor import DoctorOptions, Status, diagnose
from gadgetctl.doctor.permissions import Identity, access_hint, allowed
from gadgetctl.doctor.ports import check_path, check_tcp, check_udp

from conftest import write

pytestmark = pytest.mark.timeout(60)

NOBODY = Identity(65534, frozenset({65534}))
HEAD = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
    '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="doctor test">\n'
    "<elements>\n"
)
TAIL = "</elements>\n</configuration>\n"
DRIVER_CODES = {
    "DRV001",
    "DRV002",
    "DRV003",
    "DRV004",
    "DRV005",
    "DRV006",
    "DRV007",
    "DRV030",
    "DRV031",
}


def config(tmp_path: Path, *elements: str, drivers: tuple[str, ...] = ()) -> Path:
    manager = ""
    if drivers:
        names = "".join(f"<driver>{d}</driver>" for d in drivers)
        manager = f'<input_manager name="IM" version="2">{names}</input_manager>\n'
    return write(tmp_path / "doctor.jconf", HEAD + manager + "\n".join(elements) + "\n" + TAIL)


def fed_fifo(path: Path, mode: int = 0o666) -> int:
    """A FIFO that a program holds open for writing (a FIFO nobody writes is stale, DRV108);
    returns the descriptor to close."""
    os.mkfifo(path, mode)
    os.chmod(path, 0o600)
    fd = os.open(path, os.O_RDWR)
    os.chmod(path, mode)
    return fd


def joydev(path: Path | str) -> str:
    return f'<linux_joydev name="Joystick" version="1"><port_name>{path}</port_name></linux_joydev>'


def dtrack(port: int) -> str:
    return f'<dtrack name="Tracker" version="1"><receive_port>{port}</receive_port></dtrack>'


def motion_star(port: int) -> str:
    return (
        f'<motion_star name="Chassis" version="2"><address>127.0.0.1</address>'
        f"<server_port>{port}</server_port></motion_star>"
    )


def doctor_json(cli, *args) -> tuple[int, dict]:
    result = cli("doctor", "--format", "json", *args)
    assert result.stderr == "", result.stderr
    return result.exit_code, json.loads(result.stdout)


def checks_of(report: dict, name: str) -> list[dict]:
    return next(d for d in report["devices"] if d["name"] == name)["checks"]


def port_codes(report: dict) -> set[str]:
    """Codes of blocking findings other than the driver's own (the bundled wrappers may not load)."""
    return {d["code"] for d in report["diagnostics"] if d["severity"] == "error"} - DRIVER_CODES


# -- a self-contained plug-in with TRANSPORTS metadata --------------------------------------

FIFO_JDEF = """\
<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings definition.version="3.1"?>
<definition xmlns="http://www.vrjuggler.org/jccl/xsd/3.1/definition" name="fifo_device">
   <definition_version version="1" label="Test FIFO device">
      <abstract>false</abstract>
      <help>A device read from a file, for gadgetctl's doctor tests.</help>
      <parent>digital_device</parent>
      <category>/Devices/Digital</category>
      <property valuetype="string" variable="false" name="port_name">
         <help>The device file.</help>
         <value label="Device file" defaultvalue="/dev/null"/>
      </property>
      <upgrade_transform/>
   </definition_version>
</definition>
"""

FIFO_INIT = '''\
"""A device read from a file (doctor tests)."""

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "Fifo_drv"
ELEMENT_TYPES = {"fifo_device": ("digital",)}
TRANSPORTS = {"fifo_device": {"kind": "file", "path": "port_name"}}


def register(registry):
    from gadgetctl.input import Digital

    class FifoDevice(Digital):
        ELEMENT_TYPE = "fifo_device"

        def start_sampling(self):
            pass

        def sample(self):
            pass

        def stop_sampling(self):
            pass

    registry.register_device(FifoDevice)
'''


@pytest.fixture
def fifo_plugin(tmp_path: Path) -> Path:
    """A driver directory holding Fifo_drv (element type fifo_device)."""
    directory = tmp_path / "plugins"
    write(directory / "Fifo_drv" / "__init__.py", FIFO_INIT)
    write(directory / "Fifo_drv" / "fifo_device.jdef", FIFO_JDEF)
    return directory


def fifo_device(path: Path | str) -> str:
    return f'<fifo_device name="Pad" version="1"><port_name>{path}</port_name></fifo_device>'


# -- device files ---------------------------------------------------------------------------


def test_missing_joystick_path_is_a_blocking_finding(cli, tmp_path):
    missing = tmp_path / "js0"
    code, report = doctor_json(cli, config(tmp_path, joydev(missing), drivers=("LinuxJoydev_drv",)))
    assert code == 1
    [check] = checks_of(report, "Joystick")
    assert (
        check["status"] == "problem"
        and check["code"] == "DRV100"
        and check["target"] == str(missing)
    )
    assert check["property"] == "port_name"
    finding = next(d for d in report["diagnostics"] if d["code"] == "DRV100")
    assert finding["line"] == 6 and "gadgetctl emulate LinuxJoydev_drv" in finding["hint"]


def test_missing_dev_input_path_lists_the_joysticks(tmp_path):
    report = diagnose(
        [config(tmp_path, joydev("/dev/input/js7"))],
        DoctorOptions(joystick_glob=str(tmp_path / "none*")),
    )
    finding = next(d for d in report.diagnostics if d.code == "DRV100")
    assert "no joystick devices found" in finding.hint


def test_fifo_made_by_the_emulator_is_fine_and_a_symlink_is_followed(cli, tmp_path):
    fifo = tmp_path / "js0"
    emulation = Emulation("emulate", "LinuxJoydev_drv", "--path", fifo, "--duration", "20")
    try:
        assert emulation.wait_for(r"<port_name>(.+)</port_name>").group(1) == str(fifo)
        assert stat.S_ISFIFO(os.stat(fifo).st_mode)
        link = tmp_path / "joystick"
        link.symlink_to(fifo)
        _, report = doctor_json(cli, config(tmp_path, joydev(link), drivers=("LinuxJoydev_drv",)))
        [check] = checks_of(report, "Joystick")
        assert check["status"] == "ok", check
        assert "FIFO" in check["detail"] and f"a symlink to {fifo}" in check["detail"]
        assert port_codes(report) == set()
        assert emulation.interrupt() == (0, "")
    finally:
        emulation.close()


def test_nothing_blocking_exits_0(cli, tmp_path, fifo_plugin):
    fifo = tmp_path / "pad"
    writer = fed_fifo(fifo)
    try:
        result = cli(
            "doctor",
            "--driver-path",
            fifo_plugin,
            config(tmp_path, fifo_device(fifo), drivers=("Fifo_drv",)),
        )
    finally:
        os.close(writer)
    assert result.exit_code == 0, result.stdout
    assert "ok       Fifo_drv" in result.stdout
    assert re.search(r"ok +port_name .*pad: a FIFO", result.stdout)
    assert result.stdout.rstrip().endswith("nothing found that would stop data from arriving")


def test_a_regular_file_is_only_a_warning(tmp_path, fifo_plugin):
    plain = write(tmp_path / "recorded", "")
    report = diagnose(
        [config(tmp_path, fifo_device(plain), drivers=("Fifo_drv",))],
        DoctorOptions(driver_dirs=[fifo_plugin]),
    )
    [check] = report.devices[0].checks
    assert check.status is Status.WARNING and check.code == "DRV102"
    assert report.exit_code == 0


def test_a_directory_is_not_a_device(tmp_path):
    result = check_path(str(tmp_path), "file")
    assert result.status is Status.PROBLEM and result.code == "DRV102"


# -- permissions ----------------------------------------------------------------------------


def fake_stat(mode: int, uid: int, gid: int) -> os.stat_result:
    return os.stat_result((mode, 0, 0, 1, uid, gid, 0, 0, 0, 0))


def other_group() -> grp.struct_group:
    """A real group that NOBODY is not in, to name in hints."""
    return next(
        g for g in sorted(grp.getgrall(), key=lambda g: g.gr_gid) if g.gr_gid not in NOBODY.gids
    )


def test_permission_logic_from_mode_bits():
    joystick = fake_stat(stat.S_IFCHR | 0o660, 0, 105)
    assert not allowed(joystick, NOBODY, os.R_OK)
    assert allowed(joystick, Identity(1000, frozenset({105})), os.R_OK | os.W_OK)
    assert allowed(joystick, Identity(0, frozenset()), os.R_OK)  # root
    assert allowed(fake_stat(stat.S_IFCHR | 0o604, 0, 0), NOBODY, os.R_OK)  # others may read
    assert not allowed(fake_stat(stat.S_IFCHR | 0o604, 0, 0), NOBODY, os.R_OK | os.W_OK)
    assert not allowed(
        fake_stat(stat.S_IFCHR | 0o066, 65534, 0), NOBODY, os.R_OK
    )  # the owner bits count


def test_group_hint_names_the_group_of_the_file():
    group = other_group()
    hint = access_hint(fake_stat(stat.S_IFCHR | 0o660, 0, group.gr_gid), NOBODY, os.R_OK)
    assert hint.startswith(
        f"add yourself to group {group.gr_name}: sudo usermod -aG {group.gr_name} $USER"
    )
    closed = access_hint(fake_stat(stat.S_IFCHR | 0o600, 0, group.gr_gid), NOBODY, os.R_OK)
    assert "udev rule" in closed and "crw-------" in closed


def test_unreadable_device_for_another_user(tmp_path):
    """The whole doctor path for a user other than the one running (CI runs as root)."""
    device = write(tmp_path / "js0", "")
    device.chmod(0o640)
    group = grp.getgrgid(device.stat().st_gid).gr_name
    checked = check_path(str(device), "file", identity=Identity(4242, frozenset({4242})))
    assert checked.status is Status.PROBLEM and checked.code == "DRV101"
    assert checked.hint.startswith(f"add yourself to group {group}")
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo, 0o600)
    report = diagnose(
        [config(tmp_path, joydev(fifo))], DoctorOptions(identity=Identity(4242, frozenset()))
    )
    [check] = report.devices[0].checks
    assert check.code == "DRV101" and "may not read" in check.detail
    assert report.exit_code == 1


def test_permission_of_the_current_user(cli, tmp_path):
    """os.access decides for the user running doctor: root reads anything, others are refused."""
    fifo = tmp_path / "js0"
    writer = fed_fifo(fifo, 0o000)
    try:
        code, report = doctor_json(
            cli, config(tmp_path, joydev(fifo), drivers=("LinuxJoydev_drv",))
        )
    finally:
        os.close(writer)
    [check] = checks_of(report, "Joystick")
    if os.geteuid() == 0:
        assert check["status"] == "ok" and port_codes(report) == set()
    else:
        assert check["code"] == "DRV101" and code == 1
        assert "add yourself to group" in check["hint"] or "udev rule" in check["hint"]


# -- serial ports ---------------------------------------------------------------------------


def test_pty_behind_a_symlink_is_a_usable_serial_port(tmp_path):
    from gadgetctl.emulation import PseudoTerminal

    link = tmp_path / "glove"
    emulated = PseudoTerminal(link).open()  # an emulator's pty (a bare one is DRV108)
    try:
        checked = check_path(str(link), "serial")
        assert checked.status is Status.OK
        assert f"a symlink to {emulated.address}" in checked.detail and "writable" in checked.detail
    finally:
        emulated.close()


def test_missing_serial_port_of_an_upstream_driver_lists_the_ports(tmp_path):
    # cyber_glove: an upstream serial driver gadgetctl does not bundle (its Makefile builds nothing)
    glove = '<cyber_glove name="Glove" version="1"><port>/dev/ttyUSB97</port></cyber_glove>'
    report = diagnose([config(tmp_path, glove)])
    device = report.devices[0]
    assert device.transport_source == "upstream property names"
    assert device.checks[0].code == "DRV100"
    finding = next(d for d in report.diagnostics if d.code == "DRV100")
    assert "serial ports found" in finding.hint or "no serial ports found" in finding.hint


# -- UDP and TCP ----------------------------------------------------------------------------


def test_udp_port_taken_by_another_socket(cli, tmp_path):
    holder = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        holder.bind(("127.0.0.1", 0))
        port = holder.getsockname()[1]
        code, report = doctor_json(cli, config(tmp_path, dtrack(port), drivers=("DTrack_drv",)))
    finally:
        holder.close()
    assert code == 1
    [check] = checks_of(report, "Tracker")
    assert (
        check["code"] == "DRV103"
        and check["property"] == "receive_port"
        and "taken" in check["detail"]
    )


def test_free_udp_port(cli, tmp_path):
    probe = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    probe.bind(("127.0.0.1", 0))
    port = probe.getsockname()[1]
    probe.close()
    _, report = doctor_json(cli, config(tmp_path, dtrack(port), drivers=("DTrack_drv",)))
    [check] = checks_of(report, "Tracker")
    assert check["status"] == "ok" and port_codes(report) == set()


def test_udp_port_out_of_range():
    assert check_udp(0).code == "DRV106"
    assert check_udp(70000).code == "DRV106"


def test_tcp_server_is_only_contacted_with_probe(cli, tmp_path):
    server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    try:
        server.bind(("127.0.0.1", 0))
        server.listen(1)
        server.settimeout(0.3)
        port = server.getsockname()[1]
        path = config(tmp_path, motion_star(port), drivers=("MotionStar_drv",))

        _, report = doctor_json(cli, path)
        [check] = checks_of(report, "Chassis")
        assert check["status"] == "unchecked" and "--probe" in check["detail"]
        with pytest.raises(TimeoutError):
            server.accept()  # nobody connected

        _, report = doctor_json(cli, "--probe", "--timeout", "2", path)
        [check] = checks_of(report, "Chassis")
        assert check["status"] == "ok" and check["target"] == f"127.0.0.1:{port}"
        conn, _ = server.accept()
        conn.close()
        assert port_codes(report) == set()
    finally:
        server.close()


def test_tcp_server_not_listening(cli, tmp_path):
    closed = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    closed.bind(("127.0.0.1", 0))
    port = closed.getsockname()[1]
    closed.close()
    code, report = doctor_json(
        cli,
        "--probe",
        "--timeout",
        "2",
        config(tmp_path, motion_star(port), drivers=("MotionStar_drv",)),
    )
    assert code == 1
    [check] = checks_of(report, "Chassis")
    assert check["code"] == "DRV104" and "refused" in check["detail"]
    assert "gadgetctl emulate MotionStar_drv" in check["hint"]


def test_tcp_check_without_probe_touches_nothing():
    started = time.monotonic()
    result = check_tcp("tracker.invalid", 6000, probe=False, timeout=5)
    assert result.status is Status.UNCHECKED and time.monotonic() - started < 1


# -- drivers --------------------------------------------------------------------------------


def test_device_whose_driver_is_missing(cli, tmp_path):
    path = config(tmp_path, joydev("/dev/null"), drivers=("NoSuchJoystick_drv",))
    code, report = doctor_json(cli, path)
    assert code == 1
    codes = {d["code"] for d in report["diagnostics"]}
    assert "DRV001" in codes  # the input_manager names a plug-in nobody has
    device = report["devices"][0]
    assert device["pending"] and not device["driver_ok"]
    assert {"DRV030", "DRV031"} & codes
    result = cli("doctor", path)
    assert "NoSuchJoystick_drv" in result.stdout and "stays pending" in result.stdout


def test_device_type_no_plugin_provides(cli, tmp_path):
    code, report = doctor_json(cli, config(tmp_path, '<motionnode name="Remote" version="1"/>'))
    assert code == 1
    device = report["devices"][0]
    assert device["driver"] is None
    codes = {d["code"]: d["severity"] for d in report["diagnostics"]}
    assert codes["DRV030"] == "error" and codes["DRV105"] == "info"
    assert device["checks"][0]["detail"] == "cannot check this device's connection"


def test_plugin_that_fails_to_import(tmp_path, fifo_plugin):
    write(
        fifo_plugin / "Broken_drv" / "__init__.py",
        "GADGETCTL_API_VERSION = 1\nELEMENT_TYPES = {'broken_device': ('digital',)}\n"
        "raise ImportError('needs libfoo')\n\ndef register(registry):\n    pass\n",
    )
    overview = diagnose([], DoctorOptions(driver_dirs=[fifo_plugin]))
    plugins = {p.name: p for p in overview.plugins}
    assert plugins["Fifo_drv"].ok and not plugins["Broken_drv"].ok
    assert "needs libfoo" in plugins["Broken_drv"].error
    broken = next(d for d in overview.diagnostics if d.code == "DRV003")
    assert broken.severity.value == "error" and overview.exit_code == 1
    fifo = tmp_path / "pad"
    writer = fed_fifo(fifo)
    # a configuration that does not use the broken plug-in is not blocked by it
    try:
        used = diagnose(
            [config(tmp_path, fifo_device(fifo), drivers=("Fifo_drv",))],
            DoctorOptions(driver_dirs=[fifo_plugin]),
        )
    finally:
        os.close(writer)
    assert next(d for d in used.diagnostics if d.code == "DRV003").severity.value == "warning"
    assert used.exit_code == 0


def test_transports_naming_an_unknown_property(tmp_path, fifo_plugin):
    init = fifo_plugin / "Fifo_drv" / "__init__.py"
    init.write_text(init.read_text().replace('"path": "port_name"', '"path": "device_file"'))
    fifo = tmp_path / "pad"
    os.mkfifo(fifo)
    report = diagnose(
        [config(tmp_path, fifo_device(fifo), drivers=("Fifo_drv",))],
        DoctorOptions(driver_dirs=[fifo_plugin]),
    )
    [check] = report.devices[0].checks
    assert check.code == "DRV107" and "device_file" in check.detail
    assert report.exit_code == 0


# -- overview, JSON, errors -----------------------------------------------------------------


def test_overview_without_configuration(cli, fifo_plugin):
    code, report = doctor_json(cli, "--driver-path", fifo_plugin)
    assert report["configurations"] == [] and report["devices"] == []
    assert report["definition_path"][0]["origin"] == "bundled"
    assert str(fifo_plugin) in report["driver_places"]
    names = {p["name"]: p for p in report["plugins"]}
    assert names["Fifo_drv"]["loads"] is True and {"LinuxJoydev_drv", "DTrack_drv"} <= set(names)
    assert isinstance(report["serial_ports"], list) and isinstance(report["joysticks"], list)
    assert code == report["exit_code"]
    text = cli("doctor", "--driver-path", fifo_plugin).stdout
    for heading in (
        "Definition search path:",
        "Driver plug-ins",
        "Serial ports:",
        "Joystick devices:",
    ):
        assert heading in text


def test_json_shape(cli, tmp_path):
    _, report = doctor_json(cli, config(tmp_path, joydev(tmp_path / "js0"), dtrack(5999)))
    assert set(report) == {
        "configurations",
        "definition_path",
        "driver_places",
        "plugins",
        "devices",
        "serial_ports",
        "joysticks",
        "diagnostics",
        "blocking",
        "exit_code",
    }
    device = report["devices"][0]
    assert set(device) == {
        "name",
        "type",
        "path",
        "line",
        "driver",
        "driver_ok",
        "pending",
        "transports_from",
        "checks",
    }
    assert set(device["checks"][0]) == {
        "kind",
        "property",
        "target",
        "status",
        "detail",
        "code",
        "hint",
    }
    assert set(report["plugins"][0]) == {
        "name",
        "source",
        "path",
        "loads",
        "error",
        "element_types",
        "used",
        "shadowed_by",
    }
    assert set(report["diagnostics"][0]) == {
        "code",
        "severity",
        "category",
        "path",
        "line",
        "column",
        "message",
        "hint",
    }
    assert report["blocking"] == sum(d["severity"] == "error" for d in report["diagnostics"])


def test_usage_errors_exit_2(cli, tmp_path):
    missing = cli("doctor", tmp_path / "nope.jconf")
    assert (
        missing.exit_code == 2
        and missing.stderr.strip()
        == f"gadgetctl: error: {tmp_path / 'nope.jconf'}: no such configuration file"
    )
    bad = cli("doctor", "--timeout", "0")
    assert bad.exit_code == 2 and "Traceback" not in bad.stderr
    broken = write(tmp_path / "broken.jconf", "<configuration")
    result = cli("doctor", broken)
    assert result.exit_code == 2 and len(result.stderr.strip().splitlines()) == 1


def test_doctor_help_is_reachable(cli):
    result = cli("doctor", "--help")
    assert result.exit_code == 0 and "--probe" in result.stdout
