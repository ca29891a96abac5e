"""``optitrack`` elements for the driver's tests."""

from __future__ import annotations


def optitrack_element(
    name: str, bodies: list[int], markers: list[int], properties: str = ""
) -> str:
    """An ``optitrack`` element named ``name`` with ``properties`` (element text, may be
    empty: Motive's defaults), its rigid bodies (``body_index`` values) and its markers
    (``marker_index`` values), in that order."""
    parts = [f'<optitrack name="{name}" version="2">{properties}']
    for i, b in enumerate(bodies):
        parts.append(
            f'<rigid_body><optitrack_rigid_body name="{name} B{i}" version="1">'
            f"<body_index>{b}</body_index></optitrack_rigid_body></rigid_body>"
        )
    for i, m in enumerate(markers):
        parts.append(
            f'<marker><optitrack_marker name="{name} M{i}" version="1">'
            f"<marker_index>{m}</marker_index></optitrack_marker></marker>"
        )
    return "".join(parts) + "</optitrack>\n"
