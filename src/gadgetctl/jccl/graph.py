"""The wiring of a configuration, behind `gadgetctl config graph`: aliases to proxies to
devices to the driver plug-ins the input manager loads, with every other pointer and the
embedded elements of the elements shown.

Rendered as a text tree, Graphviz DOT or a Mermaid flowchart. Which element types are
built in and which plug-in handles the others is the input manager's knowledge: the caller
passes it in (``gadgetctl.input.plugins.catalog``), so the JCCL layer does not depend on
the input layer.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from gadgetctl.jccl.configuration import ConfigElement, Configuration
from gadgetctl.jccl.definitions import ValueType
from gadgetctl.jccl.resolve import judged_view
from gadgetctl.jccl.typeindex import TypeIndex
from gadgetctl.perf import collector_paused
from gadgetctl.safetext import printable
from gadgetctl.wording import counted

POINTER, CONTAINS, DRIVER, HANDLED_BY = "pointer", "contains", "driver", "handled_by"
MAX_TEXT_DEPTH = 64  # levels of a text tree before a chain goes on as a tree of its own


@dataclass
class Node:
    id: str
    kind: str  # alias, proxy, device, input_manager, element, plugin, missing
    type: str
    name: str
    note: str | None = None
    element: ConfigElement | None = field(default=None, repr=False)

    @property
    def short_name(self) -> str:
        """The element's own name (``name`` is the full name of embedded elements)."""
        return self.element.name if self.element is not None else self.name

    def to_dict(self) -> dict[str, object]:
        data: dict[str, object] = {
            "id": self.id,
            "kind": self.kind,
            "type": self.type,
            "name": self.name,
        }
        if self.note:
            data["note"] = self.note
        if self.element is not None:
            data["file"] = self.element.location.path
            data["line"] = self.element.location.line
        return data


@dataclass(frozen=True)
class Edge:
    source: str
    target: str
    kind: str
    label: str

    def to_dict(self) -> dict[str, str]:
        return {"from": self.source, "to": self.target, "kind": self.kind, "label": self.label}


@dataclass
class WiringGraph:
    nodes: dict[str, Node] = field(default_factory=dict)
    edges: list[Edge] = field(default_factory=list)
    _outgoing: dict[str, list[Edge]] | None = field(default=None, repr=False, compare=False)
    _indexed: int = field(default=0, repr=False, compare=False)

    def outgoing(self, node_id: str) -> list[Edge]:
        """The edges leaving ``node_id``, in order (from an index made once per set of edges,
        not a scan of every edge per node)."""
        index = self._outgoing
        if index is None or self._indexed != len(self.edges):
            index = self._outgoing = {}
            for edge in self.edges:
                index.setdefault(edge.source, []).append(edge)
            self._indexed = len(self.edges)
        return list(index.get(node_id, ()))

    def to_dict(self) -> dict[str, object]:
        return {
            "nodes": [n.to_dict() for n in self.nodes.values()],
            "edges": [e.to_dict() for e in self.edges],
        }


class GraphBuilder:
    def __init__(
        self,
        config: Configuration,
        index: TypeIndex,
        built_in: frozenset[str] = frozenset(),
        plugins: Mapping[str, str] | None = None,
    ) -> None:
        self.config = config
        self.index = index
        self.built_in = built_in  # element types handled without a plug-in
        self.plugins = plugins or {}  # element type -> driver plug-in name
        self.graph = WiringGraph()
        self.ids: dict[int, str] = {}
        self.special_ids: dict[str, str] = {}
        self.by_name = {e.name: e for e in config.elements}
        self.embedded = {c.full_name: c for e in config.elements for c in e.embedded()}

    def kind(self, element: ConfigElement) -> str:
        if element.type == "alias":
            return "alias"
        if element.type == "input_manager":
            return "input_manager"
        if self.index.known(element.type) and self.index.is_a(element.type, "proxy"):
            return "proxy"
        if element.type in self.built_in or (
            self.index.known(element.type) and self.index.is_a(element.type, "input_device")
        ):
            return "device"
        return "element"

    def pointers(self, element: ConfigElement) -> list[tuple[str, str]]:
        view = judged_view(element, self.index)
        if view is None:
            return []
        return [
            (name, v.stripped)
            for name, values in element.properties.items()
            if (p := view.get(name)) is not None and p.valuetype is ValueType.POINTER
            for v in values
            if v.stripped and v.element is None
        ]

    def node(self, element: ConfigElement) -> str:
        node_id = self.ids.get(id(element))
        if node_id is None:
            node_id = self.ids[id(element)] = f"n{len(self.graph.nodes)}"
            self.graph.nodes[node_id] = Node(
                node_id, self.kind(element), element.type, element.full_name, element=element
            )
        return node_id

    def special(self, key: str, kind: str, type_name: str, name: str, note: str | None) -> str:
        node_id = self.special_ids.get(key)
        if node_id is None:
            node_id = self.special_ids[key] = f"n{len(self.graph.nodes)}"
            self.graph.nodes[node_id] = Node(node_id, kind, type_name, name, note)
        return node_id

    def build(self) -> WiringGraph:
        tops = self.config.elements
        pointed = {
            target for e in tops for c in (e, *e.embedded()) for _, target in self.pointers(c)
        }
        for element in tops:
            family = (element, *element.embedded())
            wanted = (
                self.kind(element) != "element"
                or element.name in pointed
                or any(self.pointers(c) or c.full_name in pointed for c in family)
            )
            if wanted:
                self.add_family(element)
        self.add_pointers()
        self.add_drivers()
        return self.graph

    def add_family(self, element: ConfigElement) -> None:
        parent = self.node(element)
        for prop, values in element.properties.items():
            for value in values:
                if value.element is not None:
                    child = self.node(value.element)
                    self.graph.edges.append(Edge(parent, child, CONTAINS, prop))
                    self.add_family(value.element)

    def add_pointers(self) -> None:
        for element_id, node_id in list(self.ids.items()):
            element = self.graph.nodes[node_id].element
            assert element is not None and id(element) == element_id
            for prop, target_name in self.pointers(element):
                target = self.by_name.get(target_name) or self.embedded.get(target_name)
                if target is None:
                    target_id = self.special(
                        f"missing:{target_name}",
                        "missing",
                        "?",
                        target_name,
                        "no element of the configuration has this name",
                    )
                else:
                    if id(target) not in self.ids:
                        self.add_family(target)
                    target_id = self.ids[id(target)]
                self.graph.edges.append(Edge(node_id, target_id, POINTER, prop))

    def add_drivers(self) -> None:
        loaded: dict[str, str] = {}
        for node in list(self.graph.nodes.values()):
            if node.kind == "input_manager" and node.element is not None:
                for value in node.element.values("driver"):
                    name = value.stripped
                    if name:
                        plugin = self.special(f"plugin:{name}", "plugin", "plug-in", name, None)
                        loaded[name] = plugin
                        self.graph.edges.append(Edge(node.id, plugin, DRIVER, "driver"))
        mapping = self.plugins
        for node in list(self.graph.nodes.values()):
            if node.kind != "device" or node.element is None:
                continue
            if node.type in self.built_in:
                node.note = "built in, no plug-in needed"
                continue
            name = mapping.get(node.type)
            if name is None:
                node.note = "no known driver plug-in handles this type"
                continue
            plugin = loaded.get(name) or self.special(
                f"plugin:{name}", "plugin", "plug-in", name, "not loaded by any input_manager"
            )
            self.graph.edges.append(Edge(node.id, plugin, HANDLED_BY, "handled by"))


def build_graph(
    config: Configuration,
    index: TypeIndex,
    *,
    built_in: frozenset[str] = frozenset(),
    plugins: Mapping[str, str] | None = None,
) -> WiringGraph:
    """The wiring of ``config``; ``built_in`` are the element types that need no plug-in,
    ``plugins`` maps the others to the plug-in that handles them."""
    with collector_paused():  # a node and edges for every element: no garbage cycles
        return GraphBuilder(config, index, built_in, plugins).build()


# -- rendering ---------------------------------------------------------------------------


def _title(node: Node) -> str:
    if node.kind == "plugin":
        return f"plug-in {node.name}"
    if node.kind == "missing":
        return f"missing {node.name!r}"
    return f"{node.type} {node.short_name!r}"


def render_text(graph: WiringGraph) -> str:
    """A tree per root (elements nothing points to), aliases first; shared nodes once."""
    incoming = {e.target for e in graph.edges if e.kind in (POINTER, CONTAINS, HANDLED_BY)}
    roots = [n for n in graph.nodes.values() if n.id not in incoming and n.kind != "plugin"]
    order = {"alias": 0, "proxy": 1, "device": 2, "element": 3, "input_manager": 4, "missing": 5}
    roots.sort(key=lambda n: order.get(n.kind, 9))
    out: list[str] = []
    shown: set[str] = set()
    verbs = {POINTER: "→", CONTAINS: "contains", DRIVER: "→", HANDLED_BY: "→"}

    def walk(root_id: str) -> None:
        """Depth first with an explicit stack: a chain of any length, no recursion limit."""
        stack: list[tuple[str, str, Edge | None, bool, int] | str] = [(root_id, "", None, True, 0)]
        while stack:
            entry = stack.pop()
            if isinstance(entry, str):  # a grouped line, already drawn
                out.append(entry)
                continue
            node_id, prefix, edge, last, depth = entry
            node = graph.nodes[node_id]
            text = _title(node) + (f"  [{node.note}]" if node.note else "")
            if edge is not None:
                text = f"{edge.label} {verbs[edge.kind]} {text}"
            children = graph.outgoing(node_id)
            repeat = node_id in shown and bool(children)
            branch = "" if edge is None else ("└── " if last else "├── ")
            out.append(f"{prefix}{branch}{text}{' (see above)' if repeat else ''}")
            if repeat:
                continue
            if depth >= MAX_TEXT_DEPTH and children:  # long chains go on as a tree of their own
                out[-1] += " (continued below)"
                continued.append(node_id)
                continue
            shown.add(node_id)
            inner = prefix if edge is None else prefix + ("    " if last else "│   ")
            items = _grouped(graph, children)
            for i in range(len(items) - 1, -1, -1):
                item, end = items[i], i == len(items) - 1
                if isinstance(item, str):
                    stack.append(f"{inner}{'└── ' if end else '├── '}{item}")
                else:
                    stack.append((item.target, inner, item, end, depth + 1))

    continued: list[str] = []
    for root in roots:
        walk(root.id)
        while continued:
            walk(continued.pop(0))
    for node in graph.nodes.values():  # cycles with no root
        if node.id not in shown and node.kind != "plugin":
            walk(node.id)
            while continued:
                walk(continued.pop(0))
    return "\n".join(map(printable, out))


def _grouped(graph: WiringGraph, edges: list[Edge]) -> list[Edge | str]:
    """Edges to show, with several embedded leaves of one property and type as one line."""
    leaves: dict[tuple[str, str], list[Edge]] = {}
    for edge in edges:
        if edge.kind == CONTAINS and not graph.outgoing(edge.target):
            leaves.setdefault((edge.label, graph.nodes[edge.target].type), []).append(edge)
    items: list[Edge | str] = []
    done: set[tuple[str, str]] = set()
    for edge in edges:
        key = (edge.label, graph.nodes[edge.target].type)
        group = leaves.get(key) if edge.kind == CONTAINS else None
        if group and len(group) > 1:
            if key not in done:
                done.add(key)
                items.append(f"{edge.label} contains {counted(len(group), key[1] + ' element')}")
        else:
            items.append(edge)
    return items


_DOT_SHAPES = {
    "alias": "ellipse",
    "proxy": "box",
    "device": "box3d",
    "input_manager": "component",
    "plugin": "folder",
    "missing": "octagon",
    "element": "note",
}


def _dot_string(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'


def render_dot(graph: WiringGraph) -> str:
    lines = [
        "digraph wiring {",
        "  rankdir=LR;",
        '  node [fontname="Helvetica", fontsize=10];',
        '  edge [fontname="Helvetica", fontsize=9];',
    ]
    for node in graph.nodes.values():
        label = (
            "plug-in\n" + printable(node.name)
            if node.kind == "plugin"
            else f"{printable(node.type)}\n{printable(node.short_name)}"
        )
        if node.note:
            label += f"\n({printable(node.note)})"
        attrs = [f"label={_dot_string(label)}", f"shape={_DOT_SHAPES.get(node.kind, 'box')}"]
        if node.kind == "missing":
            attrs += ["color=red", "fontcolor=red", "style=dashed"]
        lines.append(f"  {node.id} [{', '.join(attrs)}];")
    for edge in graph.edges:
        attrs = [f"label={_dot_string(printable(edge.label))}"]
        if edge.kind == CONTAINS:
            attrs += ["style=dashed", "arrowhead=diamond"]
        elif edge.kind == HANDLED_BY:
            attrs += ["style=dotted"]
        lines.append(f"  {edge.source} -> {edge.target} [{', '.join(attrs)}];")
    lines.append("}")
    return "\n".join(lines)


def _mermaid_text(text: str) -> str:
    return (
        printable(text)
        .replace('"', "#quot;")
        .replace("|", "#124;")
        .replace("<", "#lt;")
        .replace(">", "#gt;")
    )


def render_mermaid(graph: WiringGraph) -> str:
    shapes = {
        "alias": ('(["', '"])'),
        "proxy": ('["', '"]'),
        "device": ('[["', '"]]'),
        "input_manager": ('{{"', '"}}'),
        "plugin": ('[/"', '"/]'),
        "missing": ('{"', '"}'),
        "element": ('["', '"]'),
    }
    lines = ["flowchart LR"]
    for node in graph.nodes.values():
        head = "plug-in" if node.kind == "plugin" else node.type
        label = f"{_mermaid_text(head)}<br/>{_mermaid_text(node.short_name)}"
        if node.note:
            label += f"<br/><i>{_mermaid_text(node.note)}</i>"
        left, right = shapes.get(node.kind, ('["', '"]'))
        lines.append(f"  {node.id}{left}{label}{right}")
    for edge in graph.edges:
        arrow = "-.->" if edge.kind in (CONTAINS, HANDLED_BY) else "-->"
        lines.append(f"  {edge.source} {arrow}|{_mermaid_text(edge.label)}| {edge.target}")
    missing = [n.id for n in graph.nodes.values() if n.kind == "missing"]
    if missing:
        lines.append("  classDef missing stroke:#d00,color:#d00,stroke-dasharray:4")
        lines.append(f"  class {','.join(missing)} missing")
    return "\n".join(lines)


RENDERERS = {"text": render_text, "dot": render_dot, "mermaid": render_mermaid}
