"""A process that builds definition repositories again and again (the language server,
validating in-process) reads a directory's definition files once while they stay the same,
and again as soon as one changes, comes or goes, or an editor's unsaved text stands for one."""

from __future__ import annotations

import os

from gadgetctl.jccl.repository import DefinitionRepository
from gadgetctl.jccl.searchpath import SearchPathEntry
from gadgetctl.jccl.xmlload import unsaved_texts

from jccl_samples import jdef, prop


def _definition(name: str, prop_name: str) -> str:
    return jdef(name, prop(prop_name, "integer"))


def _repository(directory) -> DefinitionRepository:
    return DefinitionRepository.from_search_path(
        [SearchPathEntry(str(directory), directory, "test")]
    )


def _properties(repo: DefinitionRepository, name: str) -> list[str]:
    version = repo.get(name)
    return [p.name for p in version.properties] if version is not None else []


def test_unchanged_files_are_read_once_and_a_changed_file_again(tmp_path):
    probe = tmp_path / "probe.jdef"
    probe.write_text(_definition("probe", "rate"))
    (tmp_path / "broken.jdef").write_text("<definition")
    first, second = _repository(tmp_path), _repository(tmp_path)
    assert first.get("probe") is second.get("probe")  # the same definitions, shared
    assert [d.code for d in second.diagnostics] == ["DEF020"]  # the broken file, each time
    assert second.entries[0].files == 2 and second.entries[0].contributed == 1

    probe.write_text(_definition("probe", "depth"))
    stat = probe.stat()
    os.utime(probe, ns=(stat.st_atime_ns, stat.st_mtime_ns + 1_000_000))  # even within a tick
    assert _properties(_repository(tmp_path), "probe") == ["depth"]

    (tmp_path / "gauge.jdef").write_text(_definition("gauge", "x"))
    assert _properties(_repository(tmp_path), "gauge") == ["x"]
    (tmp_path / "gauge.jdef").unlink()
    assert _repository(tmp_path).get("gauge") is None


def test_an_unsaved_text_stands_for_its_file_and_is_not_kept(tmp_path):
    probe = tmp_path / "probe.jdef"
    probe.write_text(_definition("probe", "rate"))
    assert _properties(_repository(tmp_path), "probe") == ["rate"]
    edited = _definition("probe", "depth")
    with unsaved_texts({probe: edited}):
        assert _properties(_repository(tmp_path), "probe") == ["depth"]
    assert _properties(_repository(tmp_path), "probe") == ["rate"]  # the file's, again
