"""`gadgetctl view CONFIG... [NAME...]`: a live 3D view of tracked poses in a web page."""

from __future__ import annotations

import sys
from pathlib import Path

import typer

from gadgetctl.cli.drivers_cmd import DRIVER_PATH_OPTION, TRUST_OPTION
from gadgetctl.cli.monitor_cmd import CHECK_OPTION, STRICT_OPTION
from gadgetctl.cli.options import BUNDLED_OPTION, DEFINITIONS_OPTION
from gadgetctl.cli.serve_cmd import ALLOW_OPTION, BIND_OPTION

DEFAULT_PORT = 8080


def register(app: typer.Typer) -> None:
    app.command(name="view")(view)


def view(
    arguments: list[str] | None = typer.Argument(
        None,
        metavar="CONFIG... [NAME...]",
        show_default=False,
        help="Configuration files (existing files ending in .jconf) and VRPN devices (vrpn:Device@host), then names or glob patterns of the devices, proxies and aliases to show (default: all), as for monitor.",
    ),
    bind: str = BIND_OPTION,
    port: int = typer.Option(
        DEFAULT_PORT,
        "--port",
        metavar="PORT",
        help="TCP port of the page (0: chosen by the system).",
    ),
    allow: list[str] = ALLOW_OPTION,
    open_browser: bool = typer.Option(
        False, "--open", help="Open the page in the default web browser."
    ),
    rate: float = typer.Option(
        60.0, "--rate", metavar="HZ", help="Frames per second: how often the page is updated."
    ),
    duration: float | None = typer.Option(
        None,
        "--duration",
        metavar="SECONDS",
        help="Stop after this many seconds (default: until Ctrl-C or SIGTERM).",
    ),
    export: Path | None = typer.Option(
        None,
        "--export",
        metavar="FILE.html",
        help="Write the scene as one self-contained page that opens offline with no server (of --duration seconds of live frames, default 2; or the whole --replay recording), instead of serving it.",
    ),
    replay: Path | None = typer.Option(
        None,
        "--replay",
        metavar="FILE",
        help="Show a recording (monitor --record, or a VRPN log) instead of live devices, with a timeline: play, pause, speed, scrubbing, its markers. CONFIG files then give the displays, users, proxies and filters; their elements named like recorded devices become replay devices.",
    ),
    driver_paths: list[Path] = DRIVER_PATH_OPTION,
    trust_driver_path: bool = TRUST_OPTION,
    definitions: list[Path] = DEFINITIONS_OPTION,
    bundled: bool = BUNDLED_OPTION,
    check: bool = CHECK_OPTION,
    strict: bool = STRICT_OPTION,
) -> None:
    """Serve a web page with a live 3D view of the configuration: its display surfaces, every
    positional proxy and alias with a fading trail coloured by health (pending, stupefied and
    faulted ones with their reason), each user's head with both eyes and the line of sight,
    the raw tracker frames before the position filters, and the digital and analog units.

    Arguments are those of monitor. The page needs no network beyond this server; it is bound
    to 127.0.0.1 unless --bind says otherwise (it has no authentication: limit clients with
    --allow). Exit status: 0 when stopped (Ctrl-C, SIGTERM, --duration); 2 on usage errors
    (viser not installed, unreadable configuration, unknown name, port taken).
    """
    from gadgetctl.errors import GadgetctlError
    from gadgetctl.view import viser_missing

    missing = viser_missing()
    if missing:
        raise GadgetctlError(missing)
    from gadgetctl.cli.monitor_cmd import check_options, split_arguments
    from gadgetctl.monitor.vrpnwatch import is_vrpn_argument
    from gadgetctl.serve.address import check_bind, check_port, parse_allow

    address = check_bind(bind)
    check_port(port)
    networks = parse_allow(allow)
    check_options(rate, duration, 1.0)
    arguments = list(arguments or ())
    if not arguments and replay is None:
        raise GadgetctlError(
            "no configuration given: CONFIG arguments are existing files ending in .jconf "
            "(or vrpn:Device@host, or --replay FILE)"
        )
    watched = [a for a in arguments if is_vrpn_argument(a)]
    configs, selectors = split_arguments(
        [a for a in arguments if not is_vrpn_argument(a)],
        require_config=not watched and replay is None,
    )
    if check and configs:
        from gadgetctl.cli.preflight import check_before_running

        check_before_running(configs, definitions=definitions, bundled=bundled, strict=strict)
    from gadgetctl.cli.monitor_cmd import watched_devices

    title = " ".join([*(Path(p).name for p in configs), *watched])
    with watched_devices(configs, watched) as configs:
        code = run_view(
            configs,
            selectors,
            bind=address,
            port=port,
            allow=networks,
            open_browser=open_browser,
            rate=rate,
            duration=duration,
            driver_paths=driver_paths,
            definitions=definitions,
            bundled=bundled,
            title=f"gadgetctl view {title}" + (f" (replay of {replay.name})" if replay else ""),
            replay=replay,
            export=export,
        )
    raise typer.Exit(code)


def run_view(
    configs: list[Path],
    selectors: list[str],
    *,
    bind: str,
    port: int,
    allow,
    open_browser: bool,
    rate: float,
    duration: float | None,
    driver_paths: list[Path],
    definitions: list[Path],
    bundled: bool,
    title: str,
    replay: Path | None = None,
    export: Path | None = None,
) -> int:
    from gadgetctl.cli.monitor_cmd import fatal_load_errors
    from gadgetctl.errors import GadgetctlError
    from gadgetctl.input.manager import InputManager, ManagerOptions
    from gadgetctl.monitor.recording import Terminated, raise_on_stop_signals
    from gadgetctl.monitor.session import MonitorSession
    from gadgetctl.serve.address import is_loopback
    from gadgetctl.view.server import ViewServer

    timeline = None
    if replay is not None:
        from gadgetctl.view.replaysource import open_view_replay

        opened = open_view_replay(
            replay,
            configs,
            definitions=list(definitions or ()),
            bundled=bundled,
            driver_dirs=list(driver_paths or ()),
        )
        manager, configuration, timeline = opened.manager, opened.configuration, opened.timeline
        for note in opened.notes:
            print(f"gadgetctl: note: {note}", file=sys.stderr)
    else:
        options = ManagerOptions(driver_dirs=list(driver_paths or ()))
        manager, configuration = InputManager.from_files(
            configs, definitions=list(definitions or ()), bundled=bundled, options=options
        )
        try:
            fatal_load_errors(configuration)
        except BaseException:
            manager.shutdown()
            raise
    session = MonitorSession(
        manager,
        configuration,
        selectors=selectors,
        rate=rate,
        source=timeline,
        info={"config": [str(p) for p in configs]},
    )
    server = None
    try:
        session.start()
        try:
            server = ViewServer(
                session,
                configuration,
                host="127.0.0.1" if export is not None else bind,
                port=0 if export is not None else port,
                title=title,
                allow=allow,
                timeline=timeline,
                on_refused=lambda a: print(
                    f"gadgetctl view: refused a client from {a} (not in --allow)",
                    file=sys.stderr,
                    flush=True,
                ),
            )
        except OSError as err:
            raise GadgetctlError(
                f"cannot serve the page on {bind}:{port}: {err.strerror or err}"
            ) from None
        if export is not None:
            return _export(server, export, duration)
        if port and server.port != port:
            raise GadgetctlError(f"cannot serve the page on {bind}:{port}: the port is taken")
        print(f"gadgetctl view: {server.url} (Ctrl-C stops)", flush=True)
        if not is_loopback(bind):
            allowed = ", ".join(str(n) for n in allow) or "everyone who can reach it"
            print(
                f"gadgetctl: warning: the page has no authentication: clients from {allowed} "
                f"see every device on {bind}:{server.port}"
                + ("" if allow else " (limit them with --allow CIDR)"),
                file=sys.stderr,
                flush=True,
            )
        if open_browser:
            import webbrowser

            webbrowser.open(server.url)
        try:
            with raise_on_stop_signals():
                server.run(duration=duration, stop_at_end=False)
        except (KeyboardInterrupt, Terminated):
            pass
    finally:
        if server is not None:
            server.stop()
        manager.shutdown()
    return 0


#: Seconds of live frames an --export writes when --duration does not say.
EXPORT_SECONDS = 2.0


def _export(server, path: Path, duration: float | None) -> int:
    """Write the self-contained page; its own one-line report."""
    from gadgetctl.errors import GadgetctlError
    from gadgetctl.safewrite import WriteError, replace_file
    from gadgetctl.view.export import export_page

    seconds = EXPORT_SECONDS if duration is None else duration
    frames = None if server.model.timeline is not None else server.session.frames(duration=seconds)
    page, written = export_page(server, seconds=seconds, live_frames=frames)
    try:
        replace_file(path, page.encode("utf-8"))
    except WriteError as err:
        raise GadgetctlError(str(err)) from None
    size = len(page.encode("utf-8"))
    print(f"gadgetctl view: wrote {path} ({written} frames, {size / 1e6:.1f} MB; opens offline)")
    return 0
