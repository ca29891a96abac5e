"""`gadgetctl demo`: what `make demo` runs: the monitor on the bundled waveform example."""

from __future__ import annotations

import typer

DEMO_SECONDS = 3.0


def register(app: typer.Typer) -> None:
    app.command(name="demo")(demo)


def demo(
    duration: float = typer.Option(
        DEMO_SECONDS, "--duration", metavar="SECONDS", help="How long to monitor."
    ),
) -> None:
    """Monitor the bundled waveform example (examples/waveform.jconf) for a few seconds: the
    live view on a terminal (q ends it early), a plain-text table otherwise."""
    from gadgetctl.cli.monitor_cmd import run_monitor
    from gadgetctl.cli.monitor_run import interactive
    from gadgetctl.cli.options import emit
    from gadgetctl.resources import examples_dir

    config = examples_dir() / "waveform.jconf"
    if not interactive():
        emit(
            f"gadgetctl demo: monitoring the simulated devices of {config.name} for {duration:g} s "
            f"(run `gadgetctl monitor {config}` on a terminal for the live view)"
        )
    code = run_monitor(
        [config], [], duration=duration, interval=1.0, stats=True, heading="gadgetctl demo"
    )
    raise typer.Exit(code)
