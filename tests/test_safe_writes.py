"""Writes of a user's file (issue 13 items 3 and 10): `upgrade --in-place` and `-o`,
`--record --overwrite`, `scaffold driver`, against real symbolic links, owners, a full and
a read-only file system (a small tmpfs mounted for the test; CI runs as root)."""

from __future__ import annotations

import os
import shutil
import stat
import subprocess
from pathlib import Path

import pytest
import typer

from conftest import CORPUS_CONFIGS

OLD_FILE = CORPUS_CONFIGS / "example.vrpn.jconf"  # one vrpn element version 1 -> 2


@pytest.fixture
def old_file(tmp_path, corpus) -> Path:
    path = tmp_path / "tracker.jconf"
    shutil.copyfile(OLD_FILE, path)
    return path


def _leftovers(directory: Path) -> list[str]:
    return sorted(p.name for p in directory.iterdir() if p.name.endswith(".tmp"))


@pytest.fixture
def small_fs(tmp_path):
    """A 96 KiB tmpfs, unmounted afterwards; ``fill()`` takes all its free space."""
    mount = tmp_path / "fs"
    mount.mkdir()
    subprocess.run(["mount", "-t", "tmpfs", "-o", "size=96k", "tmpfs", str(mount)], check=True)

    class Fs:
        path = mount

        @staticmethod
        def fill() -> None:
            with open(mount / "filler", "wb", buffering=0) as f:
                try:
                    while True:
                        f.write(b"\0" * 4096)
                except OSError:
                    pass

        @staticmethod
        def read_only() -> None:
            subprocess.run(["mount", "-o", "remount,ro", str(mount)], check=True)

    yield Fs
    subprocess.run(["umount", "-l", str(mount)], check=False)


def test_in_place_replaces_a_bak_symlink_instead_of_writing_through_it(cli, old_file, tmp_path):
    victim = tmp_path / "victim"
    victim.write_text("precious\n")
    backup = tmp_path / "tracker.jconf.bak"
    backup.symlink_to(victim)
    original = old_file.read_bytes()
    result = cli("upgrade", "--in-place", old_file)
    assert result.exit_code == 0, result.stderr
    assert victim.read_text() == "precious\n"
    assert not backup.is_symlink() and backup.read_bytes() == original
    assert old_file.read_bytes() != original


def test_in_place_upgrades_the_target_of_a_symlinked_file_and_says_so(cli, old_file, tmp_path):
    link = tmp_path / "link.jconf"
    link.symlink_to(old_file.name)
    result = cli("upgrade", "--in-place", link)
    assert result.exit_code == 0, result.stderr
    assert link.is_symlink() and os.readlink(link) == old_file.name
    assert old_file.read_bytes() != OLD_FILE.read_bytes()
    assert str(old_file) in result.stdout and "symbolic link" in result.stdout
    assert (tmp_path / "tracker.jconf.bak").is_file() and not (tmp_path / "link.jconf.bak").exists()


def test_in_place_keeps_owner_group_and_mode(cli, old_file, tmp_path):
    os.chown(old_file, 1234, 1234)
    old_file.chmod(0o640)
    result = cli("upgrade", "--in-place", old_file)
    assert result.exit_code == 0, result.stderr
    for path in (old_file, tmp_path / "tracker.jconf.bak"):
        info = path.stat()
        assert (info.st_uid, info.st_gid, stat.S_IMODE(info.st_mode)) == (1234, 1234, 0o640), path


def test_a_full_disk_is_one_line_and_keeps_the_file_and_the_previous_backup(cli, small_fs):
    path = small_fs.path / "tracker.jconf"
    shutil.copyfile(OLD_FILE, path)
    backup = small_fs.path / "tracker.jconf.bak"
    backup.write_text("the previous good backup\n")
    original = path.read_bytes()
    small_fs.fill()
    result = cli("upgrade", "--in-place", path)
    assert result.exit_code == 2
    assert result.stderr.count("\n") == 1 and "No space left on device" in result.stderr
    assert "internal error" not in result.stderr
    assert path.read_bytes() == original
    assert backup.read_text() == "the previous good backup\n"
    assert _leftovers(small_fs.path) == []


def test_a_read_only_file_system_is_one_line(cli, small_fs):
    path = small_fs.path / "tracker.jconf"
    shutil.copyfile(OLD_FILE, path)
    small_fs.read_only()
    for args in (("--in-place", path), (path, "-o", small_fs.path / "out.jconf")):
        result = cli("upgrade", *args)
        assert result.exit_code == 2
        assert result.stderr.count("\n") == 1 and "Read-only file system" in result.stderr
        assert "internal error" not in result.stderr


def test_a_file_changed_during_the_run_is_refused_and_left_alone(old_file):
    from gadgetctl.cli.upgrade_cmd import _write_in_place
    from gadgetctl.jccl.repository import default_repository
    from gadgetctl.jccl.upgrade import upgrade_file

    result = upgrade_file(old_file, default_repository([]))
    assert result.changed
    edited = result.original.replace(
        b"</configuration>", b"<!-- someone else's edit -->\n</configuration>"
    )
    old_file.write_bytes(edited)
    with pytest.raises(typer.Exit) as stopped:
        _write_in_place([result], backup=True)
    assert stopped.value.exit_code == 1
    assert old_file.read_bytes() == edited
    assert not old_file.with_name("tracker.jconf.bak").exists()
    assert _leftovers(old_file.parent) == []


def test_record_overwrite_never_follows_a_symlink(cli, tmp_path):
    config = Path(__file__).resolve().parents[1] / "examples" / "waveform.jconf"
    link = tmp_path / "rec.ndjson"
    link.symlink_to(tmp_path / "elsewhere")
    result = cli(
        "monitor", config, "--duration", "0.2", "--format", "table", "--record", link, "--overwrite"
    )
    assert result.exit_code == 2
    assert "symbolic link" in result.stderr and "internal error" not in result.stderr
    assert not (tmp_path / "elsewhere").exists() and link.is_symlink()


def test_record_to_a_full_device_is_one_line(cli):
    config = Path(__file__).resolve().parents[1] / "examples" / "waveform.jconf"
    result = cli(
        "monitor",
        config,
        "--duration",
        "0.2",
        "--format",
        "table",
        "--record",
        "/dev/full",
        "--overwrite",
    )
    assert result.exit_code == 2
    assert "No space left on device" in result.stderr and "internal error" not in result.stderr


def test_scaffold_on_a_full_disk_leaves_nothing_and_a_rerun_works(cli, small_fs):
    small_fs.fill()
    result = cli("scaffold", "driver", "AcmeWand", "--dir", small_fs.path)
    assert result.exit_code == 2 and "No space left on device" in result.stderr
    assert sorted(p.name for p in small_fs.path.iterdir()) == ["filler"]
    (small_fs.path / "filler").unlink()
    result = cli("scaffold", "driver", "AcmeWand", "--dir", small_fs.path)
    assert result.exit_code == 0, result.stderr
    assert (small_fs.path / "AcmeWand_drv" / "standalone.py").is_file()
    assert _leftovers(small_fs.path) == [] and _leftovers(small_fs.path / "AcmeWand_drv") == []


# -- temporaries of a killed run (issue 24 item 16) ------------------------------------------------

KILLED_WRITER = """
import os, signal, sys
from pathlib import Path
from gadgetctl.safewrite import replace_file

path = Path(sys.argv[1])
os.rename = lambda *a, **k: os.kill(os.getpid(), signal.SIGKILL)  # killed mid-write
replace_file(path, b"half-done\\n", expected=path.read_bytes(), backup=True)
"""


def _killed_write(path: Path) -> list[Path]:
    """Run a write of ``path`` killed by SIGKILL after its temporaries were complete; what it
    left, aged past the staleness delay."""
    import signal
    import sys
    import time

    child = subprocess.run(
        [sys.executable, "-c", KILLED_WRITER, str(path)], capture_output=True, timeout=60
    )
    assert child.returncode == -signal.SIGKILL, child.stderr
    left = [path.parent / name for name in _leftovers(path.parent)]
    old = time.time() - 3600
    for leftover in left:
        os.utime(leftover, (old, old))
    return left


@pytest.mark.parametrize("changed", [True, False])
def test_the_next_run_removes_what_a_killed_write_left(cli, old_file, changed):
    original = old_file.read_bytes()
    if not changed:  # already up to date: the next run writes nothing, and still cleans
        assert cli("upgrade", "--in-place", "--no-backup", old_file).exit_code == 0
        original = old_file.read_bytes()
    assert len(_killed_write(old_file)) == 2  # the new content and the backup
    assert old_file.read_bytes() == original
    result = cli("upgrade", "--in-place", old_file)
    assert result.exit_code == 0, result.stderr
    assert _leftovers(old_file.parent) == []
    assert result.stderr.splitlines() == [
        f"gadgetctl: note: {old_file}: removed 2 temporary files an interrupted earlier run "
        "left beside it"
    ]


def test_only_provably_abandoned_temporaries_are_removed(old_file, tmp_path):
    import sys
    import time

    from gadgetctl.safewrite import STALE_AFTER, remove_stale_temporaries

    def temporary(name: str, age: float = 3600.0) -> Path:
        path = tmp_path / name
        path.write_text("x")
        os.utime(path, (time.time() - age, time.time() - age))
        return path

    ours = temporary(".tracker.jconf.abcd1234.gadgetctl.tmp")
    fresh = temporary(".tracker.jconf.fresh123.gadgetctl.tmp", age=STALE_AFTER / 2)
    foreign = temporary(".tracker.jconf.other123.gadgetctl.tmp")
    os.chown(foreign, 65534, 65534)  # another user's
    unlike = temporary(".tracker.jconf.abcd1234.tmp")  # not our naming (an older gadgetctl's)
    link = tmp_path / ".tracker.jconf.link1234.gadgetctl.tmp"
    link.symlink_to(ours)
    held = temporary(".tracker.jconf.held1234.gadgetctl.tmp")
    holder = subprocess.Popen(  # a writer alive: it holds the lock
        [
            sys.executable,
            "-c",
            "import fcntl, os, sys; fd = os.open(sys.argv[1], os.O_RDONLY); "
            "fcntl.flock(fd, fcntl.LOCK_EX); print('locked', flush=True); sys.stdin.read()",
            str(held),
        ],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout.readline() == "locked\n"
        assert remove_stale_temporaries(old_file) == [ours]
        for kept in (fresh, foreign, unlike, held):
            assert kept.exists(), kept
        assert link.is_symlink()
    finally:
        holder.communicate("", timeout=30)  # the writer ends: its lock goes with it
    assert remove_stale_temporaries(old_file) == [held]
