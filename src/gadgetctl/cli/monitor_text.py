"""Plain-text rendering for `gadgetctl monitor` and `gadgetctl replay`: value formatting
shared with the live view, the periodic table (``--format table``), the end-of-run
statistics and recording summaries. No rich here: the output goes to pipes and CI logs.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from typing import Any, TextIO

import numpy as np

from gadgetctl.monitor.events import FINGERS, HAT_NAMES, UNIT_SYMBOLS, number_text, pose_text
from gadgetctl.monitor.session import MonitorSession
from gadgetctl.monitor.stats import DeviceSnapshot
from gadgetctl.monitor.units import (
    euler_xyz_degrees,
    length_factor,
    quaternion_wxyz,
)
from gadgetctl.monitor.views import ElementView, Snapshot, UnitView
from gadgetctl.safetext import fixed, is_printable, printable
from gadgetctl.wording import counted

TOGGLES = {0: "off", 1: "on", 2: "toggle on", 3: "toggle off"}
HAT = HAT_NAMES
BAD_STATES = {
    "faulted",
    "reconnecting",
    "undecodable",
    "pending",
    "stupefied",
    "removed",
    "stopped",
}


def rate_text(rate: float | None) -> str:
    return "-" if rate is None else f"{rate:.1f}"


def per_frame_text(stats: DeviceSnapshot | None) -> str:
    """Samples per frame over the window RATE covers (the run's mean before timed frames)."""
    if stats is None:
        return "-"
    value = stats.window_samples_per_frame
    if value is None:
        value = stats.mean_samples_per_frame
    return "-" if value is None else f"{value:.2f}"


def ms_text(seconds: float | None) -> str:
    if seconds is None or not math.isfinite(seconds):
        return "-"
    ms = seconds * 1000.0
    return f"{ms:.0f}" if ms >= 100 else f"{ms:.1f}" if ms >= 1 else f"{ms:.2f}"


def age_text(seconds: float | None) -> str:
    if seconds is None:
        return "-"
    if seconds >= 10:
        return f"{seconds:.0f} s"
    return f"{ms_text(seconds)} ms"


def number(value: float, digits: int = 3) -> str:
    return fixed(value, digits) if math.isfinite(value) else str(value)


def position_text(
    matrix: Any, length_unit: str = "meters", quaternion: bool = False, pose: str | None = None
) -> str:
    """The translation and the rotation as Euler angles (``quaternion`` adds w x y z); with
    ``pose`` (``--pose``) exactly that form (:func:`gadgetctl.monitor.events.pose_text`)."""
    if pose is not None:
        return pose_text(matrix, pose, length_unit)
    m = np.asarray(matrix, dtype=np.float64).reshape(4, 4)
    factor = length_factor(length_unit)  # Python floats: as from_meters, inf beyond any float
    x, y, z = (row[3] * factor for row in m[:3].tolist())
    symbol = UNIT_SYMBOLS.get(length_unit, length_unit)
    text = f"x {fixed(x, 3, True)} y {fixed(y, 3, True)} z {fixed(z, 3, True)} {symbol}"
    try:
        rx, ry, rz = euler_xyz_degrees(m)
        text += f"  rot {rx:+6.1f} {ry:+6.1f} {rz:+6.1f}°"
        if quaternion:
            w, qx, qy, qz = quaternion_wxyz(m)
            text += f"  q {w:+.3f} {qx:+.3f} {qy:+.3f} {qz:+.3f}"
    except ValueError:
        text += "  rot -"
    return text


def glove_parts(angles: Any) -> list[str]:
    """Each finger's joint angles in degrees: ``thumb 0/12/30/0``."""
    with np.errstate(all="ignore"):  # a hostile angle is inf, not a warning on stderr
        a = np.degrees(np.asarray(angles, dtype=np.float64).reshape(6, 4))
    return [
        f"{name} {'/'.join(fixed(v, 0) for v in row)}" for name, row in zip(FINGERS, a, strict=True)
    ]


def glove_text(angles: Any) -> str:
    return " ".join(glove_parts(angles))


class PositionTexts:
    """:func:`position_text` of the matrices of one table, remembering the last few: a
    position proxy's row shows the very matrix of its device's row just before it (10,000
    devices and their proxies: half of the 20,000 texts are made again otherwise). Kept
    small (:attr:`MOST`), the table's rows being made a chunk at a time."""

    MOST = 64

    def __init__(
        self, length_unit: str = "meters", quaternion: bool = False, pose: str | None = None
    ) -> None:
        self.length_unit = length_unit
        self.quaternion = quaternion
        self.pose = pose
        self.made = 0  # texts made, not remembered (what a test counts)
        self._texts: dict[bytes, str] = {}

    def text(self, matrix: Any) -> str:
        key = None
        if type(matrix) is np.ndarray and matrix.dtype == np.float64 and matrix.size == 16:
            key = matrix.tobytes()  # the same bytes: the same numbers, the same text
            found = self._texts.get(key)
            if found is not None:
                return found
        text = position_text(matrix, self.length_unit, self.quaternion, self.pose)
        self.made += 1
        if key is not None:
            if len(self._texts) >= self.MOST:
                self._texts.clear()
            self._texts[key] = text
        return text


def unit_value_text(
    view: UnitView,
    *,
    element: str = "device",
    length_unit: str = "meters",
    quaternion: bool = False,
    pose: str | None = None,
    positions: PositionTexts | None = None,
) -> str:
    """One unit's value as text (no bar, no sparkline); ``positions`` (made with the same
    ``length_unit``, ``quaternion`` and ``pose``) makes the text of a position."""
    kind, value = view.kind, view.value
    if kind == "analog":
        raw = "" if view.raw is None else f" (raw {number_text(view.raw)})"
        return f"{number(float(value))}{raw}"
    if kind == "digital":
        if element == "device":
            state = "pressed" if value else "released"
            mark = "*" if view.changed else ""
            return f"{state}{mark}" + (f" x{view.presses}" if view.presses else "")
        return TOGGLES.get(int(value), str(value)) + (f" x{view.presses}" if view.presses else "")
    if kind == "position":
        if positions is not None:
            return positions.text(value)
        return position_text(value, length_unit, quaternion, pose)
    if kind == "glove":
        return glove_text(value)
    if kind == "hat":
        return HAT.get(int(value), str(value))
    if kind == "string":
        return repr(value)
    if kind == "keyboard_mouse":
        return "held: " + (", ".join(value) if value else "none")
    return str(value)


def values_text(
    element: ElementView,
    *,
    length_unit: str = "meters",
    quaternion: bool = False,
    pose: str | None = None,
    positions: PositionTexts | None = None,
) -> str:
    """Every unit of an element on one line, grouped by kind."""
    groups: dict[str, list[str]] = {}
    for unit in element.values:
        text = unit_value_text(
            unit,
            element=element.element,
            length_unit=length_unit,
            quaternion=quaternion,
            pose=pose,
            positions=positions,
        )
        if element.element == "device":
            text = f"{unit.unit}: {text}"
        groups.setdefault(unit.kind, []).append(text)
    return "; ".join(f"{kind} " + ", ".join(items) for kind, items in groups.items())


def status_text(element: ElementView) -> str:
    text = element.state if not element.reason else f"{element.state}: {element.reason}"
    if element.note:
        text += f" (VR Juggler would leave it pending: {element.note})"
    return text


def difference_lines(snapshot: Snapshot) -> list[str]:
    """One line per element gadgetctl runs but VR Juggler would leave pending."""
    return [f"note: {e.name}: {status_text(e)}" for e in snapshot.elements if e.note]


# --------------------------------------------------------------------------- the table


COLUMNS = (
    "NAME",
    "KIND",
    "TYPE",
    "STATUS",
    "RATE Hz",
    "/FRAME",
    "DROPPED",
    "AGE ms",
    "JITTER ms",
    "VALUES",
)


#: Driver counters of traffic, not of trouble: left out of the health summary.
THROUGHPUT = frozenset(
    {
        "datagrams",
        "decoded",
        "packets",
        "frames",
        "records",
        "polls",
        "other_messages",
        "requests",
        "replies",
        "messages",
        "lobs_sent",
        "connects",
    }
)
#: Health fields shown elsewhere (the dropped column) or formatted with another.
_SHOWN_ELSEWHERE = frozenset({"dropped", "last_fault", "last_fault_at"})


def health_text(health: Mapping[str, Any]) -> str:
    """The trouble a driver counted (non-zero counters, faults and reconnects over the
    device's life) and its last fault with its time; empty when all is well."""
    import time

    parts = [
        f"{name} {value:g}"
        for name, value in health.items()
        if name not in THROUGHPUT
        and name not in _SHOWN_ELSEWHERE
        and isinstance(value, int | float)
        and value
    ]
    reason = health.get("last_fault")
    if reason:
        at = health.get("last_fault_at")
        when = (
            time.strftime("%H:%M:%S", time.localtime(at)) + " "
            if isinstance(at, int | float)
            else ""
        )
        parts.append(f"last fault {when}{reason}")
    return ", ".join(parts)


def table_rows(
    snapshot: Snapshot,
    *,
    length_unit: str = "meters",
    quaternion: bool = False,
    pose: str | None = None,
    positions: PositionTexts | None = None,
) -> list[list[str]]:
    rows = []
    for element in snapshot.elements:
        stats = element.stats
        own = element.element == "device"
        target = ""
        if element.target:
            target = f" -> {element.target}" + (
                f"[{element.unit}]"
                if element.unit is not None and element.element == "proxy"
                else ""
            )
        rows.append(
            [
                element.name,
                element.element,
                element.type + target,
                element.state,
                rate_text(stats.window_rate) if stats else "-",
                per_frame_text(stats) if own else "",
                str(stats.dropped) if stats and own else ("-" if own else ""),
                ms_text(element.age) if element.age is not None else "-",
                ms_text(stats.jitter) if stats and own else ("-" if own else ""),
                values_text(
                    element,
                    length_unit=length_unit,
                    quaternion=quaternion,
                    pose=pose,
                    positions=positions,
                )
                + (f"  [{element.reason}]" if element.reason else "")
                + (f"  health: {health}" if (health := health_text(element.health)) else ""),
            ]
        )
    return rows


def format_table(
    header: Sequence[str], rows: Sequence[Sequence[str]], *, last_free: bool = True
) -> str:
    """``rows`` under ``header`` in aligned columns (the last one unpadded with
    ``last_free``)."""
    return "\n".join(table_lines(header, rows, last_free=last_free))


def table_lines(
    header: Sequence[str],
    rows: Sequence[Sequence[str]],
    *,
    last_free: bool = True,
    consume: bool = False,
) -> Iterator[str]:
    """The lines of :func:`format_table`, made one at a time. With ``consume``, ``rows`` is
    a list given up to this call: its cells are made printable in place and each row is
    dropped once its line is made (the rows of 20,000 elements are 12 MB; a copy of them,
    their lines and the text of the whole table at once were as much again)."""
    table: list[Sequence[str]]
    if consume:
        table = rows if isinstance(rows, list) else list(rows)
        for index, row in enumerate(table):
            table[index] = [printable(cell) for cell in row]
    else:
        table = [[printable(cell) for cell in row] for row in rows]  # names and values from devices
    widths = [len(h) for h in header]
    for row in table:
        for i, cell in enumerate(row[:-1] if last_free else row):
            widths[i] = max(widths[i], len(cell))

    def line(row: Sequence[str]) -> str:
        cells = [
            cell.ljust(widths[i]) if i < len(row) - 1 or not last_free else cell
            for i, cell in enumerate(row)
        ]
        return "  ".join(cells).rstrip()

    return _lines(line, list(header), table, consume)


def _lines(
    line: Callable[[Sequence[str]], str],
    header: Sequence[str],
    table: list[Sequence[str]],
    consume: bool,
) -> Iterator[str]:
    yield line(header)
    for index, row in enumerate(table):
        if consume:
            table[index] = ()  # its line is made
        yield line(row)


#: Between the cells of a packed row (:class:`PackedRows`): :func:`printable` leaves no
#: control character in a cell.
_CELL = "\x00"


class PackedRows:
    """The rows of :func:`table_lines` with ``consume``, kept as one string each until their
    lines are made: each row's cells made printable and joined by :data:`_CELL`, the
    columns' widths taken as rows are added. The rows of 20,000 elements as lists of ten
    strings were about 13 MB at once; as one string each, about a third of it. Rows have at
    least one cell."""

    def __init__(self, header: Sequence[str], *, last_free: bool = True) -> None:
        self.header = list(header)
        self.last_free = last_free
        self.widths = [len(h) for h in header]
        self.rows: list[str] = []

    def add(self, rows: Iterable[Sequence[str]]) -> None:
        widths = self.widths
        last_free = self.last_free
        append = self.rows.append
        for row in rows:
            # most rows need no escape: one search of the row, not one per cell
            cells = row if is_printable("".join(row)) else [printable(c) for c in row]
            for i, cell in enumerate(cells[:-1] if last_free else cells):
                if len(cell) > widths[i]:
                    widths[i] = len(cell)
            append(_CELL.join(cells))

    def lines(self) -> Iterator[str]:
        """The header's line, then each row's; a row is dropped once its line is made."""
        widths, last_free = self.widths, self.last_free

        def line(row: Sequence[str]) -> str:
            cells = [
                cell.ljust(widths[i]) if i < len(row) - 1 or not last_free else cell
                for i, cell in enumerate(row)
            ]
            return "  ".join(cells).rstrip()

        yield line(self.header)
        rows = self.rows
        for index, packed in enumerate(rows):
            rows[index] = ""  # its line is made
            yield line(packed.split(_CELL))
        rows.clear()


def snapshot_table(
    snapshot: Snapshot,
    *,
    length_unit: str = "meters",
    quaternion: bool = False,
    pose: str | None = None,
) -> str:
    head = table_head(snapshot)
    rows = table_rows(snapshot, length_unit=length_unit, quaternion=quaternion, pose=pose)
    body = format_table(COLUMNS, rows)
    return head + "\n" + body + "\n" + "".join(f"{line}\n" for line in difference_lines(snapshot))


def table_head(snapshot: Snapshot) -> str:
    """The heading line of a table of ``snapshot``."""
    return (
        f"[{snapshot.elapsed:7.2f} s] frame {snapshot.frame}, {snapshot.frame_rate:.1f} frames/s"
        + (
            f", {counted(snapshot.samples_written, 'sample')} written"
            if snapshot.samples_written
            else ""
        )
    )


#: Lines of a table that are not element rows: the heading, the column names, the line
#: saying what was left out, and the blank line after it.
TABLE_CHROME = 4
#: Elements whose views are made at once for a table: their rows are kept, not their views
#: (the views of 10,000 devices and their proxies at once were about 30 MB).
TABLE_CHUNK = 1000


class TableView:
    """Prints a plain-text table of every selected element every ``interval`` seconds (on a
    terminal, the rows its height leaves room for)."""

    def __init__(
        self,
        session: MonitorSession,
        stream: TextIO,
        *,
        interval: float = 1.0,
        length_unit: str = "meters",
        quaternion: bool = False,
        pose: str | None = None,
    ) -> None:
        self.session = session
        self.pose = pose
        self.stream = stream
        self.interval = interval
        self.length_unit = length_unit
        self.quaternion = quaternion
        self._next: float | None = None

    def frame(self, elapsed: float) -> None:
        if self._next is None:
            self._next = self.interval
        if elapsed >= self._next:
            self._next += self.interval * max(
                1, math.floor((elapsed - self._next) / self.interval) + 1
            )
            self.print()

    def print(self) -> None:
        selected = self.session.selected
        fit = self.rows_that_fit(len(selected))
        names = selected[:fit]
        # one instant for every row, as one snapshot of them all has: the latest frame's
        # (what came after it was not read: later, slow frames made devices look slow)
        moment = self.session.last_look
        rows = PackedRows(COLUMNS)
        positions = PositionTexts(self.length_unit, self.quaternion, self.pose)
        notes: list[str] = []
        snapshots = (
            self.session.snapshot(moment, names=names[start : start + TABLE_CHUNK])
            for start in range(0, max(1, len(names)), TABLE_CHUNK)
        )
        first = next(snapshots)  # its heading is the table's
        for snapshot in itertools.chain((first,), snapshots):
            rows.add(
                table_rows(
                    snapshot,
                    length_unit=self.length_unit,
                    quaternion=self.quaternion,
                    pose=self.pose,
                    positions=positions,
                )
            )
            notes += difference_lines(snapshot)
        # what snapshot_table makes, written a part at a time: the rows are dropped as their
        # lines are made, and the text of the whole table is never made at once
        write = self.stream.write
        write(table_head(first) + "\n")
        lines = rows.lines()
        del rows
        for part in iter(lambda: list(itertools.islice(lines, TABLE_CHUNK)), []):
            write("".join(f"{line}\n" for line in part))
        text = "".join(f"{line}\n" for line in notes)
        if fit < len(selected):
            text += (
                f"… and {counted(len(selected) - fit, 'more element')} the terminal has no room "
                "for (name or pattern them to see them; a pipe or file gets every row)\n"
            )
        write(text + "\n")
        self.stream.flush()

    def rows_that_fit(self, count: int) -> int:
        """How many of ``count`` rows a table printed to a terminal shows: as many as its
        height leaves (a table of 10,000 rows no terminal shows cost more than the run
        itself); a pipe or a file gets them all."""
        isatty = getattr(self.stream, "isatty", None)
        if isatty is None or not isatty():
            return count
        import shutil

        room = shutil.get_terminal_size().lines - TABLE_CHROME
        return count if count <= room else max(1, room)


# --------------------------------------------------------------------------- statistics


STATS_COLUMNS = (
    "DEVICE",
    "STATE",
    "SAMPLES",
    "MEAN Hz",
    "P50 ms",
    "P99 ms",
    "MAX GAP ms",
    "JITTER ms",
    "DROPPED",
    "FAULTS",
)


def frames_text(session: Any) -> str:
    """The frames a session ran: how many, over how long, at what rate against the requested."""
    return (
        f"frames: {session.frames_run} in {session.run_seconds:.3f} s, "
        f"{session.achieved_rate:.1f} Hz achieved of {session.rate:g} Hz requested\n"
    )


#: The columns of the statistics left out first when a terminal is too narrow for all.
STATS_LEFT_OUT = ("P50 ms", "JITTER ms", "MAX GAP ms", "FAULTS", "P99 ms")


def stats_text(stats: Mapping[str, Mapping[str, Any]], width: int | None = None) -> str:
    """The end-of-run statistics of each device (``MonitorSession.final_stats``); with
    ``width`` (a terminal's), columns are left out whole, as STATS_LEFT_OUT orders them, until
    the table fits instead of wrapping, and a line says which."""
    if not stats:
        return "statistics: no device was monitored\n"
    rows = []
    for name, s in stats.items():
        rows.append(
            [
                name,
                str(s.get("state", "-")),
                str(s.get("samples", s.get("count", 0))),
                rate_text(s.get("mean_rate")),
                ms_text(s.get("p50_interval")),
                ms_text(s.get("p99_interval")),
                ms_text(s.get("max_gap")),
                ms_text(s.get("jitter")),
                str(s.get("dropped", 0)),
                str(s.get("faults", 0)),
            ]
        )
    lines = []
    for name, s in stats.items():
        clock = s.get("source_clock")
        if isinstance(clock, Mapping) and clock.get("offset") is not None:
            lines.append(
                f"{name}: arrival minus the source's timestamp: least {clock['offset'] * 1000:+.3f} ms "
                f"(clock offset plus the least transport latency), on average "
                f"{ms_text(clock.get('latency'))} ms more (transport and queueing), "
                f"over {counted(clock.get('samples') or 0, 'timestamp')}"
            )
    extra = "".join(line + "\n" for line in lines)
    header = list(STATS_COLUMNS)
    table = format_table(header, rows, last_free=False)
    left_out: list[str] = []
    for column in STATS_LEFT_OUT:
        if width is None or max(map(len, table.splitlines())) <= width:
            break
        index = header.index(column)
        header.pop(index)
        rows = [row[:index] + row[index + 1 :] for row in rows]
        left_out.append(column)
        table = format_table(header, rows, last_free=False)
    if left_out:
        table += f"\n(left out to fit {width} columns: {', '.join(left_out)})"
    return "statistics:\n" + table + "\n" + extra


def summary_text(summary: Any) -> str:
    """A recording summary (``gadgetctl replay --summary``)."""
    lines = [
        f"{printable(str(summary.path))}: {counted(summary.samples, 'sample')} from "
        f"{counted(len(summary.devices), 'device')} over "
        f"{summary.duration:.3f} s"
        + (f", {counted(summary.frames, 'frame')}" if summary.frames else "")
        + f"; ended: {summary.end_reason or 'cut off (no end record)'}"
    ]
    if summary.created:
        lines.append(f"created {printable(str(summary.created))}")
    start = summary.first_timestamp
    for marker in summary.markers:
        offset = "" if start is None else f" at {marker.timestamp - start:.3f} s"
        lines.append(f"marker {printable(repr(marker.name))}{offset}")
    for device in summary.devices:
        median = ms_text(device.median_interval)
        largest = ms_text(device.max_interval)
        gaps = device.gaps
        gap_text = (
            f"{counted(gaps.count, 'gap')} > {ms_text(gaps.threshold)} ms, largest {ms_text(gaps.largest)} ms"
            if gaps.count
            else "no gaps"
        )
        lines.append(
            f"{printable(device.name)}: {counted(device.updates, 'update')}, {counted(device.samples, 'sample')}, "
            f"{device.mean_rate:.1f} Hz over {device.duration:.3f} s, interval median {median} ms, "
            f"max {largest} ms, {gap_text}"
        )
        for unit in device.units:
            lines.extend(_unit_summary_lines(unit))
    for problem in summary.problems:
        lines.append(printable(f"{problem}"))
    return "\n".join(lines) + "\n"


def _unit_summary_lines(unit: Any) -> list[str]:
    """One unit of a recording summary: its range and sparkline; positions one line per
    axis (range and sparkline) and a line of rotation ranges."""
    head = f"    {printable(str(unit.kind))} {unit.unit}: {counted(unit.samples, 'sample')}"
    if unit.kind == "position":
        if unit.translation_min is None or unit.translation_max is None:
            return [head + ", range -"]
        lines = [head]
        sparks = unit.sparklines or {}
        for axis, (lo, hi) in enumerate(
            zip(unit.translation_min, unit.translation_max, strict=True)
        ):
            name = "xyz"[axis]
            spark = f"  {sparks[name]}" if sparks.get(name) else ""
            lines.append(f"      {name} {fixed(lo, 3, True)}..{fixed(hi, 3, True)} m{spark}")
        if unit.rotation_min is not None and unit.rotation_max is not None:
            turns = " ".join(
                f"{'xyz'[i]} {lo:+.1f}..{hi:+.1f}"
                for i, (lo, hi) in enumerate(zip(unit.rotation_min, unit.rotation_max, strict=True))
            )
            turn = f", turned up to {unit.turn:.1f} from the first" if unit.turn is not None else ""
            lines.append(f"      rotation (Euler XYZ, degrees) {turns}{turn}")
        return lines
    if unit.minimum is not None and unit.maximum is not None:
        span = f"{unit.minimum:.4g}..{unit.maximum:.4g}"
    else:
        span = "-"
    spark = f"  {unit.sparkline}" if unit.sparkline else ""
    return [f"{head}, range {span}{spark}"]


def problem_elements(snapshot: Snapshot) -> list[ElementView]:
    """Elements that end the run in a bad state (pending, faulted, stupefied...)."""
    return [e for e in snapshot.elements if e.state in BAD_STATES]


def problem_lines(snapshot: Snapshot) -> list[str]:
    """One line per cause: each element in a bad state with its reason, except the proxies
    and aliases stupefied only because a device shown with its own reason is not running,
    which that device's line counts."""
    problems = problem_elements(snapshot)
    shown = {e.name for e in problems}
    followers: dict[str, int] = {}
    alone: list[ElementView] = []
    for element in problems:
        device = element.blocked_by
        if device is None or device not in shown:
            alone.append(element)
        else:
            followers[device] = followers.get(device, 0) + 1
    lines = []
    for element in alone:
        line = f"{element.name}: {status_text(element)}"
        count = followers.get(element.name)
        if count:
            line += (
                f" ({counted(count, 'proxy or alias', 'proxies and aliases')} reading it stupefied)"
            )
        lines.append(line)
    return lines
