"""Every input path is read with the size limit, whatever it names (issue 13 item 6):
devices and FIFOs are refused before anything is read, an oversized file is a diagnostic in
every command."""

from __future__ import annotations

import os

import pytest

from gadgetctl.boundedread import FileTooLarge, NotRegularFile, read_limited

COMMANDS = (
    ("validate",),
    ("config", "show"),
    ("config", "graph"),
    ("upgrade", "--check"),
    ("upgrade",),
)


@pytest.fixture
def fifo(tmp_path):
    path = tmp_path / "pipe.jconf"
    os.mkfifo(path)
    return path


@pytest.fixture
def oversized(tmp_path):
    path = tmp_path / "big.jconf"
    with open(path, "wb") as f:
        f.truncate(17 * 1024 * 1024)  # sparse: above the 16 MiB limit without using the disk
    return path


@pytest.mark.timeout(60)
@pytest.mark.parametrize("command", COMMANDS, ids=" ".join)
@pytest.mark.parametrize("device", ["/dev/zero", "/dev/urandom"])
def test_devices_are_refused_before_reading(cli, command, device):
    result = cli(*command, device)
    assert result.exit_code in (1, 2)
    assert "not a regular file" in result.stdout + result.stderr
    assert "internal error" not in result.stderr


@pytest.mark.timeout(60)
@pytest.mark.parametrize("command", COMMANDS, ids=" ".join)
def test_a_fifo_is_refused_without_blocking(cli, command, fifo):
    result = cli(*command, fifo)
    assert result.exit_code in (1, 2)
    assert "a FIFO, not a regular file" in result.stdout + result.stderr


@pytest.mark.timeout(60)
@pytest.mark.parametrize("command", COMMANDS, ids=" ".join)
def test_an_oversized_configuration_is_a_diagnostic_everywhere(cli, command, oversized):
    result = cli(*command, oversized)
    assert result.exit_code in (1, 2), "an unread file must not pass"
    assert "above the limit of 16777216" in result.stdout + result.stderr
    assert "all up to date" not in result.stdout


@pytest.mark.timeout(60)
def test_replay_refuses_a_fifo(cli, fifo):
    result = cli("replay", fifo, "--summary")
    assert result.exit_code == 2 and "a FIFO, not a regular file" in result.stderr


def test_read_limited_does_not_trust_the_reported_size(tmp_path):
    # /proc files report size 0 but have content; a limit still applies to what is read
    assert read_limited("/proc/self/status", 1 << 20).startswith(b"Name:")
    with pytest.raises(FileTooLarge):
        read_limited("/proc/self/status", 10)
    with pytest.raises(NotRegularFile):
        read_limited(tmp_path)
