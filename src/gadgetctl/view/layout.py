"""What the configuration places in the world: display surfaces, simulator cameras, users.

Read from the effective elements of a configuration, as VR Juggler reads them: every
``surface_viewport`` of a ``display_window`` with its four corners (world metres, or the
tracker's frame when ``tracked``), every ``simulator_viewport`` with the proxy its
simulator plug-in puts the camera on, every ``user`` with its head alias or proxy and
interocular distance. Nothing here reads samples.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from gadgetctl.jccl.access import ElementAccess, read_bool, read_float
from gadgetctl.jccl.configuration import ConfigElement

CORNERS = ("lower_left_corner", "lower_right_corner", "upper_right_corner", "upper_left_corner")
#: At most this many surfaces, cameras and users are drawn (a configuration may hold more;
#: the rest are counted in :attr:`Layout.left_out`).
MAX_ITEMS = 256


@dataclass(frozen=True, slots=True)
class Surface:
    """A surface viewport: ``corners`` ll, lr, ur, ul, each (x, y, z)."""

    name: str
    window: str
    corners: tuple[tuple[float, float, float], ...]
    user: str | None = None
    tracked: bool = False
    tracker_proxy: str | None = None
    active: bool = True


@dataclass(frozen=True, slots=True)
class Camera:
    """A simulator viewport's camera, on the pose of ``proxy``."""

    name: str
    window: str
    proxy: str | None
    vertical_fov: float = 80.0
    user: str | None = None


@dataclass(frozen=True, slots=True)
class User:
    name: str
    head: str | None
    interocular: float = 0.0


@dataclass(slots=True)
class Layout:
    surfaces: list[Surface] = field(default_factory=list)
    cameras: list[Camera] = field(default_factory=list)
    users: list[User] = field(default_factory=list)
    left_out: int = 0

    def to_dict(self) -> dict[str, object]:
        return {
            "surfaces": [
                {
                    "name": s.name,
                    "window": s.window,
                    "corners": [list(c) for c in s.corners],
                    "user": s.user,
                    "tracked": s.tracked,
                    "tracker_proxy": s.tracker_proxy,
                    "active": s.active,
                }
                for s in self.surfaces
            ],
            "cameras": [
                {
                    "name": c.name,
                    "window": c.window,
                    "proxy": c.proxy,
                    "vertical_fov": c.vertical_fov,
                }
                for c in self.cameras
            ],
            "users": [
                {"name": u.name, "head": u.head, "interocular": u.interocular} for u in self.users
            ],
            "left_out": self.left_out,
        }


def _text(element: ConfigElement, prop: str) -> str | None:
    values = element.values(prop)
    if not values or values[0].element is not None:
        return None
    text = (values[0].text or "").strip()
    return text or None


def _floats(element: ConfigElement, prop: str, count: int, default: float = 0.0) -> list[float]:
    values = [read_float(v.text or "") for v in element.values(prop)[:count]]
    return values + [default] * (count - len(values))


def _boolean(element: ConfigElement, prop: str, default: bool) -> bool:
    text = _text(element, prop)
    return default if text is None else read_bool(text)


def _embedded(element: ConfigElement, prop: str) -> list[ConfigElement]:
    return [v.element for v in element.values(prop) if v.element is not None]


def read_layout(elements: list[ConfigElement], repo=None) -> Layout:
    """The layout of ``elements`` (a configuration's effective elements)."""
    layout = Layout()

    def room() -> bool:
        if len(layout.surfaces) + len(layout.cameras) + len(layout.users) >= MAX_ITEMS:
            layout.left_out += 1
            return False
        return True

    for element in elements:
        if element.type == "user":
            if room():
                iod = _text(element, "interocular_distance")
                if iod is None and repo is not None:
                    iod = ElementAccess(element, repo).string("interocular_distance")
                layout.users.append(
                    User(element.full_name, _text(element, "head_position"), read_float(iod or "0"))
                )
        elif element.type == "display_window":
            window = element.full_name
            for viewport in _embedded(element, "surface_viewports"):
                if not room():
                    continue
                corners = tuple(tuple(_floats(viewport, c, 3)) for c in CORNERS)
                tracked = _boolean(viewport, "tracked", False)
                layout.surfaces.append(
                    Surface(
                        viewport.name,
                        window,
                        corners,  # type: ignore[arg-type]
                        _text(viewport, "user"),
                        tracked,
                        _text(viewport, "tracker_proxy") if tracked else None,
                        _boolean(viewport, "active", True),
                    )
                )
            for viewport in _embedded(element, "simulator_viewports"):
                if not room():
                    continue
                proxy = None
                for plugin in _embedded(viewport, "simulator_plugin"):
                    proxy = _text(plugin, "camera_pos") or proxy
                fov = _text(viewport, "vertical_fov")
                layout.cameras.append(
                    Camera(
                        viewport.name,
                        window,
                        proxy,
                        read_float(fov) if fov else 80.0,
                        _text(viewport, "user"),
                    )
                )
    return layout
