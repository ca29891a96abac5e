"""Checks before running: `monitor` and `replay --config` check their configurations as
`validate` would and print the errors and warnings first (the first few, then a summary
line), so that a mistyped property is seen before the device silently uses its default."""

from __future__ import annotations

import sys
from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING

from gadgetctl.errors import GadgetctlError
from gadgetctl.wording import counted

if TYPE_CHECKING:
    from gadgetctl.jccl.xmlload import XmlDocument

#: Findings printed in full; the rest are counted in one summary line.
MOST_SHOWN = 10


def check_before_running(
    configs: list[Path],
    *,
    definitions: list[Path] | None = None,
    bundled: bool = True,
    strict: bool = False,
    stream=None,
) -> dict[Path, XmlDocument]:
    """Print the configuration findings (errors and warnings) of ``configs`` checked together;
    with ``strict``, errors stop the run (exit status 1). Returns the documents it parsed, by
    resolved path, for the run to load without parsing them again."""
    from gadgetctl.diagnostics import Severity
    from gadgetctl.files import require_file
    from gadgetctl.jccl.xmlload import FileKind
    from gadgetctl.report import render
    from gadgetctl.validate import ValidateOptions, validate_paths

    if not configs:
        return {}
    for path in configs:
        require_file(path)  # the usual one-line message for a missing or unreadable file
    stream = stream or sys.stderr
    options = ValidateOptions(
        definition_dirs=list(definitions or ()), bundled=bundled, together=True
    )
    result = validate_paths(configs, options)
    parsed = {
        Path(doc.path).resolve(): doc
        for doc in result.documents
        if doc.root is not None and doc.kind is FileKind.CONFIGURATION
    }
    forget_check_reports(parsed.values())
    found = [d for d in result.diagnostics if d.severity in (Severity.ERROR, Severity.WARNING)]
    if not found:
        return parsed
    shown = found[:MOST_SHOWN]
    text = render("text", shown, files_checked=len(result.files), hints=True).rstrip("\n")
    if len(found) > len(shown):
        body = [line for line in text.splitlines() if not line.startswith(tuple("0123456789"))]
        errors = sum(d.severity is Severity.ERROR for d in found)
        text = "\n".join(body) + (
            f"\n… and {len(found) - len(shown)} more: {counted(errors, 'error')}, "
            f"{counted(len(found) - errors, 'warning')} in all (gadgetctl validate --together "
            + " ".join(str(p) for p in configs)
            + " shows them)"
        )
    stream.write(text + "\n")
    stream.flush()
    if strict and any(d.severity is Severity.ERROR for d in found):
        raise StrictStop("configuration errors found (--strict); not starting")
    return parsed


def forget_check_reports(documents: Iterable[XmlDocument]) -> None:
    """Drop the checks' per-element reports (``ConfigElement.report``: findings, pointers,
    the view judged by) from the elements of ``documents`` read while they were parsed,
    which the run is built from: it never reads them, and 10,000 devices with their proxies
    kept 20,000 of them (about 4 MB) alive to the end. The findings themselves are in the
    diagnostics already."""
    for doc in documents:
        for block in doc.streamed or ():
            if not block.embedded:  # (the usual block: no element of it embeds one)
                for element in block.elements:
                    element.report = None
                continue
            for element in block.elements:
                element.report = None
                for embedded in element.embedded():
                    embedded.report = None


class StrictStop(GadgetctlError):
    """Configuration errors with --strict: exit status 1, not a usage error."""

    exit_code = 1
