"""`gadgetctl view`: a live 3D view of tracked poses against the configured screens.

The core (no typer, no rich): :mod:`layout` reads the configuration's display surfaces,
simulator cameras and users; :mod:`scene` keeps the scene model, updated from a
:class:`~gadgetctl.monitor.session.MonitorSession` once per frame and inspectable as JSON;
:mod:`render` draws that model with viser (the optional extra ``gadgetctl[view]``), one
batch of messages per frame; :mod:`server` runs the web page.
"""

from __future__ import annotations

EXTRA = "view"


def viser_missing() -> str | None:
    """A one-line reason when viser cannot be imported, None when it can."""
    try:
        import viser  # noqa: F401
    except ImportError:
        return (
            "gadgetctl view needs the 'view' extra (viser): "
            "pip install 'gadgetctl[view]' (or: pip install 'viser>=1')"
        )
    return None
