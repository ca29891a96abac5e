"""`gadgetctl validate`: run every check on a set of files and collect diagnostics."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from gadgetctl.diagnostics import Diagnostic, sort_key
from gadgetctl.files import expand_paths
from gadgetctl.jccl.xmlload import DEFAULT_MAX_SIZE, XmlDocument, load_file


@dataclass
class ValidateOptions:
    max_size: int = DEFAULT_MAX_SIZE
    schema: bool = True


@dataclass
class ValidationResult:
    files: list[str] = field(default_factory=list)
    diagnostics: list[Diagnostic] = field(default_factory=list)
    documents: list[XmlDocument] = field(default_factory=list)


def check_document(doc: XmlDocument, options: ValidateOptions) -> None:
    """XML-level and schema-level checks of one loaded document."""
    from gadgetctl.jccl.formats import check_format
    from gadgetctl.jccl.schema import check_schema

    if doc.root is None:
        return
    check_format(doc)
    if options.schema:
        check_schema(doc)


def load_and_check(path: Path, options: ValidateOptions) -> XmlDocument:
    try:
        doc = load_file(path, max_size=options.max_size)
    except OSError as err:
        from gadgetctl.errors import GadgetctlError

        raise GadgetctlError(f"{path}: {err.strerror or err}") from None
    check_document(doc, options)
    return doc


def validate_paths(paths: Sequence[Path], options: ValidateOptions | None = None) -> ValidationResult:
    options = options or ValidateOptions()
    result = ValidationResult()
    for path in expand_paths(paths):
        doc = load_and_check(path, options)
        result.files.append(doc.path)
        result.documents.append(doc)
        result.diagnostics.extend(doc.diagnostics)
    result.diagnostics.sort(key=sort_key)
    return result


def summarize(diagnostics: Iterable[Diagnostic]) -> dict[str, int]:
    counts = {"error": 0, "warning": 0, "info": 0}
    for d in diagnostics:
        counts[d.severity.value] += 1
    return counts
