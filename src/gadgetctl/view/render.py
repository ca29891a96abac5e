"""Draws a :class:`~gadgetctl.view.scene.SceneModel` with viser, one batch per frame.

Every update of a frame is sent inside one ``server.atomic()`` block, so the clients apply a
frame's poses together and the server sends one batch per frame, not one per device. Trails,
the side panels and the scene's JSON state change less often (``SLOW_EVERY`` frames).

The page keeps the model's JSON in an HTML panel (``<pre id="gadgetctl-scene">``) and, when
the browser runs the panel's handler, in ``window.gadgetctlScene``: tests read the scene
from there rather than from pixels.
"""

from __future__ import annotations

import html
import json
from typing import Any

import numpy as np

from gadgetctl.monitor.poses import quaternions_wxyz
from gadgetctl.view.scene import SceneModel, colour_of

#: Trails and panels are refreshed every this many frames; the JSON state every
#: STATE_EVERY frames (it is the largest message: every pose's matrices).
SLOW_EVERY = 6
STATE_EVERY = 30
#: Up to this many poses, labels follow their axes every frame; beyond, with the trails.
LABELS_EVERY_FRAME = 32
LABEL_OFFSET = np.array((0.0, 0.06, 0.0))
#: Points of a trail sent to the page, at most (the newest kept, the rest thinned evenly).
TRAIL_POINTS_SENT = 30
AXES_LENGTH = 0.15
FADE_FROM = np.array((235, 235, 235), dtype=float)  # trails fade to the background
SURFACE_COLOUR = (90, 140, 220)
EYE_COLOUR = (30, 60, 200)
SCENE_ELEMENT_ID = "gadgetctl-scene"
#: Where the page's camera starts: behind and above a CAVE-sized space, looking at its middle
#: (VR Juggler's -Z is forward, so the front wall is seen from +Z). fov: vertical, radians.
INITIAL_CAMERA = {"position": (2.5, 3.0, 6.5), "look_at": (0.0, 1.0, 0.0), "fov": 0.9}

# The page's own copy of the scene state: the HTML panel's text, parsed into
# window.gadgetctlScene by the handler of an image that cannot load (it runs each time the
# panel is replaced, i.e. each time the state is sent). The handler also keeps, in
# window.gadgetctlSceneMost, when the page first held the most poses it has held (``at``,
# milliseconds from navigation) and when the browser drew its next frame after that
# (``painted``): a busy page answers scripts late, so the time is taken in the page.
_STATE_HOOK = (
    '<img alt="" style="display:none" src="data:," '
    'onerror="try{var s=JSON.parse(document.getElementById('
    f"'{SCENE_ELEMENT_ID}').textContent);"
    "window.gadgetctlScene=s;window.gadgetctlSceneUpdates=(window.gadgetctlSceneUpdates||0)+1;"
    "var n=(s.poses||[]).filter(function(p){return p.matrix}).length,m=window.gadgetctlSceneMost;"
    "if(!m||n>m.poses){m=window.gadgetctlSceneMost={poses:n,at:performance.now()};"
    "requestAnimationFrame(function(){requestAnimationFrame(function(){m.painted=performance.now()})})}"
    '}catch(e){}">'
)


def _node(name: str) -> str:
    """A scene-tree name for an element name (viser uses / as the tree separator)."""
    return name.replace("/", "\u2215")


def _quad_faces() -> np.ndarray:
    return np.array([[0, 1, 2], [0, 2, 3]], dtype=np.uint32)


class SceneRenderer:
    """Keeps viser's scene in step with one :class:`SceneModel`."""

    def __init__(self, server: Any, model: SceneModel, *, title: str = "gadgetctl view") -> None:
        self.server = server
        self.model = model
        self.frames_sent = 0
        self._axes: Any = None
        self._origins: Any = None
        self._names: tuple[str, ...] = ()
        self._stamps: tuple[float | None, ...] = ()
        self._colours = np.zeros((0, 3), dtype=np.uint8)
        self._raw_axes: Any = None
        self._raw_names: tuple[str, ...] = ()
        self._raw_labels: dict[str, Any] = {}
        self._tracker: dict[str, Any] = {}
        self._tracker_keys: dict[str, tuple[float, ...]] = {}
        self._trails: Any = None
        self._trail_key: tuple = ()
        self._labels: dict[str, Any] = {}
        self._surfaces: dict[str, Any] = {}
        self._cameras: dict[str, Any] = {}
        self._users: dict[str, tuple[Any, Any, Any]] = {}
        self._labels_text: dict[str, str] = {}
        self._aliases: dict[str, list[str]] = {}
        self._build_static(title)

    # -- set up -------------------------------------------------------------------------

    def _build_static(self, title: str) -> None:
        scene = self.server.scene
        scene.set_up_direction("+y")
        camera = self.server.initial_camera
        camera.position = INITIAL_CAMERA["position"]
        camera.look_at = INITIAL_CAMERA["look_at"]
        camera.up = (0.0, 1.0, 0.0)
        camera.fov = INITIAL_CAMERA["fov"]
        scene.add_grid("/floor", width=8.0, height=8.0, plane="xz", cell_size=0.5, section_size=1.0)
        scene.add_frame("/world_origin", axes_length=0.3, axes_radius=0.008)
        scene.add_label("/world_origin/label", "world origin", position=(0.0, -0.05, 0.0))
        for surface in self.model.surface_views():
            node = f"/surfaces/{_node(surface['name'])}"
            corners = np.array(surface["corners"], dtype=np.float32)
            mesh = scene.add_mesh_simple(
                node,
                corners,
                _quad_faces(),
                color=SURFACE_COLOUR,
                opacity=0.35,
                side="double",
            )
            outline = np.array([[corners[i], corners[(i + 1) % 4]] for i in range(4)])
            border = scene.add_line_segments(
                node + "_outline", outline, colors=SURFACE_COLOUR, thickness=0.01
            )
            label = scene.add_label(
                node + "_label",
                f"{surface['window']}: {surface['name']}",
                position=tuple(corners.mean(axis=0)),
            )
            self._surfaces[surface["name"]] = (mesh, border, label)
        gui = self.server.gui
        gui.add_markdown(f"**{html.escape(title)}**")
        self._problems = gui.add_html("<p>starting</p>")
        self._replay_time = None
        if self.model.timeline is not None:
            self._build_replay(gui, self.model.timeline)
        with gui.add_folder("Digital and analog units", expand_by_default=True):
            self._units = gui.add_html("<p>-</p>")
        with gui.add_folder("Markers", expand_by_default=False):
            self._markers = gui.add_html("<p>none</p>")
        with gui.add_folder("Scene state (JSON)", expand_by_default=False):
            self._state = gui.add_html(self._state_html({}))

    def _build_replay(self, gui, timeline) -> None:
        """Play, pause, speed, the time slider with the markers on it, a button per marker."""
        from gadgetctl.view.timeline import MAX_SPEED, MAX_TIMELINE_MARKERS, MIN_SPEED

        duration = max(timeline.duration, 0.01)
        markers = timeline.markers[:MAX_TIMELINE_MARKERS]
        with gui.add_folder("Replay", expand_by_default=True):
            buttons = gui.add_button_group("Replay", ("Play", "Pause"))

            @buttons.on_click
            def _(event) -> None:
                if event.target.value == "Play":
                    timeline.play()
                else:
                    timeline.pause()

            speed = gui.add_slider("Speed", MIN_SPEED, MAX_SPEED, 0.05, 1.0)

            @speed.on_update
            def _(event) -> None:
                if event.client is not None:  # not our own update
                    timeline.set_speed(float(event.target.value))

            self._replay_time = gui.add_slider(
                "Time (s)",
                0.0,
                round(duration, 2),
                0.01,
                0.0,
                marks=tuple((round(t, 2), name) for name, t in markers) or None,
            )

            @self._replay_time.on_update
            def _(event) -> None:
                if event.client is not None:
                    timeline.seek(float(event.target.value))

            for index, (name, _t) in enumerate(markers):
                marker = gui.add_button(f"Go to marker: {name}")
                marker.on_click(lambda _event, index=index: timeline.seek_marker(index))

    # -- per frame ----------------------------------------------------------------------

    def render(self, *, slow: bool | None = None) -> None:
        """Send this frame's changes in one batch."""
        state = slow is True or self.frames_sent % STATE_EVERY == 0
        if slow is None:
            slow = self.frames_sent % SLOW_EVERY == 0
        with self.server.atomic():
            self._render_poses(slow)
            self._render_users()
            self._render_tracked_surfaces()
            self._render_cameras()
            if slow:
                self._render_trails()
                self._render_panels()
            if state:
                self._state.content = self._state_html(self.model.snapshot())
        self.frames_sent += 1

    def _render_poses(self, slow: bool) -> None:
        """Every drawn pose's axes in one instanced object and its health colour in one
        point cloud (two messages per frame however many poses), the raw frames likewise,
        and a label per pose (moved every frame for up to ``LABELS_EVERY_FRAME`` poses, else
        with the trails)."""
        drawn = self.model.poses
        # An alias of a drawn proxy is named on the proxy's axes rather than drawn again.
        self._aliases = {}
        for pose in drawn.values():
            if pose.element == "alias" and pose.proxy in drawn:
                self._aliases.setdefault(pose.proxy, []).append(pose.name)
        poses = [
            p
            for p in drawn.values()
            if p.matrix is not None and not (p.element == "alias" and p.proxy in drawn)
        ]
        stamps = tuple(p.timestamp for p in poses)
        names = tuple(p.name for p in poses)
        colours = np.array([colour_of(p.state) for p in poses], dtype=np.uint8).reshape(-1, 3)
        moved = stamps != self._stamps
        if names != self._names:
            self._rebuild(poses)
        elif moved:
            self._move(poses)
        if len(poses) and (names != self._names or not np.array_equal(colours, self._colours)):
            self._origins.colors = colours
        self._names, self._stamps, self._colours = names, stamps, colours
        move_labels = moved and (slow or len(poses) <= LABELS_EVERY_FRAME)
        for pose in poses:
            label = self._labels[pose.name]
            text = self._label(pose)
            if self._labels_text.get(pose.name) != text:
                label.text = text
                self._labels_text[pose.name] = text
            if move_labels:
                label.position = pose.matrix[:3, 3] + LABEL_OFFSET
        self._render_raw(poses, moved, slow)

    def _rebuild(self, poses: list) -> None:
        """(Re)create the batched objects and the labels for this set of poses."""
        scene = self.server.scene
        for handle in (self._axes, self._origins):
            if handle is not None:
                handle.remove()
        for name in list(self._labels):
            if name not in {p.name for p in poses}:
                self._labels.pop(name).remove()
                self._labels_text.pop(name, None)
        self._axes = self._origins = None
        if not poses:
            return
        matrices = np.stack([p.matrix for p in poses])
        scales = np.array([0.6 if p.element == "alias" else 1.0 for p in poses], dtype=np.float32)
        self._axes = scene.add_batched_axes(
            "/poses/axes",
            quaternions_wxyz(matrices).astype(np.float32),
            matrices[:, :3, 3].astype(np.float32),
            scales,
            axes_length=AXES_LENGTH,
            axes_radius=0.01,
        )
        self._origins = scene.add_point_cloud(
            "/poses/health",
            matrices[:, :3, 3].astype(np.float32),
            colors=np.array([colour_of(p.state) for p in poses], dtype=np.uint8),
            point_size=0.035,
            point_shape="circle",
            precision="float32",
        )
        for pose in poses:
            if pose.name not in self._labels:
                self._labels[pose.name] = scene.add_label(
                    f"/poses/labels/{_node(pose.name)}",
                    self._label(pose),
                    position=pose.matrix[:3, 3] + LABEL_OFFSET,
                )
                self._labels_text[pose.name] = self._label(pose)

    def _move(self, poses: list) -> None:
        matrices = np.stack([p.matrix for p in poses])
        positions = matrices[:, :3, 3].astype(np.float32)
        self._axes.batched_wxyzs = quaternions_wxyz(matrices).astype(np.float32)
        self._axes.batched_positions = positions
        self._origins.points = positions

    def _label(self, pose) -> str:
        text = f"{pose.name} \u2192 {pose.proxy}" if pose.element == "alias" else pose.name
        aliases = self._aliases.get(pose.name)
        if aliases:
            text = f"{', '.join(aliases)} \u2192 {text}"
        if pose.state not in ("active", "running"):
            text += f" [{pose.state}{': ' + pose.reason if pose.reason else ''}]"
        return text

    def _render_raw(self, poses: list, moved: bool, slow: bool) -> None:
        """The raw frames (before every filter) of the filtered poses, batched as the poses
        are, and each one's tracker frame."""
        scene = self.server.scene
        filtered = [p for p in poses if p.raw is not None]
        names = tuple(p.name for p in filtered)
        if not filtered:
            if self._raw_axes is not None:
                self._raw_axes.remove()
                self._raw_axes = None
            self._raw_names = names
            return
        raws = np.stack([p.raw for p in filtered])
        quats = quaternions_wxyz(raws).astype(np.float32)
        positions = raws[:, :3, 3].astype(np.float32)
        if names != self._raw_names:
            if self._raw_axes is not None:
                self._raw_axes.remove()
            self._raw_axes = scene.add_batched_axes(
                "/raw/axes", quats, positions, axes_length=AXES_LENGTH * 0.7, axes_radius=0.004
            )
        elif moved:
            self._raw_axes.batched_wxyzs = quats
            self._raw_axes.batched_positions = positions
        move_labels = moved and (slow or len(filtered) <= LABELS_EVERY_FRAME)
        for pose in filtered:
            label = self._raw_labels.get(pose.name)
            where = pose.raw[:3, 3] - LABEL_OFFSET
            if label is None:
                self._raw_labels[pose.name] = scene.add_label(
                    f"/raw/labels/{_node(pose.name)}", f"{pose.name} raw", position=where
                )
            elif move_labels:
                label.position = where
            tracker = pose.tracker
            key = tuple(np.round(tracker.ravel(), 6))
            if self._tracker_keys.get(pose.name) != key:
                self._tracker_keys[pose.name] = key
                handle = self._tracker.get(pose.name)
                if handle is None:
                    node = f"/tracker/{_node(pose.name)}"
                    self._tracker[pose.name] = scene.add_frame(
                        node,
                        axes_length=0.25,
                        axes_radius=0.004,
                        origin_color=(90, 90, 90),
                        wxyz=quaternions_wxyz(tracker[None])[0],
                        position=tracker[:3, 3],
                    )
                    scene.add_label(
                        node + "/label",
                        f"tracker frame of {pose.name}",
                        position=(0.0, -0.04, 0.0),
                    )
                else:
                    handle.wxyz = quaternions_wxyz(tracker[None])[0]
                    handle.position = tracker[:3, 3]
        self._raw_names = names

    def _render_users(self) -> None:
        scene = self.server.scene
        for user in self.model.user_views():
            if "position" not in user:
                continue
            left, right = np.array(user["left_eye"]), np.array(user["right_eye"])
            centre = (left + right) / 2
            sight = np.array(user["sight"])
            entry = self._users.get(user["name"])
            node = f"/users/{_node(user['name'])}"
            if entry is None:
                eye_l = scene.add_icosphere(
                    node + "/left_eye", radius=0.015, color=EYE_COLOUR, position=left
                )
                eye_r = scene.add_icosphere(
                    node + "/right_eye", radius=0.015, color=EYE_COLOUR, position=right
                )
                line = scene.add_line_segments(
                    node + "/sight",
                    np.array([[centre, centre + sight]], dtype=np.float32),
                    colors=EYE_COLOUR,
                    thickness=0.006,
                )
                self._users[user["name"]] = (eye_l, eye_r, line)
            else:
                eye_l, eye_r, line = entry
                eye_l.position = left
                eye_r.position = right
                line.points = np.array([[centre, centre + sight]], dtype=np.float32)

    def _render_tracked_surfaces(self) -> None:
        for surface in self.model.surface_views():
            if not surface["tracked"]:
                continue
            mesh, border, label = self._surfaces[surface["name"]]
            corners = np.array(surface["corners"], dtype=np.float32)
            mesh.vertices = corners
            border.points = np.array([[corners[i], corners[(i + 1) % 4]] for i in range(4)])
            label.position = tuple(corners.mean(axis=0))

    def _render_cameras(self) -> None:
        scene = self.server.scene
        for camera in self.model.camera_views():
            matrix = camera["matrix"]
            if matrix is None:
                continue
            m = np.array(matrix)
            # three.js cameras look down -Z as VR Juggler's do; viser's frustum looks down +Z.
            flip = np.diag((1.0, -1.0, -1.0, 1.0))
            quat = quaternions_wxyz((m @ flip)[None])[0]
            handle = self._cameras.get(camera["name"])
            if handle is None:
                self._cameras[camera["name"]] = scene.add_camera_frustum(
                    f"/cameras/{_node(camera['name'])}",
                    fov=float(np.radians(camera["vertical_fov"])),
                    aspect=4 / 3,
                    scale=0.2,
                    color=(60, 60, 60),
                    wxyz=quat,
                    position=m[:3, 3],
                )
            else:
                handle.wxyz = quat
                handle.position = m[:3, 3]

    def _render_trails(self) -> None:
        """Every trail in one line-segments object: the newest points of each pose, fading
        from the background to its health colour."""
        segments: list[np.ndarray] = []
        keys: list[tuple[int, tuple[int, int, int]]] = []
        for pose in self.model.poses.values():
            points = np.array(pose.trail, dtype=np.float32)
            if len(points) > TRAIL_POINTS_SENT:  # every n-th point, the newest kept
                stride = -(-len(points) // TRAIL_POINTS_SENT)
                points = points[::-1][::stride][::-1]
            if len(points) < 2:
                continue
            segments.append(np.stack([points[:-1], points[1:]], axis=1))
            keys.append((len(points) - 1, colour_of(pose.state)))
        if not segments:
            return
        points = np.concatenate(segments)
        key = tuple(keys)
        colours = None
        if key != self._trail_key:
            ramps = []
            for count, colour in keys:
                weights = np.linspace(0.0, 1.0, count + 1)
                ramp = FADE_FROM + (np.array(colour, dtype=float) - FADE_FROM) * weights[:, None]
                ramps.append(np.stack([ramp[:-1], ramp[1:]], axis=1))
            colours = np.concatenate(ramps).astype(np.uint8)
        if self._trails is None:
            self._trails = self.server.scene.add_line_segments(
                "/trails", points, colors=colours, thickness=0.004
            )
        else:
            self._trails.points = points
            if colours is not None:
                self._trails.colors = colours
        self._trail_key = key

    def _render_panels(self) -> None:
        model = self.model
        trouble = [
            e for e in model.elements if e["state"] not in ("running", "active", "configured")
        ]
        if trouble:
            rows = "".join(
                f"<li><b>{html.escape(str(e['name']))}</b> ({html.escape(str(e['element']))}) "
                f"<span data-state='{html.escape(str(e['state']))}'>{html.escape(str(e['state']))}</span>"
                + (f": {html.escape(str(e['reason']))}" if e["reason"] else "")
                + "</li>"
                for e in trouble
            )
            self._problems.content = f"<ul id='gadgetctl-problems'>{rows}</ul>"
        else:
            self._problems.content = "<p id='gadgetctl-problems'>every element running</p>"
        lines = []
        for units in model.units.values():
            digital = "".join("\u25cf" if v else "\u25cb" for v in units.digital)
            analog = " ".join(f"{v:.2f}" for v in units.analog)
            lines.append(
                f"<li><b>{html.escape(units.name)}</b> {digital} {html.escape(analog)}</li>"
            )
        self._units.content = "<ul>" + "".join(lines) + "</ul>" if lines else "<p>none</p>"
        if model.markers:
            self._markers.content = (
                "<ul>"
                + "".join(f"<li>{html.escape(str(m['name']))}</li>" for m in model.markers)
                + "</ul>"
            )
        if self._replay_time is not None and model.timeline is not None:
            self._replay_time.value = round(min(model.timeline.position, self._replay_time.max), 2)

    @staticmethod
    def _state_html(snapshot: dict[str, object]) -> str:
        text = html.escape(json.dumps(snapshot, separators=(",", ":")), quote=False)
        return (
            f"<pre id='{SCENE_ELEMENT_ID}' style='max-height:12em;overflow:auto;font-size:9px'>"
            f"{text}</pre>{_STATE_HOOK}"
        )
