"""Diagnostics as a JSON list of objects with the model's field names."""

from __future__ import annotations

import json
from collections.abc import Sequence

from gadgetctl.diagnostics import Diagnostic


def render_json(diagnostics: Sequence[Diagnostic]) -> str:
    return json.dumps([d.to_dict() for d in diagnostics], indent=2)
