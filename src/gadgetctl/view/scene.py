"""The scene model of `gadgetctl view`: what the page draws, as plain data.

Built from a running :class:`~gadgetctl.monitor.session.MonitorSession` (the same device
selection, proxies, aliases, replay and VRPN sources as ``monitor``) and the configuration's
:class:`~gadgetctl.view.layout.Layout`; :meth:`SceneModel.update` reads the live proxies once
per frame. Everything is in VR Juggler's world frame (metres, Y up) as the proxies deliver it
after their filters; the raw frame of a filtered pose is the device's sample before any
filter (device units read as metres), found by running the filter chains backwards, so a
wrong rotation or unit shows as a frame away from where it should be.

:meth:`SceneModel.snapshot` is the whole state as JSON-ready data: the page shows the same
JSON (``window.gadgetctlScene``) and tests read either side.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

from gadgetctl.input.filters import FilterChain
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.proxies import PositionProxy
from gadgetctl.view.layout import Layout

#: Trail length in seconds of frames, and the most points a trail keeps.
TRAIL_SECONDS = 2.0
MAX_TRAIL_POINTS = 240
#: Digital and analog units shown per device, at most.
MAX_UNITS = 32
#: Positional proxies and aliases drawn, at most (the rest are counted, not drawn).
MAX_POSES = 1024

#: Health colours (RGB 0-255) by state.
COLOURS: dict[str, tuple[int, int, int]] = {
    "running": (40, 170, 70),
    "active": (40, 170, 70),
    "pending": (150, 150, 150),
    "stupefied": (230, 140, 20),
    "faulted": (210, 40, 40),
    "undecodable": (210, 40, 40),
    "reconnecting": (230, 200, 30),
    "stopped": (120, 120, 120),
}
UNKNOWN_COLOUR = (150, 150, 150)


def colour_of(state: str) -> tuple[int, int, int]:
    return COLOURS.get(state, UNKNOWN_COLOUR)


def _matrix_list(matrix: np.ndarray | None) -> list[list[float]] | None:
    if matrix is None:
        return None
    return [[round(float(v), 6) for v in row] for row in matrix]


@dataclass(slots=True)
class PoseState:
    """One positional proxy or alias."""

    name: str
    element: str  # proxy, alias, or device (a device's unit no drawn proxy reads)
    proxy: str  # the proxy read (itself for a proxy; the device for a device's unit)
    device: str | None = None
    unit: int = 0
    state: str = "pending"
    reason: str | None = None
    matrix: np.ndarray | None = None
    raw: np.ndarray | None = None  # the sample before every filter (device units)
    tracker: np.ndarray | None = None  # the tracker's own frame in the world
    timestamp: float | None = None
    trail: deque = field(default_factory=lambda: deque(maxlen=MAX_TRAIL_POINTS))
    filtered: bool = False


@dataclass(slots=True)
class UnitsState:
    """The digital and analog units of one selected device."""

    name: str
    state: str
    reason: str | None
    digital: list[int] = field(default_factory=list)
    analog: list[float] = field(default_factory=list)


class SceneModel:
    """The scene of one session; see the module documentation."""

    def __init__(self, session, layout: Layout, *, trail_seconds: float = TRAIL_SECONDS) -> None:
        self.session = session
        self.layout = layout
        self.frame = 0
        self.time = 0.0
        self.left_out = 0
        self.poses: dict[str, PoseState] = {}
        self.units: dict[str, UnitsState] = {}
        self.elements: list[dict[str, object]] = []
        self.markers: list[dict[str, object]] = []
        #: The replay being shown (a :class:`~gadgetctl.view.timeline.ReplayTimeline`).
        self.timeline = None
        self._trail_points = max(2, min(MAX_TRAIL_POINTS, round(trail_seconds * session.rate)))
        self._chains: dict[tuple[int, int], tuple[np.ndarray, np.ndarray] | None] = {}
        self._names: list[str] | None = None
        self._unit_devices: list[str] = []
        self._plan_key: tuple[int, int] | None = None

    # -- what is drawn ------------------------------------------------------------------

    def _positional_names(self) -> list[str]:
        """Selected positional proxies and aliases, plus every proxy the layout needs."""
        manager = self.session.manager
        wanted: list[str] = []
        seen: set[str] = set()

        def add(name: str | None) -> None:
            if name and name not in seen:
                seen.add(name)
                wanted.append(name)

        needed = [u.head for u in self.layout.users]
        needed += [s.tracker_proxy for s in self.layout.surfaces if s.tracked]
        needed += [c.proxy for c in self.layout.cameras]
        for name in self.session.selected:
            target = manager.aliases.get(name)
            proxy = manager.proxies.get(target if target is not None else name)
            if isinstance(proxy, PositionProxy) or (
                proxy is None and self._pending_positional(name)
            ):
                add(name)
        for name in needed:
            add(name)
        # Positional devices no drawn proxy reads (a replay with no configuration, a
        # vrpn:Device@host watch) are drawn unit by unit, as their samples come.
        read = {manager.proxies[n].device_name for n in wanted if n in manager.proxies}
        read |= {
            manager.proxies[t].device_name
            for n in wanted
            if (t := manager.aliases.get(n)) is not None and t in manager.proxies
        }
        self._unit_devices = [
            name
            for name in self.session.selected
            if name not in read
            and (device := manager.device(name)) is not None
            and DeviceKind.POSITION in device.kinds()
        ]
        if len(wanted) > MAX_POSES:
            self.left_out = len(wanted) - MAX_POSES
            wanted = wanted[:MAX_POSES]
        return wanted

    def _pending_positional(self, name: str) -> bool:
        status = self.session.manager.status(name)
        return status is not None and "position" in (status.type or "")

    def _make_pose(self, name: str) -> PoseState:
        manager = self.session.manager
        target = manager.aliases.get(name)
        element = "alias" if target is not None else "proxy"
        pose = PoseState(name, element, target if target is not None else name)
        pose.trail = deque(maxlen=self._trail_points)
        return pose

    def _chain_of(self, proxy: PositionProxy) -> tuple[np.ndarray, np.ndarray] | None:
        """The folded filters of the device and then the proxy (None: unfiltered or a
        zero scale, no raw frame)."""
        device = proxy.device
        cache_key = (id(proxy), id(device))
        if cache_key in self._chains:
            return self._chains[cache_key]
        chains = []
        device_chain = getattr(device, "position_filters", None)
        if isinstance(device_chain, FilterChain) and device_chain:
            chains.append(device_chain)
        if proxy.filters:
            chains.append(proxy.filters)
        result = None
        if chains:
            left, right = np.eye(4), np.eye(4)
            for chain in chains:
                folded = chain.folded
                if folded is None:
                    left = None
                    break
                left, right = folded[0] @ left, right @ folded[1]
            if left is not None:
                result = (np.linalg.inv(left), np.linalg.inv(right))
        if len(self._chains) >= MAX_POSES:  # devices restarted many times: start again
            self._chains.clear()
        self._chains[cache_key] = result
        return result

    # -- per frame ----------------------------------------------------------------------

    def update(self, *, statuses: bool = True) -> None:
        """Read every positional proxy (once per frame); with ``statuses`` also the
        elements' states and the units panel."""
        session = self.session
        manager = session.manager
        self.frame = session.frame
        self.time = session.frame_timestamp
        key = (len(manager.devices), len(manager.proxies))
        if self._names is None or key != self._plan_key:
            self._names = self._positional_names()
            self._plan_key = key
            kept = {n: p for n, p in self.poses.items() if p.element == "device"}
            self.poses = {n: self.poses.get(n) or self._make_pose(n) for n in self._names}
            self.poses.update((n, p) for n, p in kept.items() if p.proxy in self._unit_devices)
        for pose in list(self.poses.values()):
            if pose.element == "device":
                continue
            self._update_pose(pose)
        self._update_device_units()
        if statuses:
            self._update_statuses()

    def _update_device_units(self) -> None:
        """The position units of the devices in ``_unit_devices``, each a pose
        ``DEVICE[unit]`` with the device's sample (after the device's own filters)."""
        manager = self.session.manager
        for name in self._unit_devices:
            device = manager.device(name)
            if device is None:
                continue
            latest = device.store.latest(DeviceKind.POSITION)
            shown, reason = device.shown_state()
            state = "active" if shown.value == "running" else shown.value
            values = [] if latest is None else list(latest.values)[:MAX_UNITS]
            for unit, matrix in enumerate(values):
                key = f"{name}[{unit}]"
                pose = self.poses.get(key)
                if pose is None:
                    if len(self.poses) >= MAX_POSES:
                        self.left_out += 1
                        break
                    pose = self.poses[key] = PoseState(key, "device", name, name, unit)
                    pose.trail = deque(maxlen=self._trail_points)
                pose.state, pose.reason = state, reason
                if latest.timestamp == pose.timestamp:
                    continue
                pose.timestamp = latest.timestamp
                pose.matrix = np.array(matrix, dtype=float)
                chain = getattr(device, "position_filters", None)
                folded = chain.folded if isinstance(chain, FilterChain) and chain else None
                if folded is not None:
                    left, right = folded
                    pose.raw = np.linalg.inv(left) @ pose.matrix @ np.linalg.inv(right)
                    tracker = left.copy()
                    scale = np.linalg.norm(tracker[:3, :3], axis=0)
                    tracker[:3, :3] /= np.where(scale > 0, scale, 1.0)
                    pose.tracker = tracker
                pose.trail.append(pose.matrix[:3, 3].copy())

    def _update_pose(self, pose: PoseState) -> None:
        manager = self.session.manager
        proxy = manager.proxies.get(pose.proxy)
        if not isinstance(proxy, PositionProxy):
            status = manager.status(pose.name)
            if pose.element == "alias" and status is None:
                pose.state, pose.reason = "stupefied", f"its proxy {pose.proxy!r} is not configured"
            elif status is not None:
                pose.state, pose.reason = status.state, status.reason
            else:
                pose.state, pose.reason = "removed", "no longer configured"
            pose.matrix = None
            return
        pose.device, pose.unit = proxy.device_name or None, proxy.unit
        if proxy.stupefied:
            pose.state, pose.reason = "stupefied", proxy.reason
            return  # keeps the last pose it had, drawn as stupefied
        device = proxy.device
        if device is not None:
            shown, reason = device.shown_state()
            pose.state, pose.reason = shown.value, reason
            if pose.state == "running":
                pose.state = "active"
        else:
            pose.state, pose.reason = "active", None
        if proxy.timestamp is None:
            return  # nothing delivered yet
        if proxy.timestamp == pose.timestamp and pose.matrix is not None:
            return
        pose.timestamp = proxy.timestamp
        matrix = np.array(proxy.matrix, dtype=float)
        pose.matrix = matrix
        chain = self._chain_of(proxy)
        pose.filtered = chain is not None
        if chain is not None:
            inv_left, inv_right = chain
            pose.raw = inv_left @ matrix @ inv_right
            tracker = np.linalg.inv(inv_left)
            scale = np.linalg.norm(tracker[:3, :3], axis=0)
            tracker[:3, :3] /= np.where(scale > 0, scale, 1.0)
            pose.tracker = tracker
        pose.trail.append(matrix[:3, 3].copy())

    def _update_statuses(self) -> None:
        session = self.session
        manager = session.manager
        elements: list[dict[str, object]] = []
        units: dict[str, UnitsState] = {}
        for name in session.selected:
            view = session.element_view(name)
            elements.append(
                {
                    "name": name,
                    "element": view.element,
                    "type": view.type,
                    "state": view.state,
                    "reason": view.reason,
                    "target": view.target,
                    "blocked_by": view.blocked_by,
                }
            )
            device = manager.device(name)
            if device is None or len(units) >= MAX_POSES:
                continue
            kinds = device.kinds()
            if DeviceKind.DIGITAL not in kinds and DeviceKind.ANALOG not in kinds:
                continue
            entry = UnitsState(name, view.state, view.reason)
            latest = (
                device.store.latest(DeviceKind.DIGITAL) if DeviceKind.DIGITAL in kinds else None
            )
            if latest is not None:
                entry.digital = [int(v) for v in list(latest.values)[:MAX_UNITS]]
            latest = device.store.latest(DeviceKind.ANALOG) if DeviceKind.ANALOG in kinds else None
            if latest is not None:
                normalize = getattr(device, "normalize", None)
                values = [float(v) for v in list(latest.values)[:MAX_UNITS]]
                entry.analog = [round(normalize(v) if normalize else v, 4) for v in values]
            units[name] = entry
        self.elements = elements
        self.units = units
        self.markers = [{"name": m.name, "time": m.timestamp} for m in session.markers[-MAX_UNITS:]]

    # -- reading ------------------------------------------------------------------------

    def user_views(self) -> list[dict[str, object]]:
        """Each user's head, eyes (interocular distance apart along the head's X axis) and
        line of sight (the head's -Z axis, VR Juggler's forward)."""
        result = []
        for user in self.layout.users:
            pose = self.poses.get(user.head) if user.head else None
            entry: dict[str, object] = {
                "name": user.name,
                "head": user.head,
                "interocular": user.interocular,
                "state": pose.state if pose else "pending",
            }
            if pose is not None and pose.matrix is not None:
                m = pose.matrix
                half = user.interocular / 2.0
                x_axis, forward = m[:3, 0], -m[:3, 2]
                centre = m[:3, 3]
                entry["position"] = [round(float(v), 6) for v in centre]
                entry["left_eye"] = [round(float(v), 6) for v in centre - half * x_axis]
                entry["right_eye"] = [round(float(v), 6) for v in centre + half * x_axis]
                entry["sight"] = [round(float(v), 6) for v in forward]
            result.append(entry)
        return result

    def surface_views(self) -> list[dict[str, object]]:
        """Every surface with its corners in the world (a tracked one moved by its
        tracker proxy's pose)."""
        result = []
        for surface in self.layout.surfaces:
            corners = np.array(surface.corners, dtype=float)
            state = "active"
            if surface.tracked:
                pose = self.poses.get(surface.tracker_proxy or "")
                if pose is None or pose.matrix is None:
                    state = pose.state if pose else "pending"
                else:
                    m = pose.matrix
                    corners = corners @ m[:3, :3].T + m[:3, 3]
                    state = pose.state
            result.append(
                {
                    "name": surface.name,
                    "window": surface.window,
                    "tracked": surface.tracked,
                    "tracker_proxy": surface.tracker_proxy,
                    "state": state,
                    "corners": [[round(float(v), 6) for v in c] for c in corners],
                }
            )
        return result

    def camera_views(self) -> list[dict[str, object]]:
        result = []
        for camera in self.layout.cameras:
            pose = self.poses.get(camera.proxy or "")
            result.append(
                {
                    "name": camera.name,
                    "window": camera.window,
                    "proxy": camera.proxy,
                    "vertical_fov": camera.vertical_fov,
                    "state": pose.state if pose else "pending",
                    "matrix": _matrix_list(pose.matrix if pose else None),
                }
            )
        return result

    def pose_views(self, names: Iterable[str] | None = None) -> list[dict[str, object]]:
        result = []
        for name in self.poses if names is None else names:
            pose = self.poses[name]
            result.append(
                {
                    "name": pose.name,
                    "element": pose.element,
                    "proxy": pose.proxy,
                    "device": pose.device,
                    "unit": pose.unit,
                    "state": pose.state,
                    "reason": pose.reason,
                    "colour": list(colour_of(pose.state)),
                    "matrix": _matrix_list(pose.matrix),
                    "raw": _matrix_list(pose.raw),
                    "tracker_frame": _matrix_list(pose.tracker),
                    "timestamp": pose.timestamp,
                    "trail_points": len(pose.trail),
                }
            )
        return result

    def snapshot(self) -> dict[str, object]:
        """The whole scene as JSON-ready data."""
        return {
            "frame": self.frame,
            "time": self.time,
            "surfaces": self.surface_views(),
            "cameras": self.camera_views(),
            "users": self.user_views(),
            "poses": self.pose_views(),
            "elements": list(self.elements),
            "units": [
                {
                    "name": u.name,
                    "state": u.state,
                    "reason": u.reason,
                    "digital": u.digital,
                    "analog": u.analog,
                }
                for u in self.units.values()
            ],
            "markers": list(self.markers),
            "replay": self.timeline.state() if self.timeline is not None else None,
            "left_out": self.left_out + self.layout.left_out,
        }
