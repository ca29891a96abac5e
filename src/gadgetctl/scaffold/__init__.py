"""`gadgetctl scaffold`: generate a driver plug-in that works on the first run.

A generated driver has the layout of the bundled ones (docs/architecture.md, "Driver
plug-ins"): a standalone protocol half, a wrapper for the input manager, a .jdef, an
example configuration, an emulator of a placeholder protocol over the chosen transport
and tests that run the driver against it. Only the protocol is left to write.

The templates are files under ``templates/`` (see :mod:`gadgetctl.scaffold.render`). The
names below are imported lazily, so the command line stays fast.
"""

from __future__ import annotations

import importlib
from typing import Any

_EXPORTS = {
    "DEFAULT_TRANSPORT": "model",
    "DEFAULT_TYPES": "model",
    "TRANSPORT_NAMES": "model",
    "TYPE_NAMES": "model",
    "DriverNames": "model",
    "DriverSpec": "model",
    "ScaffoldError": "model",
    "GeneratedFile": "generate",
    "ScaffoldResult": "generate",
    "generate": "generate",
    "scaffold": "generate",
    "summary_lines": "generate",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return __all__
