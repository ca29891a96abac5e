"""The bundled definitions kept between processes (gadgetctl.jccl.defcache): a cache file
gives exactly what reading the files gives, and is never used when it is stale, corrupt,
writable by others or turned off."""

from __future__ import annotations

import marshal
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from gadgetctl.jccl import defcache, repository, xmlload
from gadgetctl.jccl.repository import _read_directory
from gadgetctl.resources import definitions_dir

from jccl_samples import jdef, prop

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture
def cache(tmp_path, monkeypatch) -> Path:
    """An empty cache folder, and no reads kept in this process."""
    folder = tmp_path / "cache"
    monkeypatch.setenv(defcache.CACHE_VAR, str(folder))
    monkeypatch.setattr(repository, "_READ_DIRECTORIES", {})
    return folder


def _read(directory: Path, monkeypatch) -> list:
    """The directory read afresh in this process, lasting (the cache may answer)."""
    monkeypatch.setattr(repository, "_READ_DIRECTORIES", {})
    return _read_directory(directory, lasting=True)


def _parsed(monkeypatch) -> list[str]:
    """The names of the files the reads from now on parse."""
    parsed: list[str] = []
    load_file = xmlload.load_file

    def counting(path, **kwargs):
        parsed.append(path.name)
        return load_file(path, **kwargs)

    monkeypatch.setattr(xmlload, "load_file", counting)
    return parsed


def _definitions(tmp_path: Path) -> Path:
    directory = tmp_path / "definitions"
    directory.mkdir()
    (directory / "probe.jdef").write_text(jdef("probe", prop("rate", "integer")))
    (directory / "broken.jdef").write_text("<definition")
    return directory


def _cache_file(folder: Path, directory: Path) -> Path:
    return defcache.cache_file(directory, folder)


def test_the_bundled_definitions_from_the_cache_are_those_read(cache, monkeypatch):
    fresh = _read(definitions_dir(), monkeypatch)
    assert _cache_file(cache, definitions_dir()).is_file()
    parsed = _parsed(monkeypatch)
    cached = _read(definitions_dir(), monkeypatch)
    assert parsed == []  # no file parsed: the cache answered
    assert len(cached) == len(fresh) > 80
    assert cached == fresh  # every definition, version, property and location
    assert [type(o[1].location) for o in cached] == [type(o[1].location) for o in fresh]


def test_a_repository_keeps_the_bundled_directory_only(cache, monkeypatch, tmp_path):
    directory = _definitions(tmp_path)
    repository.default_repository([directory])
    assert sorted(p.name for p in cache.iterdir()) == [_cache_file(cache, definitions_dir()).name]


def test_a_changed_added_or_removed_file_is_read_again(cache, monkeypatch, tmp_path):
    directory = _definitions(tmp_path)
    first = _read(directory, monkeypatch)
    assert [o[1].name if o[1] else None for o in first] == [None, "probe"]
    assert "skipped" in first[0][2]

    parsed = _parsed(monkeypatch)
    probe = directory / "probe.jdef"
    before = probe.stat()
    probe.write_text(jdef("probe", prop("deep", "integer")))  # the same size, the same file
    while True:  # and the same time, set back until the change time tells them apart
        os.utime(probe, ns=(before.st_atime_ns, before.st_mtime_ns))
        after = probe.stat()
        if after.st_ctime_ns != before.st_ctime_ns:
            break
    assert (after.st_size, after.st_mtime_ns, after.st_ino) == (
        before.st_size,
        before.st_mtime_ns,
        before.st_ino,
    )
    changed = _read(directory, monkeypatch)
    assert [p.name for p in changed[1][1].newest.properties] == ["deep"]
    assert parsed == ["broken.jdef", "probe.jdef"]
    parsed.clear()
    assert _read(directory, monkeypatch) == changed and parsed == []  # kept again

    (directory / "gauge.jdef").write_text(jdef("gauge", prop("x")))
    assert [o[0].name for o in _read(directory, monkeypatch)] == [
        "broken.jdef",
        "gauge.jdef",
        "probe.jdef",
    ]
    (directory / "gauge.jdef").unlink()
    assert [o[0].name for o in _read(directory, monkeypatch)] == ["broken.jdef", "probe.jdef"]


def test_a_change_of_the_reading_code_reads_again(cache, monkeypatch, tmp_path):
    directory = _definitions(tmp_path)
    code = tmp_path / "code"
    code.mkdir()
    reader = code / "gadgetctl_test_reader.py"
    reader.write_text("# a module of the reading code\n")
    monkeypatch.syspath_prepend(str(code))
    monkeypatch.setattr(defcache, "READING_CODE", (*defcache.READING_CODE, reader.stem))
    _read(directory, monkeypatch)
    parsed = _parsed(monkeypatch)
    assert _read(directory, monkeypatch) and parsed == []

    reader.write_text("# a module of the reading code, changed\n")
    _read(directory, monkeypatch)
    assert parsed == ["broken.jdef", "probe.jdef"]
    monkeypatch.delitem(sys.modules, reader.stem)


@pytest.mark.parametrize(
    "spoil",
    [
        lambda data, key: b"not marshal data",
        lambda data, key: data[: len(data) // 2],
        lambda data, key: b"",
        lambda data, key: marshal.dumps((key, (("probe.jdef", ("probe",), ""),))),
        lambda data, key: marshal.dumps((key, 42)),
        lambda data, key: marshal.dumps(key),
    ],
    ids=["garbage", "truncated", "empty", "wrong shape", "not outcomes", "no outcomes"],
)
def test_a_corrupt_cache_file_is_read_past_and_replaced(cache, monkeypatch, tmp_path, spoil):
    directory = _definitions(tmp_path)
    fresh = _read(directory, monkeypatch)
    path = _cache_file(cache, directory)
    stored_key, _ = marshal.loads(path.read_bytes())
    path.write_bytes(spoil(path.read_bytes(), stored_key))

    parsed = _parsed(monkeypatch)
    assert _read(directory, monkeypatch) == fresh
    assert parsed == ["broken.jdef", "probe.jdef"]
    parsed.clear()
    assert _read(directory, monkeypatch) == fresh and parsed == []  # replaced: used again


def test_a_cache_file_others_may_write_is_not_used(cache, monkeypatch, tmp_path):
    directory = _definitions(tmp_path)
    _read(directory, monkeypatch)
    path = _cache_file(cache, directory)
    path.chmod(0o666)
    parsed = _parsed(monkeypatch)
    _read(directory, monkeypatch)
    assert parsed == ["broken.jdef", "probe.jdef"]
    assert path.stat().st_mode & 0o777 == 0o600  # (and replaced by a file of ours)


def test_a_link_in_place_of_the_cache_file_is_not_followed(cache, monkeypatch, tmp_path):
    directory = _definitions(tmp_path)
    _read(directory, monkeypatch)
    path = _cache_file(cache, directory)
    elsewhere = tmp_path / "elsewhere"
    path.rename(elsewhere)
    path.symlink_to(elsewhere)
    parsed = _parsed(monkeypatch)
    _read(directory, monkeypatch)
    assert parsed == ["broken.jdef", "probe.jdef"]
    assert not path.is_symlink()  # the link itself was replaced, not what it points at
    assert elsewhere.is_file()


def test_an_unsaved_text_is_never_kept(cache, monkeypatch, tmp_path):
    directory = _definitions(tmp_path)
    probe = directory / "probe.jdef"
    with xmlload.unsaved_texts({probe: jdef("probe", prop("edited"))}):
        read = _read(directory, monkeypatch)
    assert [p.name for p in read[1][1].newest.properties] == ["edited"]
    assert not cache.exists()
    assert [p.name for p in _read(directory, monkeypatch)[1][1].newest.properties] == ["rate"]


def test_with_the_cache_off_or_unwritable_the_files_are_read(monkeypatch, tmp_path):
    directory = _definitions(tmp_path)
    monkeypatch.setenv(defcache.CACHE_VAR, "")
    assert defcache.cache_dir() is None
    parsed = _parsed(monkeypatch)
    first = _read(directory, monkeypatch)
    assert _read(directory, monkeypatch) == first
    assert parsed == ["broken.jdef", "probe.jdef"] * 2

    blocker = tmp_path / "a file"
    blocker.write_text("")
    monkeypatch.setenv(defcache.CACHE_VAR, str(blocker / "cache"))
    assert _read(directory, monkeypatch) == first
    assert blocker.read_text() == "" and sorted(p.name for p in tmp_path.iterdir()) == [
        "a file",
        "definitions",
    ]


def test_the_cache_folder(monkeypatch, tmp_path):
    environ = {"HOME": str(tmp_path)}
    if os.name != "nt":
        assert defcache.cache_dir(environ) == tmp_path / ".cache" / "gadgetctl"
        assert defcache.cache_dir({**environ, "XDG_CACHE_HOME": "/var/c"}) == Path(
            "/var/c/gadgetctl"
        )
        relative = {**environ, "XDG_CACHE_HOME": "c"}  # (ignored, as XDG says)
        assert defcache.cache_dir(relative) == tmp_path / ".cache" / "gadgetctl"
    assert defcache.cache_dir({defcache.CACHE_VAR: "/x/y"}) == Path("/x/y")
    assert defcache.cache_dir({defcache.CACHE_VAR: "", "HOME": str(tmp_path)}) is None


def test_validate_processes_say_the_same_with_and_without_the_cache(tmp_path, corpus):
    """Byte for byte: the first process writes the cache, the second reads it."""
    folder = tmp_path / "cache"
    configs = corpus / "modules" / "vrjuggler" / "data" / "configFiles"

    def validate(cache_dir: str) -> bytes:
        env = {**os.environ, defcache.CACHE_VAR: cache_dir}
        command = [sys.executable, "-m", "gadgetctl", "validate", str(configs), "-f", "json"]
        done = subprocess.run(command, capture_output=True, env=env, cwd=REPO, timeout=120)
        assert done.returncode in (0, 1), done.stderr
        return done.stdout

    without = validate("")
    assert not folder.exists()
    assert validate(str(folder)) == without
    written = _cache_file(folder, definitions_dir())
    assert written.is_file()
    before = written.stat().st_mtime_ns
    assert validate(str(folder)) == without
    assert written.stat().st_mtime_ns == before  # read, not written again
    shutil.rmtree(folder)
