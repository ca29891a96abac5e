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

#: Trails, panels and the JSON state are refreshed every this many frames.
SLOW_EVERY = 6
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
# panel is replaced, i.e. each time the state is sent).
_STATE_HOOK = (
    '<img alt="" style="display:none" src="data:," '
    f"onerror=\"try{{window.gadgetctlScene=JSON.parse(document.getElementById('{SCENE_ELEMENT_ID}')"
    '.textContent);window.gadgetctlSceneUpdates=(window.gadgetctlSceneUpdates||0)+1}catch(e){}">'
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
        self._frames: dict[str, Any] = {}
        self._raw: dict[str, Any] = {}
        self._tracker: dict[str, Any] = {}
        self._trails: dict[str, Any] = {}
        self._labels: dict[str, Any] = {}
        self._surfaces: dict[str, Any] = {}
        self._cameras: dict[str, Any] = {}
        self._users: dict[str, tuple[Any, Any, Any]] = {}
        self._colours: dict[str, tuple[int, int, int]] = {}
        self._sent: dict[str, float | None] = {}
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
        model = self.model
        if slow is None:
            slow = self.frames_sent % SLOW_EVERY == 0
        with self.server.atomic():
            self._render_poses()
            self._render_users()
            self._render_tracked_surfaces()
            self._render_cameras()
            if slow:
                self._render_trails()
                self._render_panels()
        self.frames_sent += 1
        del model

    def _render_poses(self) -> None:
        scene = self.server.scene
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
        if not poses:
            return
        matrices = np.stack([p.matrix for p in poses])
        quats = quaternions_wxyz(matrices)
        for pose, quat in zip(poses, quats, strict=True):
            node = f"/poses/{_node(pose.name)}"
            handle = self._frames.get(pose.name)
            colour = colour_of(pose.state)
            position = pose.matrix[:3, 3]
            if handle is None:
                alias = pose.element == "alias"
                handle = self._frames[pose.name] = scene.add_frame(
                    node,
                    axes_length=AXES_LENGTH * (0.6 if alias else 1.0),
                    axes_radius=0.006 if alias else 0.01,
                    origin_color=colour,
                    wxyz=quat,
                    position=position,
                )
                self._labels[pose.name] = scene.add_label(
                    node + "/label", self._label(pose), position=(0.0, 0.06, 0.0)
                )
                self._colours[pose.name] = colour
                self._sent[pose.name] = pose.timestamp
            elif self._sent.get(pose.name) != pose.timestamp:
                handle.wxyz = quat
                handle.position = position
                self._sent[pose.name] = pose.timestamp
            self._mark_state(pose)
            if pose.raw is not None:
                self._render_raw(pose)

    def _label(self, pose) -> str:
        text = pose.name if pose.element == "proxy" else f"{pose.name} \u2192 {pose.proxy}"
        aliases = self._aliases.get(pose.name)
        if aliases:
            text = f"{', '.join(aliases)} \u2192 {text}"
        if pose.state not in ("active", "running"):
            text += f" [{pose.state}{': ' + pose.reason if pose.reason else ''}]"
        return text

    def _mark_state(self, pose) -> None:
        handle = self._frames.get(pose.name)
        if handle is None:
            return
        colour = colour_of(pose.state)
        if self._colours.get(pose.name) != colour:
            handle.origin_color = colour
            self._colours[pose.name] = colour
        text = self._label(pose)
        if self._labels_text.get(pose.name) != text:
            self._labels[pose.name].text = text
            self._labels_text[pose.name] = text

    def _render_raw(self, pose) -> None:
        scene = self.server.scene
        raw_quat = quaternions_wxyz(pose.raw[None])[0]
        handle = self._raw.get(pose.name)
        if handle is None:
            node = f"/raw/{_node(pose.name)}"
            self._raw[pose.name] = scene.add_frame(
                node,
                axes_length=AXES_LENGTH * 0.7,
                axes_radius=0.004,
                origin_color=(120, 120, 120),
                wxyz=raw_quat,
                position=pose.raw[:3, 3],
            )
            scene.add_label(node + "/label", f"{pose.name} raw", position=(0.0, -0.04, 0.0))
            tracker = pose.tracker
            self._tracker[pose.name] = scene.add_frame(
                f"/tracker/{_node(pose.name)}",
                axes_length=0.25,
                axes_radius=0.004,
                origin_color=(90, 90, 90),
                wxyz=quaternions_wxyz(tracker[None])[0],
                position=tracker[:3, 3],
            )
            scene.add_label(
                f"/tracker/{_node(pose.name)}/label",
                f"tracker frame of {pose.name}",
                position=(0.0, -0.04, 0.0),
            )
        else:
            handle.wxyz = raw_quat
            handle.position = pose.raw[:3, 3]

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
        scene = self.server.scene
        for pose in self.model.poses.values():
            points = np.array(pose.trail, dtype=np.float32)
            if len(points) < 2:
                continue
            segments = np.stack([points[:-1], points[1:]], axis=1)
            weights = np.linspace(0.0, 1.0, len(segments) + 1)
            colour = np.array(colour_of(pose.state), dtype=float)
            ramp = FADE_FROM + (colour - FADE_FROM) * weights[:, None]
            colours = np.stack([ramp[:-1], ramp[1:]], axis=1).astype(np.uint8)
            handle = self._trails.get(pose.name)
            if handle is None:
                self._trails[pose.name] = scene.add_line_segments(
                    f"/trails/{_node(pose.name)}", segments, colors=colours, thickness=0.004
                )
            else:
                handle.points = segments
                handle.colors = colours

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
        self._state.content = self._state_html(model.snapshot())

    @staticmethod
    def _state_html(snapshot: dict[str, object]) -> str:
        text = html.escape(json.dumps(snapshot, separators=(",", ":")), quote=False)
        return (
            f"<pre id='{SCENE_ELEMENT_ID}' style='max-height:12em;overflow:auto;font-size:9px'>"
            f"{text}</pre>{_STATE_HOOK}"
        )
