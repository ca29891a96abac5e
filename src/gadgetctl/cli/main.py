"""Entry point of the `gadgetctl` command."""

from __future__ import annotations

import os
import sys


def run() -> None:
    """The console script (and ``python -m gadgetctl``): gadgetctl owns its process, so a
    finished command may end it at once (see :mod:`gadgetctl.cli.exiting`)."""
    from gadgetctl.cli import exiting

    exiting.own_process = True
    main()


def main(argv: list[str] | None = None) -> None:
    args = sys.argv[1:] if argv is None else argv
    if args in (["--version"], ["-V"]):  # answered without loading the CLI framework
        from gadgetctl import __version__

        print(f"gadgetctl {__version__}")
        return
    if args[:1] == ["__complete"]:  # the shell's Tab: answered without the CLI framework either
        from gadgetctl.cli.candidates import main as complete

        sys.exit(complete(args[1:]))
    from gadgetctl.cli.app import build_app
    from gadgetctl.errors import GadgetctlError

    app = build_app()
    try:
        app(args=argv, prog_name="gadgetctl", standalone_mode=True)
    except GadgetctlError as err:
        from gadgetctl.safetext import printable

        print(f"gadgetctl: error: {printable(str(err))}", file=sys.stderr)
        sys.exit(err.exit_code)
    except KeyboardInterrupt:
        print("gadgetctl: interrupted", file=sys.stderr)
        sys.exit(130)
    except Exception as err:  # a bug of ours: one line unless debugging
        if os.environ.get("GADGETCTL_DEBUG"):
            raise
        print(
            f"gadgetctl: internal error: {type(err).__name__}: {err} "
            "(set GADGETCTL_DEBUG=1 for a traceback)",
            file=sys.stderr,
        )
        sys.exit(2)
