"""`gadgetctl upgrade`."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import typer

from gadgetctl.cli.options import BUNDLED_OPTION, DEFINITIONS_OPTION, DataFormat, emit
from gadgetctl.wording import counted


def register(app: typer.Typer) -> None:
    app.command(name="upgrade")(upgrade)


def upgrade(
    paths: list[Path] = typer.Argument(
        ...,
        metavar="PATHS...",
        help="Files or directories (searched for *.jconf and *.jdef).",
        show_default=False,
    ),
    check: bool = typer.Option(
        False,
        "--check",
        help="Change nothing; list what would change and exit 1 if anything would (for CI).",
    ),
    diff: bool = typer.Option(
        False, "--diff", help="Print a unified diff of the changes instead of the files."
    ),
    in_place: bool = typer.Option(
        False, "--in-place", "-i", help="Rewrite the files (atomically)."
    ),
    backup: bool = typer.Option(
        True, "--backup/--no-backup", help="With --in-place, keep the old file as FILE.bak."
    ),
    output: Path = typer.Option(
        None,
        "--output",
        "-o",
        metavar="FILE",
        help="Write the upgraded file here (one input file only).",
        show_default=False,
    ),
    drop_removed: bool = typer.Option(
        False,
        "--drop-removed",
        help="Also remove properties the element's "
        "newest definition no longer has (validate's CFG021, e.g. device_host).",
    ),
    fmt: DataFormat = typer.Option(
        DataFormat.text, "--format", "-f", help="Output format of the --check listing."
    ),
    definitions: list[Path] = DEFINITIONS_OPTION,
    bundled: bool = BUNDLED_OPTION,
) -> None:
    """Bring elements up to date with their definitions (the definitions' upgrade transforms,
    one version at a time) and files up to the current file formats.

    Only changed elements are rewritten; comments, layout and other elements stay as they
    are. A file where any element cannot be upgraded is left unchanged. Without --check,
    --diff, --in-place or -o, the upgraded file is printed (one input file only).
    """
    from gadgetctl.errors import GadgetctlError
    from gadgetctl.files import expand_paths
    from gadgetctl.jccl.repository import default_repository
    from gadgetctl.jccl.upgrade import upgrade_file, with_given_definitions

    files = expand_paths(paths)
    writes = sum(bool(x) for x in (in_place, output is not None))
    if writes > 1:
        raise GadgetctlError("--in-place and --output exclude each other")
    if output is not None and len(files) != 1:
        raise GadgetctlError("--output takes exactly one input file")
    if output is not None and output.is_dir():
        raise GadgetctlError(
            f"--output {output}: is a directory; give the name of the file to write "
            f"(e.g. -o {output / files[0].name})"
        )
    if output is not None and not output.parent.is_dir():
        raise GadgetctlError(f"--output {output}: no such directory {output.parent}")
    if not (check or diff or in_place or output is not None) and len(files) != 1:
        raise GadgetctlError("several files: use --check, --diff or --in-place")
    for directory in definitions:
        if not directory.is_dir():
            raise GadgetctlError(f"--definitions {directory}: no such directory")
    repo = with_given_definitions(default_repository(definitions, bundled=bundled), files)
    results = []
    for path in files:
        try:
            results.append(upgrade_file(path, repo, drop_removed=drop_removed))
        except OSError as err:
            raise GadgetctlError(f"{path}: {err.strerror or err}") from None
    _report_problems(results)
    failed = any(r.failed for r in results)
    if check:
        _listing(results, fmt)
    if diff:
        _diff(results)
    if in_place:
        _write_in_place(results, backup)
    elif output is not None:
        from gadgetctl.safewrite import replace_file

        result = results[0]
        done = replace_file(
            output, result.upgraded if result.upgraded is not None else result.original
        )
        _say_removed(str(output), done.removed)
    elif not (check or diff):
        result = results[0]
        sys.stdout.buffer.write(result.upgraded if result.upgraded is not None else result.original)
        sys.stdout.flush()
    changed = any(r.changed for r in results)
    raise typer.Exit(1 if failed or (check and changed) else 0)


def _report_problems(results) -> None:
    from gadgetctl.report import render

    problems = [p for r in results for p in r.problems]
    if problems:
        text = render("text", problems, files_checked=len(results))
        sys.stderr.write("\n".join(text.splitlines()[:-1]) + "\n")


def _listing(results, fmt: DataFormat) -> None:
    if fmt is DataFormat.json:
        emit(
            json.dumps(
                [
                    {
                        "path": r.display,
                        "changed": r.changed,
                        "failed": r.failed,
                        "format": r.format_notes,
                        "elements": [
                            {
                                "type": e.type,
                                "name": e.name,
                                "line": e.line,
                                "from": e.from_version,
                                "to": e.to_version,
                                "created": e.created,
                                "dropped": list(e.dropped),
                            }
                            for e in r.elements
                        ],
                    }
                    for r in results
                    if r.changed or r.failed
                ],
                indent=2,
            )
        )
        return
    lines = []
    for r in results:
        if not r.changed:
            continue
        lines += [f"{r.display}: {note}" for note in r.format_notes]
        lines += [
            f"{r.display}:{e.line}: {e.describe()}" if e.line else f"{r.display}: {e.describe()}"
            for e in r.elements
        ]
    count = sum(r.changed for r in results)
    elements = sum(len(r.elements) for r in results if r.changed)
    failed = sum(r.failed for r in results)
    if failed:
        lines.append(
            f"{failed} of {counted(len(results), 'file')} could not be upgraded (see above)"
        )
    lines.append(
        f"{count} of {counted(len(results), 'file')} would change ({counted(elements, 'element')} upgraded)"
        if count
        else f"{counted(len(results), 'file')} checked: all up to date"
        if not failed
        else f"{counted(len(results) - failed, 'other file')} up to date"
    )
    emit("\n".join(lines))


def _diff(results) -> None:
    import difflib

    for r in results:
        if not r.changed:
            continue
        old = r.original.decode("utf-8", "replace").splitlines(keepends=True)
        new = r.upgraded.decode("utf-8", "replace").splitlines(keepends=True)
        sys.stdout.writelines(difflib.unified_diff(old, new, r.display, r.display + " (upgraded)"))
    sys.stdout.flush()


def _say_removed(display: str, removed) -> None:
    """One line for the temporary files a killed earlier run left beside a file."""
    if removed:
        sys.stderr.write(
            f"gadgetctl: note: {display}: removed {counted(len(removed), 'temporary file')} "
            "an interrupted earlier run left beside it\n"
        )


def _write_in_place(results, backup: bool) -> None:
    """Rewrite each changed file (its target, when it is a symbolic link), refusing one that
    changed since it was read; the others are still written."""
    from gadgetctl.safewrite import FileChangedError, remove_stale_temporaries, replace_file

    refused = None
    for r in results:
        if not r.changed:
            _say_removed(r.display, remove_stale_temporaries(r.path))
            continue
        try:
            done = replace_file(r.path, r.upgraded, expected=r.original, backup=backup)
        except FileChangedError as err:
            sys.stderr.write(f"gadgetctl: {err}\n")
            refused = err
            continue
        _say_removed(r.display, done.removed)
        what = (
            f"{done.target} (through the symbolic link {r.display})" if done.via_link else r.display
        )
        emit(
            f"upgraded {what} ({counted(len(r.elements), 'element')}"
            + (f"; {'; '.join(r.format_notes)})" if r.format_notes else ")")
        )
    if refused is not None:
        raise typer.Exit(refused.exit_code)
