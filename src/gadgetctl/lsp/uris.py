"""Document URIs and the JCCL files they name."""

from __future__ import annotations

from pathlib import Path

from pygls.uris import to_fs_path

from gadgetctl.lsp.analysis import JCCL_SUFFIXES, real


def path_of(uri: str) -> Path | None:
    fs = to_fs_path(uri)
    return real(fs) if fs else None


def is_jccl(path: Path | None) -> bool:
    return path is not None and path.suffix.lower() in JCCL_SUFFIXES
