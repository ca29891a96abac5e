"""`gadgetctl lsp` as a command: without its extra it says what to install."""

from __future__ import annotations

import subprocess
import sys


def test_without_pygls_the_command_says_which_extra_to_install():
    blocked = (
        "import sys; sys.modules['pygls'] = None; sys.argv = ['gadgetctl', 'lsp'];"
        "from gadgetctl.cli.main import run; run()"
    )
    done = subprocess.run(
        [sys.executable, "-c", blocked],
        capture_output=True,
        text=True,
        timeout=60,
        stdin=subprocess.DEVNULL,
    )
    assert done.returncode == 2
    assert done.stdout == ""
    assert done.stderr.count("\n") == 1 and "pip install 'gadgetctl[lsp]'" in done.stderr
