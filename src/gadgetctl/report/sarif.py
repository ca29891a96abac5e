"""Diagnostics as a SARIF 2.1.0 log."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

from gadgetctl import __version__
from gadgetctl.diagnostics import Diagnostic, lookup

SARIF_SCHEMA = "https://json.schemastore.org/sarif-2.1.0.json"
_LEVEL = {"error": "error", "warning": "warning", "info": "note"}


def _uri(path: str | None) -> str:
    if not path:
        return ""
    p = Path(path)
    return p.as_uri() if p.is_absolute() else p.as_posix()


def _rule(code: str) -> dict:
    entry = lookup(code)
    return {
        "id": code,
        "name": "".join(w.capitalize() for w in entry.title.replace("-", " ").split()),
        "shortDescription": {"text": entry.title},
        "fullDescription": {"text": entry.description},
        "help": {"text": entry.fix or entry.description},
        "defaultConfiguration": {"level": _LEVEL[entry.severity.value]},
        "properties": {"category": entry.category.value},
    }


def _result(d: Diagnostic, rule_index: int) -> dict:
    region: dict[str, int] = {}
    if d.line is not None:
        region["startLine"] = d.line
        if d.column is not None:
            region["startColumn"] = d.column
    location: dict = {"artifactLocation": {"uri": _uri(d.path)}}
    if region:
        location["region"] = region
    text = d.message if not d.hint else f"{d.message} ({d.hint})"
    return {
        "ruleId": d.code,
        "ruleIndex": rule_index,
        "level": _LEVEL[d.severity.value],
        "message": {"text": text},
        "locations": [{"physicalLocation": location}],
    }


def sarif_log(diagnostics: Sequence[Diagnostic]) -> dict:
    codes = sorted({d.code for d in diagnostics})
    index = {code: i for i, code in enumerate(codes)}
    return {
        "$schema": SARIF_SCHEMA,
        "version": "2.1.0",
        "runs": [
            {
                "tool": {
                    "driver": {
                        "name": "gadgetctl",
                        "version": __version__,
                        "informationUri": "https://pypi.org/project/gadgetctl/",
                        "rules": [_rule(code) for code in codes],
                    }
                },
                "columnKind": "unicodeCodePoints",
                "results": [_result(d, index[d.code]) for d in diagnostics],
            }
        ],
    }


def render_sarif(diagnostics: Sequence[Diagnostic]) -> str:
    return json.dumps(sarif_log(diagnostics), indent=2)
