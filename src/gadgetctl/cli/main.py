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
    if args in (["--help"], ["-h"]):  # the root help, kept as typer renders it (roothelp)
        from gadgetctl.cli import roothelp

        if roothelp.answer(args):
            return
    if args[:1] == ["__complete"]:  # the shell's Tab: answered without the CLI framework either
        from gadgetctl.cli.candidates import main as complete

        sys.exit(complete(args[1:]))
    import typer

    from gadgetctl.cli.app import build_app
    from gadgetctl.cli.commands import COMMANDS
    from gadgetctl.errors import GadgetctlError

    # Click's exceptions, wherever this typer keeps Click (vendored since 0.28)
    clicks = sys.modules[typer.BadParameter.__module__]
    ClickException, UsageError = clicks.ClickException, clicks.UsageError
    NoArgsIsHelpError = getattr(clicks, "NoArgsIsHelpError", ())
    Abort = typer.Abort

    # A command line that starts with a command's name is parsed by that command alone;
    # anything else (a root option, a typo that gets suggestions) sees every command.
    app = build_app(args[0] if args and args[0] in COMMANDS else None)
    try:
        code = app(args=argv, prog_name="gadgetctl", standalone_mode=False)
    except NoArgsIsHelpError as err:  # a group without its command: its help is the answer
        err.show()
        sys.exit(err.exit_code)
    except UsageError as err:  # an option or argument error: one line, naming the option
        print(f"gadgetctl: error: {usage_error_text(err, args, app)}", file=sys.stderr)
        sys.exit(2)
    except ClickException as err:
        from gadgetctl.safetext import printable

        print(f"gadgetctl: error: {printable(err.format_message())}", file=sys.stderr)
        sys.exit(2)
    except Abort:
        print("gadgetctl: error: aborted", file=sys.stderr)
        sys.exit(2)
    except BrokenPipeError:  # the reader went away (| head): what it wanted was written
        _quiet_broken_pipe()
        sys.exit(0)
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
    sys.exit(code if isinstance(code, int) and not isinstance(code, bool) else 0)


def usage_error_text(err, args: list[str], app) -> str:
    """A Click usage error in one line: the command, what is wrong with which option or
    argument, and where the usage is (``--help``), instead of Click's usage block."""
    from gadgetctl.safetext import printable

    message = " ".join(err.format_message().split()).rstrip(".")
    if message[:1].isupper() and message[1:2].islower():
        message = message[0].lower() + message[1:]
    context = getattr(err, "ctx", None)
    path = context.command_path if context is not None else _command_path(args, app)
    command = path.removeprefix("gadgetctl").strip()
    where = f"{command}: " if command else ""
    return printable(f"{where}{message} (see '{path} --help')")


def _command_path(args: list[str], app) -> str:
    """The command ``args`` name (``gadgetctl config show``), for errors Click reports
    without their command (a missing option value)."""
    import typer.main

    command = typer.main.get_command(app)
    words = ["gadgetctl"]
    for word in args:
        sub = getattr(command, "commands", {}).get(word)
        if sub is None:
            break
        words.append(word)
        command = sub
    return " ".join(words)


def _quiet_broken_pipe() -> None:
    """Point stdout at /dev/null so that the interpreter's last flush finds no closed pipe."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError):
        pass
