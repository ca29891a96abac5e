"""Shared fixtures: the corpus, an in-process CLI runner, and a network guard."""

from __future__ import annotations

import ipaddress
import os
import shutil
import signal
import socket
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
if str(Path(__file__).parent) not in sys.path:
    sys.path.insert(0, str(Path(__file__).parent))  # for jccl_samples
CORPUS = REPO.parent / "shared" / "corpus" / "vrjuggler"
CORPUS_DEFINITIONS = CORPUS / "modules" / "vrjuggler" / "data" / "definitions"
CORPUS_CONFIGS = CORPUS / "modules" / "vrjuggler" / "data" / "configFiles"


def pytest_configure(config) -> None:
    """A run started as a background job (`make test &`, `nohup`) inherits SIGINT ignored, and so
    would every process the tests start (an ignored signal stays ignored across exec): the
    Ctrl-C tests then waited for ever. The tests need Python's own Ctrl-C, in here and in children."""
    if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)


@pytest.fixture(scope="session")
def corpus() -> Path:
    """The VR Juggler corpus beside the repository. Missing corpus is a failure, not a skip."""
    assert CORPUS.is_dir(), (
        f"corpus not found at {CORPUS}; ../shared must sit beside the repository"
    )
    return CORPUS


def require_tool(name: str, package: str) -> str:
    """The path of a system tool a test needs. Missing, it is a skip on a developer's machine
    and a failure in CI (``CI`` set), where `.ci/run` installs it: no test skips itself in CI."""
    path = shutil.which(name)
    if path is None:
        message = f"{name} is not installed (apt-get install {package}; .ci/run installs it)"
        if os.environ.get("CI"):
            pytest.fail(message)
        pytest.skip(message)
    return path


def _is_local(address) -> bool:
    if isinstance(address, (str, bytes)):  # AF_UNIX path
        return True
    host = address[0]
    if host in ("localhost", ""):
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


@pytest.fixture(autouse=True)
def no_network(monkeypatch):
    """Fail any test that tries to reach a non-loopback address."""
    real_connect, real_connect_ex, real_sendto = (
        socket.socket.connect,
        socket.socket.connect_ex,
        socket.socket.sendto,
    )

    def guard(address) -> None:
        if not _is_local(address):
            raise AssertionError(f"test tried to reach the network: {address!r}")

    def connect(self, address):
        guard(address)
        return real_connect(self, address)

    def connect_ex(self, address):
        guard(address)
        return real_connect_ex(self, address)

    def sendto(self, data, *args):
        guard(args[-1])
        return real_sendto(self, data, *args)

    monkeypatch.setattr(socket.socket, "connect", connect)
    monkeypatch.setattr(socket.socket, "connect_ex", connect_ex)
    monkeypatch.setattr(socket.socket, "sendto", sendto)


@dataclass
class CliResult:
    exit_code: int
    stdout: str
    stderr: str


@pytest.fixture
def cli(capsys, monkeypatch):
    """Run ``gadgetctl ARGS`` in-process, as the console script does."""
    from gadgetctl.cli.main import main

    def run(*args: str | Path, cwd: Path | None = None) -> CliResult:
        if cwd is not None:
            monkeypatch.chdir(cwd)
        capsys.readouterr()
        code = 0
        try:
            main([str(a) for a in args])
        except SystemExit as exit_:
            code = exit_.code if isinstance(exit_.code, int) else (0 if exit_.code is None else 2)
        out = capsys.readouterr()
        return CliResult(code, out.out, out.err)

    return run


def modules_after_validate(directory: Path) -> set[str]:
    """The modules a fresh `gadgetctl validate DIRECTORY -f json` process has imported when
    the command ends (run through the CLI's main, in a Python process of its own)."""
    import subprocess

    code = (
        "import sys\nfrom gadgetctl.cli.main import main\n"
        "try:\n    main(['validate', sys.argv[1], '-f', 'json'])\n"
        "except SystemExit:\n    pass\n"
        "sys.stderr.write(' '.join(sorted(sys.modules)))"
    )
    done = subprocess.run(
        [sys.executable, "-c", code, str(directory)], capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 0, done.stderr
    return set(done.stderr.split())


def write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


PYTHON = sys.executable
