"""The web page of `gadgetctl view`: a viser server drawing one session's scene.

The page (viser's client, served from the viser wheel) needs no network beyond the
connection to this server. :class:`ViewServer` runs the session's frames: once per frame the
scene model reads the proxies and the renderer sends the changes in one batch.
"""

from __future__ import annotations

import contextlib
import io
import ipaddress
import threading
from collections.abc import Callable, Iterable
from typing import Any

from gadgetctl.view.layout import read_layout
from gadgetctl.view.render import SceneRenderer
from gadgetctl.view.scene import SceneModel


class ViewServer:
    """Serves ``session``'s scene on ``host:port`` (0: a port the system picks)."""

    def __init__(
        self,
        session,
        configuration,
        *,
        host: str = "127.0.0.1",
        port: int = 0,
        title: str = "gadgetctl view",
        allow: Iterable[ipaddress.IPv4Network] = (),
        on_refused: Callable[[str], None] | None = None,
        timeline=None,
    ) -> None:
        import viser

        self.session = session
        self.title = title
        elements = configuration.elements if configuration is not None else []
        self.model = SceneModel(session, read_layout(elements, session.manager.repo))
        self.model.timeline = timeline
        self.allow = list(allow)
        self.refused = 0
        self._on_refused = on_refused
        self._lock = threading.Lock()
        with _quiet():  # viser prints a banner of its own; the command prints the address
            self.server = viser.ViserServer(host=host, port=port, label=title, verbose=False)
        if self.allow:
            self._guard()
        self.model.update()
        self.renderer = SceneRenderer(self.server, self.model, title=title)
        self.renderer.render(slow=True)

    def _guard(self) -> None:
        """Close the connection of a client outside ``allow`` before anything is sent."""
        from gadgetctl.serve.address import allowed

        websock = self.server._websock_server

        async def guard(connection: Any) -> None:
            live = websock._live_connections.get(connection.client_id)
            if live is None:
                return
            address = str(live.remote_address[0]) if live.remote_address else ""
            if not allowed(address, self.allow):
                self.refused += 1
                if self._on_refused is not None:
                    self._on_refused(address)
                await live.close(1008, "not allowed by --allow")

        websock.on_client_connect(guard)

    @property
    def host(self) -> str:
        return self.server.get_host()

    @property
    def port(self) -> int:
        return self.server.get_port()

    @property
    def url(self) -> str:
        host = self.host
        shown = "127.0.0.1" if host in ("0.0.0.0", "") else host
        return f"http://{shown}:{self.port}/"

    @property
    def clients(self) -> int:
        return len(self.server.get_clients())

    def step(self) -> None:
        """Bring the model and the page up to this frame (the session has stepped)."""
        with self._lock:
            self.model.update(statuses=self.renderer.frames_sent % 6 == 0)
            self.renderer.render()
            if self.model.timeline is not None:
                self.model.timeline.advance()  # what it hands over shows in the next frame

    def step_now(self, *, slow: bool) -> None:
        """Bring the model and the page up to this frame, with (``slow``) or without the
        statuses, trails and panels; the timeline is left alone (the caller drives it)."""
        with self._lock:
            self.model.update(statuses=slow)
            self.renderer.render(slow=slow)

    def snapshot(self) -> dict[str, object]:
        with self._lock:
            return self.model.snapshot()

    def run(self, *, duration: float | None = None, stop_at_end: bool = True) -> None:
        """Run the session's frames, drawing each one, until ``duration`` or stop."""
        for _ in self.session.frames(duration=duration, stop_at_end=stop_at_end):
            self.step()

    def stop(self) -> None:
        self.session.stop()
        with _quiet():
            self.server.stop()


@contextlib.contextmanager
def _quiet():
    """Swallow what viser prints on stdout (its start banner, "Server stopped")."""
    with contextlib.redirect_stdout(io.StringIO()):
        yield
