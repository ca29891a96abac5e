"""Generated drivers work untouched: for every transport and several combinations of device
types, the generated .jdef and example.jconf validate clean, `drivers list` finds the
plug-in, `drivers load` loads it, `monitor` shows samples from its emulator, the code
passes ruff, and the generated tests pass (run in a subprocess, all drivers at once, as
cookiecutter-pytest-plugin tests its template). A --package project installs into a fresh
virtual environment and is found through its entry point.
"""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import sysconfig
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import pytest
from lxml import etree

from gadgetctl.scaffold import DriverSpec, scaffold

from conftest import REPO

CONFIG_NS = "http://www.vrjuggler.org/jccl/xsd/3.0/configuration"


@dataclass(frozen=True)
class Case:
    name: str
    transport: str
    types: tuple[str, ...]

    @property
    def id(self) -> str:
        return f"{self.transport}-{'+'.join(self.types)}"


CASES = [
    Case("ButtonBox", "serial", ("digital",)),
    Case("AxisPad", "udp", ("analog", "digital")),
    Case("TrackerPuck", "tcp", ("position",)),
    Case("DataMitt", "file", ("glove", "digital")),
    Case("SelfMade", "none", ("analog", "digital")),
    # every type at once, with the longest name accepted (generated lines stay within 88)
    Case(
        "Abcdefghijklmnopqrstuvwxyz" + "abcdef",
        "serial",
        ("analog", "digital", "position", "glove", "gesture", "command", "string", "hat"),
    ),
    Case(
        "EverythingAtOnce",
        "udp",
        ("hat", "string", "command", "gesture", "glove", "position", "analog", "digital"),
    ),
]


@dataclass
class Generated:
    case: Case
    spec: DriverSpec

    @property
    def plugin(self) -> str:
        return self.spec.names.plugin

    @property
    def folder(self) -> Path:
        return self.spec.plugin_dir

    @property
    def parent(self) -> Path:
        return self.spec.plugin_dir.parent


@pytest.fixture(scope="module")
def generated(tmp_path_factory) -> dict[str, Generated]:
    """Every case generated once, each in its own directory."""
    found = {}
    for case in CASES:
        directory = tmp_path_factory.mktemp(case.id)
        spec = DriverSpec.create(
            case.name, case.types, case.transport, vendor="Acme", directory=directory
        )
        scaffold(spec)
        found[case.id] = Generated(case, spec)
    return found


@pytest.fixture(params=CASES, ids=[c.id for c in CASES])
def driver(request, generated) -> Generated:
    return generated[request.param.id]


def test_validate_is_clean(cli, driver):
    result = cli("validate", driver.folder, "--strict", "--format", "json")
    assert result.exit_code == 0, result.stdout
    assert json.loads(result.stdout) == []


def test_drivers_list_finds_the_plugin(cli, driver, monkeypatch):
    monkeypatch.delenv("GADGETCTL_DRIVER_PATH", raising=False)
    result = cli("drivers", "list", "--driver-path", driver.parent, "--format", "json")
    assert result.exit_code == 0, result.stderr
    (entry,) = [p for p in json.loads(result.stdout)["plugins"] if p["name"] == driver.plugin]
    assert entry["source"] == "--driver-path"
    assert entry["problems"] == []
    assert entry["provides"] == {driver.spec.names.element_type: list(driver.case.types)}
    assert entry["api_version"] == 1
    monkeypatch.setenv("GADGETCTL_DRIVER_PATH", str(driver.parent))
    listed = json.loads(cli("drivers", "list", "--format", "json").stdout)["plugins"]
    assert [p["source"] for p in listed if p["name"] == driver.plugin] == ["GADGETCTL_DRIVER_PATH"]


def test_drivers_load_succeeds(cli, driver):
    result = cli(
        "drivers", "load", "--driver-path", driver.parent, driver.plugin, "--format", "json"
    )
    assert result.exit_code == 0, result.stdout
    (loaded,) = json.loads(result.stdout)["plugins"]
    assert loaded["ok"] is True
    assert loaded["diagnostics"] == []


def test_emulate_runs_the_emulator(cli, driver, tmp_path):
    if driver.case.transport == "none":
        result = cli("emulate", "--driver-path", driver.parent, driver.plugin)
        assert result.exit_code == 2 and "ships no emulator" in result.stderr
        return
    where = {
        "serial": ["--port", tmp_path / "tty"],
        "file": ["--path", tmp_path / "fifo"],
        "udp": ["--port", str(free_udp_port())],
        "tcp": ["--port", "0"],
    }[driver.case.transport]
    result = cli(
        "emulate", "--driver-path", driver.parent, driver.plugin, *where, "--duration", "0.2"
    )
    assert result.exit_code == 0, result.stderr
    assert f"Point the {driver.spec.names.element_type} element at it" in result.stdout


def test_monitor_shows_samples_from_the_emulator(cli, driver, tmp_path):
    with emulator_for(driver, tmp_path) as values:
        config = example_configuration(driver, tmp_path, values)
        result = cli("monitor", config, "--duration", "1.0", "--format", "ndjson")
    assert result.exit_code == 0, result.stderr
    records = [json.loads(line) for line in result.stdout.splitlines()]
    device = driver.spec.names.camel
    kinds = {r["kind"] for r in records if r["type"] == "sample" and r.get("device") == device}
    assert kinds == set(driver.case.types)
    statuses = [r for r in records if r["type"] == "status"]
    assert statuses and all(r["state"] in ("running", "active") for r in statuses), statuses


def test_generated_code_passes_ruff(generated):
    ruff = [sys.executable, "-m", "ruff"]
    folders = [str(g.folder) for g in generated.values()]
    config = ["--config", str(REPO / "pyproject.toml")]
    for command in (
        [*ruff, "check", *config, *folders],
        [*ruff, "format", "--check", *config, *folders],
        # ruff's default line length too, for authors without a configuration
        [*ruff, "format", "--check", "--isolated", "--line-length", "88", *folders],
    ):
        proc = subprocess.run(command, capture_output=True, text=True, timeout=60)
        assert proc.returncode == 0, proc.stdout + proc.stderr


def test_generated_tests_pass(generated, tmp_path):
    """All generated test suites in one pytest run, in a subprocess."""
    tests = [str(g.folder / "tests") for g in generated.values()]
    env = {k: v for k, v in os.environ.items() if k not in ("GADGETCTL_DRIVER_PATH", "PYTHONPATH")}
    proc = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *tests],
        capture_output=True,
        text=True,
        timeout=240,
        cwd=tmp_path,
        env=env,
    )
    assert proc.returncode == 0, proc.stdout[-6000:] + proc.stderr[-2000:]
    summary = proc.stdout.strip().splitlines()[-1]
    emulated = sum(g.case.transport != "none" for g in generated.values())
    expected = (
        7 * emulated
        + 4 * (len(generated) - emulated)
        + sum("position" in g.case.types for g in generated.values())
    )
    assert summary.startswith(f"{expected} passed"), summary


def test_package_installs_and_is_found_by_its_entry_point(tmp_path):
    spec = DriverSpec.create(
        "AcmeMitt", ["glove", "digital"], "udp", package=True, directory=tmp_path
    )
    scaffold(spec)
    python = fresh_venv(tmp_path / "venv")
    install = subprocess.run(
        [
            python,
            "-m",
            "pip",
            "install",
            "--no-deps",
            "--no-build-isolation",
            "--no-index",
            "--quiet",
            str(spec.target),
        ],
        capture_output=True,
        text=True,
        timeout=180,
    )
    assert install.returncode == 0, install.stdout + install.stderr
    listed = subprocess.run(
        [python, "-m", "gadgetctl", "drivers", "list", "--format", "json"],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=tmp_path,
    )
    assert listed.returncode == 0, listed.stderr
    (entry,) = [p for p in json.loads(listed.stdout)["plugins"] if p["name"] == "AcmeMitt_drv"]
    assert entry["source"] == "entry point"
    assert entry["module"] == "AcmeMitt_drv"
    assert Path(entry["path"]).is_relative_to(tmp_path / "venv")
    assert entry["provides"] == {"acme_mitt": ["glove", "digital"]}
    loaded = subprocess.run(
        [python, "-m", "gadgetctl", "drivers", "load", "AcmeMitt_drv"],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=tmp_path,
    )
    assert loaded.returncode == 0, loaded.stdout + loaded.stderr
    # the project's own tests, run the way its README says: `python -m pytest` in the project
    tested = subprocess.run(
        [python, "-m", "pytest", "-q", "-p", "no:cacheprovider"],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=spec.target,
    )
    assert tested.returncode == 0, tested.stdout[-4000:] + tested.stderr[-2000:]
    assert tested.stdout.strip().splitlines()[-1].startswith("7 passed"), tested.stdout


# -- helpers -------------------------------------------------------------------------------------


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


@contextmanager
def emulator_for(driver: Generated, tmp_path: Path) -> Iterator[dict[str, str]]:
    """Run the generated emulator, loaded the way `gadgetctl emulate` loads it, at an address
    of the test's own; yields the device properties that point at it."""
    from gadgetctl.input.plugins.discovery import DriverSearch
    from gadgetctl.input.plugins.emulators import find_emulator, load_emulator

    transport = driver.case.transport
    if transport == "none":
        yield {}
        return
    search = DriverSearch.standard([driver.parent], bundled=False, entry_points=False, environ={})
    module = load_emulator(find_emulator(driver.plugin, search))
    cls = getattr(module, f"{driver.spec.names.camel}Emulator")
    where = {
        "serial": tmp_path / "tty",
        "file": tmp_path / "fifo",
        "udp": free_udp_port(),
        "tcp": 0,
    }
    with cls(where[transport], rate=200.0) as emulator:
        if transport in ("serial", "file"):
            yield {"port" if transport == "serial" else "path": emulator.address}
        elif transport == "udp":
            yield {"port": str(emulator.port)}
        else:
            yield {"host": emulator.host, "port": str(emulator.port)}


def example_configuration(driver: Generated, tmp_path: Path, values: dict[str, str]) -> Path:
    """The generated example.jconf, with an absolute driver_path and ``values`` set."""
    tree = etree.parse(str(driver.folder / "example.jconf"))
    ns = {"j": CONFIG_NS}
    for element in tree.iterfind(".//j:input_manager/j:driver_path", ns):
        element.text = str(driver.parent)
    device = tree.find(f"j:elements/j:{driver.spec.names.element_type}", ns)
    for name, value in values.items():
        device.find(f"j:{name}", ns).text = value
    path = tmp_path / "example.jconf"
    tree.write(str(path), xml_declaration=True, encoding="UTF-8")
    return path


def fresh_venv(path: Path) -> str:
    """A new virtual environment that also sees this interpreter's packages (gadgetctl,
    hatchling, pip...), so nothing is downloaded."""
    subprocess.run(
        [sys.executable, "-m", "venv", "--system-site-packages", "--without-pip", str(path)],
        check=True,
        timeout=120,
        capture_output=True,
    )
    python = path / "bin" / "python"
    if not python.exists():
        python = path / "Scripts" / "python.exe"
    purelib = subprocess.run(
        [str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
        check=True,
        capture_output=True,
        text=True,
        timeout=60,
    ).stdout.strip()
    ours = dict.fromkeys(sysconfig.get_paths()[k] for k in ("purelib", "platlib"))
    lines = "".join(f"import site; site.addsitedir({d!r})\n" for d in ours)
    Path(purelib, "_gadgetctl_test_parent.pth").write_text(lines, encoding="utf-8")
    return str(python)
