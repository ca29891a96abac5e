"""The live dashboard of `gadgetctl monitor`: one block per device, one line per proxy
and alias, drawn from :class:`~gadgetctl.monitor.session.MonitorSession` snapshots.

Lines are lists of (text, style) segments; rich turns the styles into escape codes for the
console's colour system (none with NO_COLOR or ``--color never`` consoles) and measures
cells. The screen is redrawn in place on the alternate screen, one write per refresh, and
only the lines that fit are built, so a refresh costs the same for 3 devices or 300;
PgUp and PgDn scroll.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Iterable, Sequence

from rich.cells import cell_len, set_cell_size
from rich.color import ColorSystem
from rich.console import Console
from rich.style import Style

from gadgetctl.cli.monitor_text import (
    age_text,
    glove_parts,
    health_text,
    ms_text,
    position_text,
    rate_text,
    unit_value_text,
)
from gadgetctl.input.clock import now
from gadgetctl.monitor.events import number_text
from gadgetctl.monitor.session import MonitorSession
from gadgetctl.monitor.sparkline import sparkline
from gadgetctl.monitor.views import ElementView, UnitView
from gadgetctl.safetext import fixed, printable

BAR_WIDTH = 16
SPARK_WIDTH = 20
SPARK_REFRESH = 0.1  # seconds a sparkline is reused
EIGHTHS = " ▏▎▍▌▋▊▉"
STATE_STYLES = {
    "running": "green",
    "active": "green",
    "configured": "cyan",
    "faulted": "bold red",
    "undecodable": "bold red",
    "reconnecting": "yellow",
    "pending": "yellow",
    "unknown type": "dim",
    "stupefied": "yellow",
    "stopped": "red",
    "removed": "red",
}
HEADER_LINES = 3
COMPACT = 2  # the compact layout shows segments of priority up to this
DETAILED = 9  # the detailed layout: everything that fits
NAME_WIDTH = 24  # the least width of the name column
NAME_WIDTH_MAX = 44  # longer names are cut with "…" so that the columns stay in line
TYPE_WIDTH = 28
REASON_INDENT = "      "
REASON_LINES = 3  # a reason longer than this many screen lines ends in "…"
_SYSTEMS = {
    "standard": ColorSystem.STANDARD,
    "256": ColorSystem.EIGHT_BIT,
    "truecolor": ColorSystem.TRUECOLOR,
    "windows": ColorSystem.WINDOWS,
}


def bar(value: float, width: int = BAR_WIDTH) -> str:
    """A horizontal bar for a value in [0, 1], with eighth-cell resolution."""
    if not math.isfinite(value):
        return "?" * width
    cells = max(0.0, min(1.0, value)) * width
    full = int(cells)
    rest = int((cells - full) * 8)
    text = "█" * full + (EIGHTHS[rest] if full < width and rest else "")
    return text + "·" * (width - len(text))


class Line(list):
    """A screen line: (text, style) segments, each with a priority for narrow terminals
    (0: always shown; the higher, the sooner it is left out, see :meth:`fit`)."""

    def __init__(self, *args: object) -> None:
        super().__init__(*args)
        self.priorities: list[int] = [0] * len(self)

    def add(self, text: str, style: str = "", priority: int = 0) -> Line:
        self.append(
            (printable(text), style)
        )  # names, values and reasons come from devices and files
        self.priorities.append(priority)
        return self

    def fit(self, width: int, most: int = DETAILED) -> Line:
        """The line without segments of priority above ``most``, then without the least
        important ones (the rightmost first among equals) until it fits ``width`` cells."""
        keep = [i for i, p in enumerate(self.priorities) if p <= most]
        size = sum(cell_len(self[i][0]) for i in keep)
        for level in sorted(
            {self.priorities[i] for i in keep if self.priorities[i] > 0}, reverse=True
        ):
            if size <= width:
                break
            for i in reversed([i for i in keep if self.priorities[i] == level]):
                if size <= width:
                    break
                keep.remove(i)
                size -= cell_len(self[i][0])
        # What the removals left room for comes back, the most important first: a glove's
        # fingers give way to the type column, and return where the column left anyway.
        allowed = [i for i, p in enumerate(self.priorities) if p <= most]
        for i in sorted(set(allowed) - set(keep), key=lambda i: (self.priorities[i], i)):
            extra = cell_len(self[i][0])
            if size + extra <= width:
                keep.append(i)
                size += extra
        keep.sort()
        fitted = Line()
        for i in keep:
            fitted.add(self[i][0], self[i][1], self.priorities[i])
        return fitted

    @property
    def plain(self) -> str:
        return "".join(text for text, _ in self)


class Screen:
    """Full-screen output on the alternate screen of ``console``'s terminal."""

    def __init__(self, console: Console) -> None:
        self.console = console
        self.file = console.file
        system = None if console.no_color else console.color_system
        self._system = _SYSTEMS.get(system) if system else None
        self._codes: dict[str, tuple[str, str]] = {}
        self.active = False

    def __enter__(self) -> Screen:
        self.file.write("\x1b[?1049h\x1b[?25l\x1b[H\x1b[2J")
        self.file.flush()
        self.active = True
        return self

    def __exit__(self, *exc: object) -> None:
        if self.active:
            self.active = False
            self.file.write("\x1b[0m\x1b[?25h\x1b[?1049l")
            self.file.flush()

    def _style(self, style: str) -> tuple[str, str]:
        codes = self._codes.get(style)
        if codes is None:
            if self._system is None or not style:
                codes = ("", "")
            else:
                before, _, after = (
                    Style.parse(style).render("\0", color_system=self._system).partition("\0")
                )
                codes = (before, after)
            self._codes[style] = codes
        return codes

    def draw(self, lines: Iterable[Line], width: int, height: int) -> None:
        out = ["\x1b[H"]
        for count, line in enumerate(lines):
            if count >= height:
                break
            if count:
                out.append("\x1b[K\r\n")
            used = 0
            for text, style in line:
                if used >= width:
                    break
                size = cell_len(text)
                if used + size > width:
                    text = set_cell_size(text, width - used)
                    size = width - used
                used += size
                before, after = self._style(style)
                out.append(before + text + after if before else text)
        out.append("\x1b[K\x1b[J")
        self.file.write("".join(out))
        self.file.flush()


class LiveView:
    """Draws the dashboard of ``session`` on ``console``'s terminal."""

    def __init__(
        self,
        session: MonitorSession,
        console: Console,
        *,
        title: str = "",
        length_unit: str = "meters",
        quaternion: bool = False,
        recording: str | None = None,
        heading: str = "gadgetctl monitor",
    ) -> None:
        self.session = session
        self.console = console
        self.title = title
        self.length_unit = length_unit
        self.quaternion = quaternion
        self.recording = recording
        self.heading = heading
        self.paused = False
        self.offset = 0
        self.prompt: str | None = None
        self.focus: str | None = None  # the keyboard_mouse_device that gets the keys
        self.compact = False  # v switches between the compact and the detailed layout
        self.message = ""
        self.total_lines = 0
        self.screen = Screen(console)
        self.width = 200  # of the screen being rendered: reasons are wrapped to it
        self.name_width = NAME_WIDTH  # the name column, wide enough for the longest name
        self._names: tuple[str, ...] = ()  # the selection name_width was measured for
        self._sparks: dict[int, tuple[float, str]] = {}

    # -- lifecycle ----------------------------------------------------------------------

    def __enter__(self) -> LiveView:
        self.screen.__enter__()
        return self

    def __exit__(self, *exc: object) -> None:
        self.screen.__exit__(*exc)

    def draw(self, *, force: bool = False) -> None:
        if self.paused and not force:
            return
        width, height = self.console.size
        self.screen.draw(self.render(width, height), width, height)

    def scroll(self, pages: int) -> None:
        step = max(1, self.console.size.height - HEADER_LINES - 1)
        self.offset = max(0, min(self.offset + pages * step, max(0, self.total_lines - step)))
        self.draw(force=True)

    # -- rendering ----------------------------------------------------------------------

    def render(self, width: int, height: int) -> list[Line]:
        """The screen's lines (at most ``height``)."""
        moment = now()
        session = self.session
        self.width = width
        lines = self._header(moment)
        budget = max(1, height - HEADER_LINES - 1)
        names = session.selected
        key = tuple(names)
        if key != self._names:  # measured again only when the selection changes
            self._names = key
            longest = max((cell_len(printable(name)) for name in names), default=0)
            self.name_width = max(NAME_WIDTH, min(NAME_WIDTH_MAX, longest + 2))
        line_no = shown = 0
        index = len(names)
        for position, name in enumerate(names):
            if shown >= budget:
                index = position
                break
            most = COMPACT if self.compact else DETAILED
            for line in self._element_lines(session.element_view(name, moment)):
                if line_no >= self.offset and shown < budget:
                    lines.append(line.fit(width, most))
                    shown += 1
                line_no += 1
        self.total_lines = line_no + (len(names) - index)
        below = len(names) - index
        if below:
            lines.append(
                Line().add(
                    f"… {below} more below; PgUp/PgDn scroll, NAME patterns narrow the view", "dim"
                )
            )
        elif self.offset:
            lines.append(Line().add("(scrolled: PgUp goes back)", "dim"))
        return lines

    def text(self, width: int = 200, height: int = 50) -> str:
        """The screen as plain text (tests)."""
        return "\n".join(line.plain for line in self.render(width, height))

    def _header(self, moment: float) -> list[Line]:
        session = self.session
        first = Line().add(self.heading, "bold")
        if self.title:
            first.add(f"  {self.title}")
        first.add(
            f"  frame {session.frame}  {session.frame_rate:.0f} fps  "
            f"{moment - (session.started_at or moment):.1f} s"
        )
        if self.recording:
            first.add(f"  recording {self.recording}", "red")
        if session.finished:
            first.add("  FINISHED (q quits)", "bold cyan")
        if self.paused:
            first.add("  PAUSED (sampling goes on)", "bold yellow")
        keyboards = session.keyboards()
        layout = "detailed" if self.compact else "compact"
        second = Line().add("q quit  p pause  ", "dim").add("r reset stats  m marker  ", "dim", 1)
        second.add(f"v {layout}  ", "dim", 1).add("PgUp/PgDn scroll  ", "dim", 2)
        if keyboards:
            second.add("other keys and the mouse → ", "dim").add(self.focus or keyboards[0], "bold")
            if len(keyboards) > 1:
                second.add(f"  (Tab: next of {len(keyboards)} keyboards)", "dim", 1)
        else:
            second.add("(no keyboard_mouse_device: other keys are ignored)", "dim")
        third = Line()
        if self.prompt is not None:
            third.add(f"marker name (Enter to write, Esc to cancel): {self.prompt}▏", "bold")
        elif self.message:
            third.add(self.message, "cyan")
        width = self.console.size.width
        return [first, second.fit(width), third]

    def _element_lines(self, view: ElementView) -> list[Line]:
        if view.element == "device":
            return self._device_lines(view)
        line = Line().add("  ").add(self._name(view.name, self.name_width - 2), "bold").add(" ")
        if view.element == "alias":
            target = f"alias → {view.target or '?'}"
        elif view.element == "proxy":
            unit = f"[{view.unit}]" if view.unit is not None else ""
            target = f"{view.type} → {view.target or '?'}{unit}"
        else:
            target = view.type
        line.add(f"{target:<40} ", "dim", 3)
        style = STATE_STYLES.get(view.state, "")
        line.add(f"{view.state:<12}", style)
        if view.blocked_by:
            line.add(f" see {view.blocked_by}", style)
        if view.note:
            line.add(" (VR Juggler would leave it pending)", "dim", 4)
        for unit in view.values:
            line.add(" ")
            self._unit(line, unit, view.element)
        if view.reason and not view.blocked_by:
            return [line, *self._reason_lines(view.reason, style)]
        return [line]

    @staticmethod
    def _name(name: str, width: int) -> str:
        """``name`` in a column of ``width`` cells: padded, or cut with "…" when longer."""
        text = printable(name)
        if cell_len(text) > width:
            return set_cell_size(text, width - 1) + "…"
        return set_cell_size(text, width)

    def _reason_lines(self, reason: str, style: str) -> list[Line]:
        """``reason`` under its element, wrapped to the screen (at most REASON_LINES lines):
        why a device is pending, faulted or reconnecting shows at any width."""
        room = max(20, self.width - len(REASON_INDENT))
        wrapped = textwrap.wrap(printable(reason), room, break_on_hyphens=False) or [""]
        if len(wrapped) > REASON_LINES:
            wrapped = wrapped[:REASON_LINES]
            wrapped[-1] = wrapped[-1][: room - 1] + "…"
        return [Line().add(REASON_INDENT + part, style or "red") for part in wrapped]

    def _device_lines(self, view: ElementView) -> list[Line]:
        head = (
            Line()
            .add(self._name(view.name, self.name_width), "bold cyan")
            .add(f" {view.type:<{TYPE_WIDTH}}", "dim", 3)
        )
        head.add(f" {view.state:<12}", STATE_STYLES.get(view.state, ""))
        stats = view.stats
        if stats is not None:
            spf = stats.window_samples_per_frame  # over the window of the rate beside it
            if spf is None:
                spf = stats.mean_samples_per_frame
            head.add(f" {rate_text(stats.window_rate):>8} Hz")
            head.add(f"  {'-' if spf is None else f'{spf:.1f}':>5}/frame", "", 3)
            head.add(
                f"  dropped {stats.dropped:<3}",
                "red" if stats.dropped else "",
                1 if stats.dropped else 2,
            )
            health = health_text(view.health)  # faults and reconnects included
            if health:
                head.add(f"  health: {health}", "yellow", 1)
            head.add(f"  age {age_text(view.age):>9}", "", 2)
            head.add(f"  jitter {ms_text(stats.jitter):>6} ms", "", 4)
            head.add(f"  p99 {ms_text(stats.p99_interval):>6} ms", "", 5)
            head.add(f"  max gap {ms_text(stats.max_gap):>6} ms", "", 5)
        lines = [head]
        if view.reason:
            lines.extend(self._reason_lines(view.reason, STATE_STYLES.get(view.state, "red")))
        digital = []
        for unit in view.values:
            if unit.kind == "digital":
                digital.append(unit)
                continue
            line = Line().add(f"    {unit.kind} {unit.unit:<3}", "dim")
            self._unit(line, unit, "device")
            lines.append(line)
        if digital:
            line = Line().add("    digital    ", "dim")
            for unit in digital:
                line.add(f"{unit.unit}:", "dim")
                self._button(line, unit, "device")
            lines.append(line)
        return lines

    def _button(self, line: Line, unit: UnitView, element: str) -> None:
        if element == "device":
            on = bool(unit.value)
            line.add("●" if on else "○", "bold green" if on else "")
            line.add("↕" if unit.changed else " ", "yellow")
        else:
            state = int(unit.value)
            on = state in (1, 2)
            line.add("●" if on else "○", "bold green" if on else "")
            line.add({2: "↑", 3: "↓"}.get(state, " "), "yellow")
        line.add(f"×{unit.presses}  " if unit.presses else "  ", "dim")  # noqa: RUF001

    def _spark(self, history: Sequence[float], moment: float) -> str:
        """The sparkline of a unit's history, recomputed at most every SPARK_REFRESH s."""
        cached = self._sparks.get(id(history))
        if cached is not None and moment - cached[0] < SPARK_REFRESH:
            return cached[1]
        text = sparkline(list(history), SPARK_WIDTH, lo=0.0, hi=1.0)
        self._sparks[id(history)] = (moment, text)
        return text

    def _unit(self, line: Line, unit: UnitView, element: str) -> None:
        kind = unit.kind
        if kind == "analog":
            value = float(unit.value)
            line.add(bar(value), "blue", 3).add(f" {fixed(value, 3):>6}")
            if unit.raw is not None:
                line.add(f" raw {number_text(unit.raw):<9}", "dim", 2)
            if unit.history:
                line.add(" " + self._spark(unit.history, now()), "magenta", 4)
        elif kind == "digital":
            self._button(line, unit, element)
        elif kind == "position":
            translation, _, rest = position_text(
                unit.value, self.length_unit, self.quaternion
            ).partition("  rot")
            line.add(translation)
            if rest:
                rotation, _, quaternion = rest.partition("  q ")
                line.add("  rot" + rotation, "", 4)  # after the type, as docs/monitor.md says
                if quaternion:
                    line.add("  q " + quaternion, "", 5)
        elif kind == "glove":
            for index, finger in enumerate(glove_parts(unit.value)):  # left out whole, never cut
                line.add(("" if index == 0 else " ") + finger, "", 0 if index == 0 else 4)
        else:
            line.add(unit_value_text(unit, element=element, length_unit=self.length_unit))
