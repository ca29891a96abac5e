"""Entry point of the `gadgetctl` command."""

from __future__ import annotations

import errno
import os
import sys


def run() -> None:
    """The console script (and ``python -m gadgetctl``): gadgetctl owns its process, so a
    finished command may end it at once (see :mod:`gadgetctl.cli.exiting`)."""
    from gadgetctl.cli import exiting

    exiting.own_process = True
    # numpy's OpenBLAS starts a worker thread per core at import, which spins while the
    # import goes on (0.06 s of CPU a command); gadgetctl's matrices are 4x4 and never need
    # them. A user's own setting stands.
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
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
    if args[:1] == ["validate"]:
        _validate_without_typer(args[1:])  # (returns when typer must read the command line)
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
        _tool_error(err)
    except KeyboardInterrupt:
        print("gadgetctl: interrupted", file=sys.stderr)
        sys.exit(130)
    except Exception as err:  # a bug of ours: one line unless debugging
        _internal_error(err)
    sys.exit(code if isinstance(code, int) and not isinstance(code, bool) else 0)


def _tool_error(err) -> None:
    from gadgetctl.safetext import printable

    print(f"gadgetctl: error: {printable(str(err))}", file=sys.stderr)
    sys.exit(err.exit_code)


def _internal_error(err: Exception) -> None:
    if os.environ.get("GADGETCTL_DEBUG"):
        raise err
    print(
        f"gadgetctl: internal error: {type(err).__name__}: {err} "
        "(set GADGETCTL_DEBUG=1 for a traceback)",
        file=sys.stderr,
    )
    sys.exit(2)


def _validate_without_typer(words: list[str]) -> None:
    """`gadgetctl validate` in gadgetctl's own process, its command line read without typer
    when it can be (see :mod:`gadgetctl.cli.validate_fast`); the command ends the process.
    Returns at once when typer must read the command line. What goes wrong while it runs
    ends as it does under typer (whose command runner turns EOFError into an abort,
    KeyboardInterrupt into exit status 130 and a closed pipe into exit status 1)."""
    from gadgetctl.cli import exiting

    if not exiting.own_process:  # in-process callers get typer's reading, as always
        return
    import gc

    # Validation pauses the cyclic collector and, in its own process, never resumes it
    # (see gadgetctl.perf): paused from here, it does not walk the modules being imported
    # either (about 20 collections, a few milliseconds, that free nothing of note).
    collecting = gc.isenabled()
    gc.disable()
    from gadgetctl.cli.validate_fast import parse

    request = parse(words, os.environ)
    if request is None:
        if collecting:
            gc.enable()
        return
    from gadgetctl.cli.validate_run import run_validate
    from gadgetctl.errors import GadgetctlError

    try:
        try:
            run_validate(**request)
        except EOFError:
            print(file=sys.stderr)
            print("gadgetctl: error: aborted", file=sys.stderr)
            sys.exit(2)
        except KeyboardInterrupt:
            sys.exit(130)
        except OSError as err:
            if err.errno != errno.EPIPE:
                raise
            _pacify_broken_pipe()
            sys.exit(1)
    except GadgetctlError as err:
        _tool_error(err)
    except Exception as err:
        _internal_error(err)
    sys.exit(0)


def _pacify_broken_pipe() -> None:
    """What typer's command runner does when the reader went away: wrap stdout and stderr
    so that their last flush says nothing."""
    import importlib

    import typer

    utils = importlib.import_module(typer.BadParameter.__module__.rpartition(".")[0] + ".utils")
    sys.stdout = utils.PacifyFlushWrapper(sys.stdout)
    sys.stderr = utils.PacifyFlushWrapper(sys.stderr)


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
