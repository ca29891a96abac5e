"""The `gadgetctl` command's entry point (gadgetctl.cli.main.run) sets up its process."""

from __future__ import annotations

import os

from gadgetctl.cli import exiting
from gadgetctl.cli import main as entry


def test_the_command_asks_numpy_for_one_blas_thread_unless_the_user_chose(monkeypatch):
    seen: list[str | None] = []
    monkeypatch.setattr(entry, "main", lambda: seen.append(os.environ.get("OPENBLAS_NUM_THREADS")))
    monkeypatch.setattr(exiting, "own_process", exiting.own_process)  # run() sets it
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "")  # (so that teardown restores the original)
    monkeypatch.delenv("OPENBLAS_NUM_THREADS")
    entry.run()
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "4")
    entry.run()
    assert seen == ["1", "4"]
