"""`gadgetctl view --export FILE.html`: the scene as one self-contained page.

viser serialises the scene's messages (with the pauses between frames) and writes them
into a copy of its own client page (``window.__VISER_EMBED_DATA__``), which plays them back
with no server and no network: the client, three.js included, is inline in that page. The
frames are made here without waiting for the clock: a live configuration runs its devices
for ``seconds`` (default 2 s) of frames; a recording is stepped through from start to end
by seeking its timeline, at ``EXPORT_RATE`` frames a second of recording, fewer when that
would be more than ``MAX_EXPORT_FRAMES``. The scene model's last snapshot is written into the
page too (``window.gadgetctlScene``), as the live page keeps it.
"""

from __future__ import annotations

import html
import json

EXPORT_RATE = 30.0
#: At most this many frames are written (a long recording is exported at a lower rate).
MAX_EXPORT_FRAMES = 3600


def export_frames(duration: float) -> tuple[int, float]:
    """(frames, seconds between frames) for ``duration`` seconds of scene."""
    frames = max(1, min(MAX_EXPORT_FRAMES, round(duration * EXPORT_RATE) + 1))
    step = duration / (frames - 1) if frames > 1 else 0.0
    return frames, step


def export_page(view_server, *, seconds: float, live_frames=None) -> tuple[str, int]:
    """The self-contained page of ``view_server``'s scene and the frames it holds.

    With a timeline (``view_server.model.timeline``) the recording is stepped through; else
    ``live_frames`` (an iterator of the session's frames, paced by its clock) runs for
    ``seconds``."""
    model = view_server.model
    serializer = view_server.server.get_scene_serializer()
    timeline = model.timeline
    written = 0
    if timeline is not None:
        timeline.pause()
        frames, step = export_frames(timeline.duration)
        session = view_server.session
        for index in range(frames):
            timeline.seek(index * step)
            timeline.advance()
            session.step()
            view_server.step_now(slow=True)
            if index:
                serializer.insert_sleep(step)
            written += 1
    else:
        previous = None
        for frame in live_frames if live_frames is not None else ():
            view_server.step_now(slow=written % 3 == 0)
            if previous is not None:
                serializer.insert_sleep(max(0.0, frame.timestamp - previous))
            previous = frame.timestamp
            written += 1
    page = serializer.as_html()
    state = json.dumps(model.snapshot(), separators=(",", ":"))
    script = (
        "<script>window.gadgetctlScene="
        + state.replace("<", "\\u003c")
        + ";window.gadgetctlExport=true;</script>"
        + f"<title>{html.escape(view_server.title)}</title>"
    )
    head_end = page.index("</head>")
    return page[:head_end] + script + page[head_end:], written
