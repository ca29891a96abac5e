"""Running a monitor session to the end in one of its views, shared by `monitor`, `replay`
and `demo`: live (rich, keys), table (plain text, periodic), ndjson (records on stdout) or
events (one line per change on stdout). Signals, the terminal and the writers are handled here, so that Ctrl-C, SIGTERM
or an error always restore the terminal and leave complete recordings.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from gadgetctl.cli.monitor_format import OutputFormat
from gadgetctl.errors import GadgetctlError
from gadgetctl.input.clock import now
from gadgetctl.monitor.poses import EULER, MATRIX
from gadgetctl.monitor.recording import Recorder, RecordingError, Terminated, raise_on_stop_signals
from gadgetctl.monitor.session import MonitorSession
from gadgetctl.perf import collector_paused
from gadgetctl.safetext import printable
from gadgetctl.wording import counted


@dataclass
class RunOptions:
    format: OutputFormat | None = None  # None: live on a terminal, table otherwise
    duration: float | None = None
    per_frame: bool = False
    stats: bool = False
    record: Path | None = None
    overwrite: bool = False
    interval: float = 1.0
    length_unit: str = "meters"
    quaternion: bool = False
    mouse: bool = True
    keyboard: str | None = None  # the keyboard_mouse_device keys go to first (None: the first one)
    title: str = ""
    heading: str = "gadgetctl monitor"
    notes: list[str] = field(default_factory=list)
    pose: str | None = None  # matrix, quaternion, euler (None: matrix in ndjson, euler in views)
    thresholds: Any = (
        None  # gadgetctl.monitor.events.Thresholds of --format events (None: defaults)
    )
    #: Whether lost data (kernel drops, samples over the per-frame cap) leaves the exit
    #: status 0: `monitor --accept-loss`; replay and demo have no transport to lose data in.
    accept_loss: bool = True


#: ``--record -``: the recording goes to standard output, the human output to stderr.
STDOUT_RECORD = "-"


def records_to_stdout(record: Path | None) -> bool:
    return record is not None and str(record) == STDOUT_RECORD


def human_output(record: Path | None = None):
    """Where tables, statistics and the live view go: stdout, unless it carries the recording."""
    return sys.stderr if records_to_stdout(record) else sys.stdout


def interactive(record: Path | None = None) -> bool:
    return sys.stdin.isatty() and human_output(record).isatty()


def choose_format(requested: OutputFormat | None, record: Path | None = None) -> OutputFormat:
    if requested is None:
        return OutputFormat.live if interactive(record) else OutputFormat.table
    if requested is OutputFormat.live and not interactive(record):
        where = "stderr" if records_to_stdout(record) else "stdout"
        raise GadgetctlError(
            f"the live view needs a terminal on stdin and {where}; "
            "use --format table or --format ndjson"
        )
    return requested


def check_record_path(path: Path | None, overwrite: bool, mode: OutputFormat | None = None) -> None:
    if path is None:
        return
    if records_to_stdout(path):
        if mode in (OutputFormat.ndjson, OutputFormat.events):
            raise GadgetctlError(
                f"--record - and --format {mode.value} both write to standard output; "
                "use one of them"
            )
        if sys.stdout.isatty():
            raise GadgetctlError(
                "--record -: standard output is a terminal; redirect it to a file or a "
                "pipe (or use --format ndjson to watch the records)"
            )
        return
    if path.is_dir():
        raise GadgetctlError(f"--record {path}: is a directory; give the name of the file to write")
    if path.exists() and not overwrite:
        raise GadgetctlError(f"{path}: file exists (use --overwrite to replace it)")
    if not path.parent.is_dir():
        raise GadgetctlError(f"--record {path}: no such directory {path.parent}")


def run(session: MonitorSession, options: RunOptions, *, feeder=None) -> int:
    """Run the (started) session to its end; returns the exit status (0, or 1 when an
    element ended pending, faulted or stupefied, or a device faulted during the run)."""
    mode = choose_format(options.format, options.record)
    check_record_path(options.record, options.overwrite, mode)
    human = human_output(options.record)
    if records_to_stdout(options.record):
        out = sys.stdout.buffer
        session.add_sink(lambda info: Recorder.to_stream(out, info, clock=now))
    elif options.record is not None:
        path, overwrite = options.record, options.overwrite
        session.add_sink(lambda info: Recorder(path, info, overwrite=overwrite, clock=now))
    if mode is OutputFormat.ndjson:
        stream = sys.stdout.buffer
        pose = options.pose or MATRIX

        def open_stream(info):
            return Recorder.to_stream(
                stream, info if pose == MATRIX else {**info, "pose": pose}, clock=now
            )

        session.add_sink(open_stream, per_frame=options.per_frame, pose=pose)
    elif mode is OutputFormat.events:
        session.add_consumer(EventPrinter(sys.stdout, options))
    for note in options.notes:
        print(f"gadgetctl: note: {note}", file=sys.stderr)
    reason = "closed"
    broken_pipe = False
    outcome: tuple[Mapping, list[str]] = ({}, [])
    try:
        with raise_on_stop_signals():
            try:
                if feeder is not None:
                    feeder.start()
                if mode is OutputFormat.live:
                    _live(session, options, human)
                elif mode is OutputFormat.table:
                    _table(session, options, human)
                else:  # ndjson, events: written by the session's sinks and consumers
                    notice = RateNotice(session)
                    for _ in session.frames(duration=options.duration):
                        notice.check()
                    notice.check()
            except KeyboardInterrupt:
                reason = "interrupted"
            except Terminated:
                reason = "terminated"
            except BrokenPipeError:
                if mode not in (OutputFormat.events, OutputFormat.table):
                    raise
                broken_pipe = True  # `--format events | head`: the reader has what it wanted
            except RecordingError as err:
                if (
                    mode is OutputFormat.ndjson or records_to_stdout(options.record)
                ) and "Broken pipe" in str(err):
                    broken_pipe = True  # the reader went away (`| head`): not an error
                else:
                    reason = "error"
                    raise GadgetctlError(str(err)) from None
            finally:
                if feeder is not None:
                    feeder.stop()
                # the frames are over: no sample is read any more, so the scheduler stands
                # still (with 10,000 devices its passes cost more than what follows); what
                # is read now lives to the end, so the cyclic collector does not walk the
                # whole heap again for it (a second with 10,000 devices)
                with collector_paused(), session.manager.hold_sampling():
                    try:
                        statistics = _shows_statistics(mode, options)
                        outcome = _evaluate(
                            session, accept_loss=options.accept_loss, statistics=statistics
                        )
                        if _shows_statistics_text(mode, options):  # after the devices stop
                            outcome = (dict(outcome[0]), outcome[1])
                        try:
                            if broken_pipe:
                                _silence_stdout()
                            # a sink added by the caller still gets its statistics
                            session.close_sinks(reason, final=outcome[0] if statistics else None)
                        except RecordingError as err:
                            if not broken_pipe and "Broken pipe" not in str(err):
                                raise GadgetctlError(str(err)) from None
                            _silence_stdout()
                    finally:
                        session.manager.shutdown()
    except (KeyboardInterrupt, Terminated):
        reason = "interrupted"  # a second signal while finishing: the files are complete up to here
    if broken_pipe:
        return 0
    return _finish(session, mode, options, *outcome, human=human)


class EventPrinter:
    """``--format events``: each frame's changes (:mod:`gadgetctl.monitor.events`), one line
    each, flushed every frame so that a pipe sees them at once."""

    def __init__(self, stream, options: RunOptions) -> None:
        from gadgetctl.monitor.events import ChangeDetector, Thresholds

        self.stream = stream
        self.detector = ChangeDetector(options.thresholds or Thresholds())
        self.pose = options.pose or EULER
        self.length_unit = options.length_unit
        self.origin: float | None = None
        self.lines = 0  # written so far

    def __call__(self, session: MonitorSession, moment: float) -> None:
        from gadgetctl.monitor.events import event_lines

        if self.origin is None:  # when the session started its devices: no sample is older
            self.origin = session.configured_at or session.started_at or moment
        events = self.detector.frame(session, moment)
        if events:
            self.lines += len(events)
            lines = event_lines(events, self.origin, pose=self.pose, length_unit=self.length_unit)
            self.stream.write("\n".join(lines) + "\n")
            self.stream.flush()


class RateNotice:
    """Says once that the frames do not reach the requested rate (on stderr, or through
    ``tell`` in the live view)."""

    def __init__(self, session: MonitorSession, tell=None) -> None:
        self.session = session
        self.tell = tell or (
            lambda text: print(f"gadgetctl: note: {text}", file=sys.stderr, flush=True)
        )
        self.told = False

    def check(self) -> None:
        shortfall = self.session.rate_shortfall
        if shortfall is None or self.told:
            return
        self.told = True
        requested, achieved = shortfall
        if round(achieved) >= 1:
            pace = f"about {counted(round(achieved), 'frame')} per second"
        else:  # 10,000 devices: "about 0 frames per second" said nothing
            pace = f"about one frame every {1 / max(achieved, 1e-3):.1f} seconds"
        self.tell(
            f"the frame rate of {requested:g} Hz is not reached: {pace} "
            "(--duration counts seconds all the same)"
        )


def _silence_stdout() -> None:
    with contextlib.suppress(OSError, ValueError):
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)


def _shows_statistics(mode: OutputFormat, options: RunOptions) -> bool:
    """Whether the run writes or prints the final statistics: a stats record (ndjson, a
    recording), the statistics table (--stats, the live view)."""
    return (
        mode in (OutputFormat.ndjson, OutputFormat.live)
        or options.record is not None
        or options.stats
    )


def _shows_statistics_text(mode: OutputFormat, options: RunOptions) -> bool:
    """Whether :func:`_finish` prints the statistics table (after the devices are stopped)."""
    return mode is not OutputFormat.ndjson and (options.stats or mode is OutputFormat.live)


def _evaluate(
    session: MonitorSession, *, accept_loss: bool = True, statistics: bool = True
) -> tuple[Mapping, list[str]]:
    """The final statistics (none unless ``statistics``: nothing shows them, and 10,000
    devices' cost a third of a second) and the problems, read before the devices are stopped."""
    from gadgetctl.cli.monitor_text import BAD_STATES, problem_lines
    from gadgetctl.monitor.loss import run_problems

    # made a device at a time where they are written (a stats record), not held all at once
    final = session.final_stats_view() if statistics else {}
    faults = session.final_faults()  # the faults, states and errors of the final statistics
    # the states and reasons of the elements in a bad state are what it reads
    snapshot = session.snapshot(detail=False, states=BAD_STATES)
    problems = problem_lines(snapshot)
    problems += [
        f"{name}: {counted(count, 'fault')}, last error: {error or '-'}"
        for name, (count, state, error) in faults.items()
        if count and state == "running"
    ]
    devices = session.manager.devices
    problems += run_problems(
        ((name, devices[name]) for name in session.watched if name in devices),
        accept_loss=accept_loss,
    )
    return final, problems


def _finish(
    session: MonitorSession,
    mode: OutputFormat,
    options: RunOptions,
    final: Mapping,
    problems: list[str],
    *,
    human=None,
) -> int:
    from gadgetctl.cli.monitor_text import frames_text, stats_text

    human = human or sys.stdout
    if _shows_statistics_text(mode, options):
        # after the live view (which leaves the screen as it was) always, as demo does
        width = None
        if mode is OutputFormat.live and human.isatty():  # the statistics stay unwrapped
            width = shutil.get_terminal_size().columns
        human.write(frames_text(session) + stats_text(final, width))
    if mode is OutputFormat.live and options.record is not None:
        where = (
            "standard output"
            if records_to_stdout(options.record)
            else printable(str(options.record))
        )
        markers = len(session.markers)
        human.write(
            f"recording: {where}: {counted(session.samples_written, 'sample')}, "
            f"{counted(markers, 'marker')}\n"
        )
    if (
        session.finished and mode is not OutputFormat.ndjson
    ):  # events: stdout holds only event lines
        (sys.stderr if mode is OutputFormat.events else human).write("replay finished\n")
    human.flush()
    for line in problems:
        print(f"gadgetctl: problem: {printable(line)}", file=sys.stderr)
    return 1 if problems else 0


def _table(session: MonitorSession, options: RunOptions, human) -> None:
    from gadgetctl.cli.monitor_text import TableView

    table = TableView(
        session,
        human,
        interval=options.interval,
        length_unit=options.length_unit,
        quaternion=options.quaternion,
        pose=options.pose,
    )
    notice = RateNotice(session)
    for frame in session.frames(duration=options.duration):
        notice.check()
        table.frame(frame.elapsed)
    # the frames are over: no walk of the whole heap for the table, and the scheduler stands
    # still (it would stand in for the frames while 10,000 rows are made)
    with collector_paused(), session.manager.hold_sampling():
        table.print()
    notice.check()


def _live(session: MonitorSession, options: RunOptions, human) -> None:
    from rich.console import Console

    from gadgetctl.cli.monitor_live import LiveView
    from gadgetctl.cli.monitor_terminal import KeyDecoder, RawTerminal

    console = Console(file=human)
    decoder = KeyDecoder()
    recording = (
        ("standard output" if records_to_stdout(options.record) else str(options.record))
        if options.record
        else None
    )
    view = LiveView(
        session,
        console,
        title=options.title,
        length_unit=options.length_unit,
        quaternion=options.quaternion,
        recording=recording,
        heading=options.heading,
    )
    controls = _Controls(
        session, view, has_recording=options.record is not None, keyboard=options.keyboard
    )
    notice = RateNotice(session, lambda text: setattr(view, "message", text))
    with RawTerminal(mouse=options.mouse) as terminal, view:
        # a finished replay stays on screen (FINISHED) until q, unless a duration was given
        for _ in session.frames(
            duration=options.duration, stop_at_end=options.duration is not None
        ):
            notice.check()
            moment = now()
            events = decoder.feed(terminal.read(), moment) + decoder.flush(moment)
            for event in events:
                controls.handle(event)
            if controls.quit:
                break
            view.draw()


class _Controls:
    """What the keys of the live view do: the monitor's own keys, the marker prompt, and
    everything else forwarded to the keyboard/mouse devices."""

    def __init__(
        self, session: MonitorSession, view, *, has_recording: bool, keyboard: str | None = None
    ) -> None:
        self.session = session
        self.view = view
        self.has_recording = has_recording
        self.quit = False
        keyboards = session.keyboards()
        view.focus = keyboard if keyboard in keyboards else (keyboards[0] if keyboards else None)

    def cycle_focus(self, step: int) -> None:
        """Give the keys to the next (or previous) keyboard_mouse_device."""
        keyboards = self.session.keyboards()
        if not keyboards:
            return
        current = keyboards.index(self.view.focus) if self.view.focus in keyboards else -step
        self.view.focus = keyboards[(current + step) % len(keyboards)]
        self.view.message = f"keys and the mouse go to {self.view.focus}"
        self.view.draw(force=True)

    def handle(self, event) -> None:
        from gadgetctl.input.keys import Key

        view = self.view
        if view.prompt is not None:
            self._prompt(event)
            return
        if (event.kind == "key" and not event.modifiers) or event.text == "\x03":
            text = event.text
            if text in ("q", "\x03"):
                self.quit = True
                return
            if text == "p":
                view.paused = not view.paused
                view.draw(force=True)
                return
            if text == "r":
                self.session.reset_stats()
                view.message = "statistics reset"
                return
            if text == "v":
                view.compact = not view.compact
                view.message = f"{'compact' if view.compact else 'detailed'} layout (v switches)"
                view.draw(force=True)
                return
            if text == "m":
                view.prompt = ""
                view.draw(force=True)
                return
            if event.key in (Key.KEY_TAB, Key.KEY_BACKTAB) and len(self.session.keyboards()) > 1:
                self.cycle_focus(-1 if event.key is Key.KEY_BACKTAB else 1)
                return
            if event.key in (Key.KEY_PRIOR, Key.KEY_NEXT):
                view.scroll(-1 if event.key is Key.KEY_PRIOR else 1)
                return
        self._forward(event)

    def _prompt(self, event) -> None:
        view = self.view
        text = event.text
        if event.kind != "key" or text is None:
            return
        if text in ("\r", "\n"):
            marker = self.session.mark(view.prompt.strip() or None)
            where = "written to the recording" if self.has_recording else "noted (no --record file)"
            view.message = f"marker {marker.name!r} {where}"
            view.prompt = None
        elif text == "\x1b":
            view.prompt = None
            view.message = "marker cancelled"
        elif text in ("\x7f", "\x08"):
            view.prompt = view.prompt[:-1]
        elif text.isprintable():
            view.prompt += text
        view.draw(force=True)

    def _forward(self, event) -> None:
        """To the focused keyboard_mouse_device only (one window per device, as VR Juggler)."""
        target = self.view.focus
        if target is None:
            return
        events = self.session.manager.events
        if event.kind == "key" and event.key is not None:
            events.tap(event.key, modifiers=event.modifiers, target=target)
        elif event.kind == "button" and event.key is not None:
            (events.press if event.pressed else events.release)(event.key, target=target)
        elif event.kind == "move":
            events.move(event.dx, event.dy, target=target)
        elif event.kind == "scroll" and event.direction:
            events.scroll(event.direction, target=target)
