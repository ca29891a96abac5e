"""`gadgetctl serve CONFIG... [NAME...]`: share a configuration's devices over VRPN."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import typer

from gadgetctl.cli.drivers_cmd import DRIVER_PATH_OPTION, TRUST_OPTION
from gadgetctl.cli.monitor_cmd import CHECK_OPTION, STRICT_OPTION
from gadgetctl.cli.options import BUNDLED_OPTION, DEFINITIONS_OPTION, DataFormat, emit
from gadgetctl.wording import counted

#: --bind and --allow, shared with `gadgetctl view`.
BIND_OPTION = typer.Option(
    "127.0.0.1",
    "--bind",
    metavar="ADDR",
    help="IPv4 address to listen on: 127.0.0.1 (this machine only), 0.0.0.0 (every interface) or one NIC's address.",
)
ALLOW_OPTION = typer.Option(
    [],
    "--allow",
    metavar="CIDR",
    help="Accept clients only from this network or address (192.168.1.0/24). Repeatable; default: everyone who reaches --bind.",
)


def register(app: typer.Typer) -> None:
    app.command(name="serve")(serve)


def serve(
    arguments: list[str] = typer.Argument(
        ...,
        metavar="CONFIG... [NAME...]",
        show_default=False,
        help="Configuration files (existing files ending in .jconf), then names or glob patterns of the devices, proxies and aliases to serve (default: all).",
    ),
    list_: bool = typer.Option(
        False,
        "--list",
        help="Print the VRPN name of every served element and what it is served as, then exit.",
    ),
    names: list[str] = typer.Option(
        [],
        "--name",
        metavar="OLD=NEW",
        help="Serve the element OLD as the VRPN device NEW. Repeatable.",
    ),
    bind: str = BIND_OPTION,
    port: int = typer.Option(
        3883,
        "--port",
        metavar="PORT",
        help="TCP and UDP port (VRPN's default 3883; 0: chosen by the system and printed).",
    ),
    allow: list[str] = ALLOW_OPTION,
    duration: float | None = typer.Option(
        None,
        "--duration",
        metavar="SECONDS",
        help="Stop after this many seconds (default: until Ctrl-C or SIGTERM).",
    ),
    rate: float = typer.Option(
        1000.0,
        "--rate",
        metavar="HZ",
        help="Frames per second: how often new samples are gathered and sent.",
    ),
    client_buffer: int = typer.Option(
        1 << 20,
        "--client-buffer",
        metavar="BYTES",
        help="Bytes queued per client before its messages are dropped (and counted).",
    ),
    record: Path | None = typer.Option(
        None,
        "--record",
        metavar="FILE",
        help="Also write every served device sample to FILE (the recording format of monitor --record).",
    ),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace an existing --record file."),
    fmt: DataFormat = typer.Option(
        DataFormat.text,
        "--format",
        "-f",
        help="text, or json: --list as one JSON object, events as one JSON object per line.",
    ),
    driver_paths: list[Path] = DRIVER_PATH_OPTION,
    trust_driver_path: bool = TRUST_OPTION,
    definitions: list[Path] = DEFINITIONS_OPTION,
    bundled: bool = BUNDLED_OPTION,
    check: bool = CHECK_OPTION,
    strict: bool = STRICT_OPTION,
) -> None:
    """Run the input manager on CONFIG files and serve every device, proxy and alias over
    VRPN, so that VRPN clients (VR Juggler's VRPN_drv, gadgetctl's, Unity's, vrpn_print_devices)
    read them as NAME@host: position units as Tracker sensors, buttons as a Button, analog
    units as an Analog (proxies normalised to 0..1), strings and commands as Text.

    VRPN names are the element names with every run of characters other than letters,
    digits, '_', '-' and '.' made one '_' (see --list, docs/serve.md). VRPN has no
    authentication: bind beyond 127.0.0.1 only on a trusted network, and limit clients with
    --allow. Exit status: 0 when stopped (Ctrl-C, SIGTERM, --duration); 2 on usage errors
    (unreadable configuration, unknown name, port taken).
    """
    from gadgetctl.cli.monitor_cmd import fatal_load_errors, split_arguments
    from gadgetctl.input.manager import InputManager, ManagerOptions
    from gadgetctl.serve.address import check_bind, check_port, parse_allow
    from gadgetctl.serve.naming import parse_renames
    from gadgetctl.serve.service import ServeOptions, ServeService

    configs, selectors = split_arguments(arguments, command="serve")
    parsed = {}  # the documents the check parsed: loaded without parsing them again
    if check:  # the configuration findings first, as monitor does
        from gadgetctl.cli.preflight import check_before_running

        parsed = check_before_running(
            configs, definitions=definitions, bundled=bundled, strict=strict
        )
    options = ServeOptions(
        selectors=selectors,
        renames=parse_renames(names),
        bind=check_bind(bind),
        port=check_port(port),
        allow=parse_allow(allow),
        rate=_check_rate(rate),
        client_buffer=_check_buffer(client_buffer),
        statistics=record is not None,  # the recording ends with per-device statistics
    )
    if duration is not None and not duration >= 0:
        from gadgetctl.errors import GadgetctlError

        raise GadgetctlError(f"--duration is a number of seconds, 0 or more, not {duration:g}")
    manager, configuration = InputManager.from_files(
        configs,
        definitions=list(definitions),
        bundled=bundled,
        options=ManagerOptions(driver_dirs=list(driver_paths)),
        parsed=parsed,
    )
    fatal_load_errors(configuration)
    if record is not None and not list_:
        from gadgetctl.cli.monitor_run import check_record_path, records_to_stdout
        from gadgetctl.errors import GadgetctlError

        if records_to_stdout(record):
            manager.shutdown()
            raise GadgetctlError(
                "--record -: serve reports its clients on standard output; give a file name"
            )
        check_record_path(record, overwrite)
    service = ServeService(
        manager, configuration, options, info={"config": [str(p) for p in configs]}
    )
    try:
        catalog = service.prepare()
        if list_:
            _print_list(catalog, fmt)
            raise typer.Exit(0)
        if record is not None:
            from gadgetctl.input.clock import now
            from gadgetctl.monitor.recording import Recorder

            service.session.add_sink(
                lambda info: Recorder(record, info, overwrite=overwrite, clock=now)
            )
        raise typer.Exit(_run(service, duration, fmt))
    finally:
        service.close()


def _check_rate(rate: float) -> float:
    from gadgetctl.errors import GadgetctlError

    if not 0 < rate <= 10_000:
        raise GadgetctlError(
            f"--rate must be more than 0 and at most 10000 frames per second, not {rate:g}"
        )
    return rate


def _check_buffer(size: int) -> int:
    from gadgetctl.errors import GadgetctlError

    if size < 65536:
        raise GadgetctlError(
            f"--client-buffer must be at least 65536 bytes (one VRPN message), not {size}"
        )
    return size


def _units_text(entry) -> str:
    parts = []
    for role in entry.roles:
        count = entry.units.get(role)
        label = {"tracker": "Tracker", "button": "Button", "analog": "Analog", "text": "Text"}[
            role.value
        ]
        noun = {"tracker": "sensor", "button": "button", "analog": "channel"}.get(role.value)
        if noun and count is not None:
            label += f" ({count} {noun}{'s' if count != 1 else ''})"
        parts.append(label)
    if entry.analog_range is not None:
        low, high = entry.analog_range
        parts.append(f"analog {low:g}..{high:g}")
    if entry.not_served:
        parts.append("not served: " + ", ".join(entry.not_served))
    return ", ".join(parts) if parts else "nothing VRPN can carry"


def _print_list(catalog, fmt: DataFormat) -> None:
    if fmt is DataFormat.json:
        emit(json.dumps({"served": [e.to_dict() for e in catalog]}, indent=2))
        return
    if not catalog:
        emit("nothing to serve")
        return
    from gadgetctl.safetext import printable

    width = max(len(e.vrpn_name) for e in catalog)
    lines = []
    for entry in catalog:
        # element, type and source names come from the configuration: escaped, one line each
        origin = (
            "" if entry.vrpn_name == entry.element else f"  (element '{printable(entry.element)}')"
        )
        source = f" of {printable(entry.source)}" if entry.source else ""
        lines.append(
            f"{entry.vrpn_name:<{width}}  {entry.kind} {printable(entry.element_type)}{source}: "
            f"{_units_text(entry)}{origin}"
        )
    emit("\n".join(lines))


def _bind_error(options, err: OSError):
    from gadgetctl.doctor.ports import check_serve_port
    from gadgetctl.errors import GadgetctlError

    where = f"{options.bind}:{options.port}"
    check = check_serve_port(options.bind, options.port) if options.port else None
    if check is not None and check.code:
        return GadgetctlError(f"cannot serve on {where}: {check.detail}; {check.hint}")
    return GadgetctlError(f"cannot serve on {where}: {err.strerror or err}")


def _say(fmt: DataFormat, record: dict[str, object], text: str) -> None:
    if fmt is DataFormat.json:
        sys.stdout.write(json.dumps(record) + "\n")
    else:
        sys.stdout.write(text + "\n")
    sys.stdout.flush()


def _run(service, duration: float | None, fmt: DataFormat) -> int:
    from gadgetctl.monitor.recording import Terminated, raise_on_stop_signals
    from gadgetctl.serve.address import is_loopback

    options = service.options
    try:
        import gadgetctl.vrpn.server  # noqa: F401
    except ImportError:
        from gadgetctl.errors import GadgetctlError

        raise GadgetctlError(
            "this gadgetctl has no VRPN protocol library yet (gadgetctl.vrpn)"
        ) from None
    try:
        port = service.listen()
    except OSError as err:
        raise _bind_error(options, err) from None
    served = [e for e in service.catalog if e.roles]
    where = f"{options.bind}:{port}"
    _say(
        fmt,
        {
            "event": "listening",
            "host": options.bind,
            "port": port,
            "devices": len(served),
            "names": [e.vrpn_name for e in served],
        },
        f"gadgetctl serve: {counted(len(served), 'VRPN device')} on {where} (TCP and UDP): "
        + ", ".join(e.vrpn_name for e in served[:8])
        + (" ..." if len(served) > 8 else ""),
    )
    if not is_loopback(options.bind):
        allowed = ", ".join(str(n) for n in options.allow) or "everyone who can reach it"
        print(
            f"gadgetctl: warning: VRPN has no authentication: clients from {allowed} may read every "
            f"served device on {where}"
            + ("" if options.allow else " (limit them with --allow CIDR)"),
            file=sys.stderr,
            flush=True,
        )

    def show(event) -> None:
        record = {"event": event.kind, "client": event.client, "detail": event.detail}
        text = f"gadgetctl serve: client {event.client} {event.kind}"
        if event.kind == "disconnected":
            record.update(sent=event.sent, dropped=event.dropped)
            text += f": {counted(event.sent, 'message')} sent, {event.dropped} dropped"
        if event.detail:
            text += f" ({event.detail})"
        _say(fmt, record, text)

    service.listeners.append(show)
    reason = "duration"
    try:
        with raise_on_stop_signals():
            try:
                for _ in service.frames(duration):
                    pass
            except KeyboardInterrupt:
                reason = "interrupted"
            except Terminated:
                reason = "terminated"
    except (KeyboardInterrupt, Terminated):
        reason = "interrupted"
    try:
        service.close(reason)
    except (KeyboardInterrupt, Terminated):
        pass
    totals = service.totals()
    counters = totals["counters"]
    noted = {
        k: v
        for k, v in counters.items()
        if k not in ("accepted", "connections", "disconnects", "lobs", "messages")
    }
    _say(
        fmt,
        {"event": "stopped", "reason": reason, **totals},
        f"gadgetctl serve: stopped ({reason}): {counted(totals['messages'], 'message')} to "
        f"{counted(totals['clients'], 'client')}, {totals['dropped']} dropped"
        + (
            "; " + ", ".join(f"{k.replace('_', ' ')} {v}" for k, v in noted.items())
            if noted
            else ""
        ),
    )
    return 0
