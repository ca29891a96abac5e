"""The configuration model: element instances read from .jconf files."""

from __future__ import annotations

from collections.abc import Container, Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

from lxml import etree

from gadgetctl.diagnostics import Diagnostic
from gadgetctl.jccl.definitions import Location

EMBEDDED_SEPARATOR = "/"


class SourceLocation:
    """Where a node of a parsed document starts. Looking up the column costs a search of the
    source line, so line and column are found on first use only (most nodes never need them)."""

    __slots__ = ("_doc", "_found", "_node")

    def __init__(self, doc, node: etree._Element) -> None:
        self._doc = doc
        self._node = node
        self._found: tuple[int | None, int | None] | None = None

    def _locate(self) -> tuple[int | None, int | None]:
        if self._found is None:
            self._found = self._doc.locate(self._node)
        return self._found

    @property
    def path(self) -> str:
        return self._doc.path

    @property
    def line(self) -> int | None:
        return self._locate()[0]

    @property
    def column(self) -> int | None:
        return self._locate()[1]

    def resolved(self) -> Location:
        return Location(self.path, self.line, self.column)

    def __str__(self) -> str:
        return str(self.resolved())

    def __repr__(self) -> str:
        return f"SourceLocation({self})"


class TagLocation(SourceLocation):
    """Where a start tag without attributes (a property value) is, from its line, name and
    how many tags of that name come before it on that line. Keeps no reference to the
    parsed node, so that a large configuration does not pin one lxml proxy per value."""

    __slots__ = ("_index", "_line", "_local")

    def __init__(self, doc, line: int | None, local: str, index: int = 0) -> None:
        self._doc = doc
        self._node = None
        self._found = None
        self._line = line
        self._local = local
        self._index = index

    def _locate(self) -> tuple[int | None, int | None]:
        if self._found is None:
            self._found = self._doc.locate_tag(self._line, self._local, self._index)
        return self._found


#: Where a tag read from a document is: its line times _LINE_SPAN plus its rank among the
#: tags of its name on that line (see TagLocation), one int instead of a location object.
_LINE_SPAN = 1 << 32


class _Placed:
    """Something read from a tag of a document, or placed by its maker: ``_where`` holds a
    location, or (with ``_at``, a packed position) the document, and :attr:`location` is
    made when asked for (few of 200,000 elements and values ever are)."""

    __slots__ = ()

    def _tag(self) -> str:
        """The local name of the tag it was read from."""
        raise NotImplementedError

    @property
    def location(self) -> Location | SourceLocation:
        at = self._at  # type: ignore[attr-defined]
        if at is None:
            return self._where  # type: ignore[attr-defined]
        line, index = divmod(at, _LINE_SPAN)
        return TagLocation(self._where, line, self._tag(), index)  # type: ignore[attr-defined]

    @location.setter
    def location(self, location: Location | SourceLocation) -> None:
        self._where, self._at = location, None  # type: ignore[attr-defined]


_new = object.__new__


class PropertyValue(_Placed):
    """One value of a property: the text as written, or an embedded element.

    A value read from a document keeps the document and a packed position instead of a
    location object, and makes its :attr:`location` when asked (a configuration of
    200,000 elements has at least as many values, and few of them are ever reported)."""

    __slots__ = ("_at", "_local", "_where", "element", "text")

    def __init__(
        self,
        text: str,
        location: Location | SourceLocation | None = None,
        element: ConfigElement | None = None,
    ) -> None:
        self.text = text
        self.element = element
        self._where = location  # a location, or (with _at) the document
        self._at: int | None = None
        self._local: str | None = None

    @classmethod
    def read(cls, text: str, doc, at: int, local: str) -> PropertyValue:
        """A value read from ``doc`` at the packed position ``at`` of a ``<local>`` tag."""
        value = _new(cls)  # (each slot set once, without __init__: one value per tag)
        value.text = text
        value.element = None
        value._where = doc
        value._at = at
        value._local = local
        return value

    def _tag(self) -> str:
        return self._local or ""

    @property
    def stripped(self) -> str:
        return self.text.strip()

    def __repr__(self) -> str:
        return (
            f"PropertyValue(text={self.text!r}, location={self.location}, element={self.element!r})"
        )

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, PropertyValue):
            return NotImplemented
        return (
            self.text == other.text
            and self.element == other.element
            and str(self.location) == str(other.location)
        )

    __hash__ = None  # type: ignore[assignment]  (mutable, as the dataclass was)


def _version_number(text: str | None) -> int | None:
    try:
        return int((text or "").strip())
    except ValueError:
        return None


#: The property names of each shape of element seen, shared (see ConfigElement._props).
_SHAPES: dict[tuple[str, ...], tuple[str, ...]] = {}

#: The number of each version attribute text seen (a file holds a handful of them).
_VERSION_NUMBERS: dict[str | None, int | None] = {}


class ConfigElement(_Placed):
    """One configuration element. Read from a document it keeps the document and a packed
    position rather than a location object (see :class:`PropertyValue`); ``report`` is
    where :class:`~gadgetctl.jccl.elementcheck.ElementChecker` keeps its findings."""

    __slots__ = (
        "_at",
        "_names",
        "_props",
        "_where",
        "name",
        "parent",
        "parent_property",
        "report",
        "type",
        "version",
        "version_text",
    )

    def __init__(
        self,
        type: str,
        name: str,
        version_text: str | None,
        location: Location | SourceLocation | None,
        properties: dict[str, list[PropertyValue]] | None = None,
        parent: ConfigElement | None = None,
        parent_property: str | None = None,
    ) -> None:
        # (written out: 200,000 elements are made per large check)
        self.type = type
        self.name = name
        self.version_text = version_text
        self._where = location
        self._at: int | None = None
        # A dict of property name -> values, or (read from a file) the values of each name
        # in a tuple, the names in ``_names``, a tuple shared by every element of that
        # shape: a dict of one property is 184 bytes, and 200,000 aliases have one each.
        self._props: dict[str, list[PropertyValue]] | tuple[list[PropertyValue], ...] = (
            {} if properties is None else properties
        )
        self._names: tuple[str, ...] | None = None
        self.parent = parent
        self.parent_property = parent_property
        self.report = None
        #: The version attribute as a number (None when missing or not a number), read
        #: once: a configuration of 50,000 elements asks for it several times per element.
        try:
            self.version: int | None = _VERSION_NUMBERS[version_text]
        except KeyError:
            self.version = _version_number(version_text)
            if len(_VERSION_NUMBERS) < 1024:
                _VERSION_NUMBERS[version_text] = self.version

    @classmethod
    def read(
        cls,
        type: str,
        name: str,
        version_text: str | None,
        doc,
        at: int,
        parent: ConfigElement | None = None,
        parent_property: str | None = None,
    ) -> ConfigElement:
        """An element read from ``doc`` at the packed position ``at`` of its tag."""
        element = cls(type, name, version_text, doc, None, parent, parent_property)
        element._at = at
        return element

    def _tag(self) -> str:
        return self.type

    @property
    def file(self) -> str:
        return self._where.path

    def __repr__(self) -> str:
        return (
            f"ConfigElement(type={self.type!r}, name={self.name!r}, "
            f"version_text={self.version_text!r}, location={self.location})"
        )

    @property
    def full_name(self) -> str:
        """``parent/property/child`` for embedded elements, as VR Juggler names them."""
        if self.parent is None:
            return self.name
        return EMBEDDED_SEPARATOR.join(
            (self.parent.full_name, self.parent_property or "", self.name)
        )

    @property
    def properties(self) -> dict[str, list[PropertyValue]]:
        """Property name -> values as written, in document order (a dict made on first use
        from the compact form, and kept: the caller may change it)."""
        if self._names is None:
            return self._props  # type: ignore[return-value]
        made = self._props = dict(self.property_items())
        self._names = None
        return made

    @properties.setter
    def properties(self, properties: dict[str, list[PropertyValue]]) -> None:
        self._props, self._names = properties, None

    def compact(self) -> None:
        """Keep the properties in the compact form: the names in a tuple shared by every
        element of that shape, and for each name its one value (no list around it) or its
        list of values; with one name, that alone. (A dict of one property and its list
        are 250 bytes, and 200,000 aliases have one each.)"""
        props = self._props
        if self._names is not None or not isinstance(props, dict):
            return
        names = tuple(props)
        shared = _SHAPES.get(names)
        if shared is None:
            shared = names
            if len(_SHAPES) < 4096:
                _SHAPES[names] = names
        self._names = shared
        if len(names) == 1:  # (the usual element of a large configuration: one alias)
            (values,) = props.values()
            self._props = values[0] if len(values) == 1 else values
            return
        self._props = tuple(
            [values[0] if len(values) == 1 else values for values in props.values()]
        )

    def _compact_items(self) -> tuple:
        props = self._props
        return (props,) if len(self._names) == 1 else props  # type: ignore[arg-type]

    def property_items(self) -> Iterable[tuple[str, list[PropertyValue]]]:
        """(name, values) of every property written, without making the dict (a value
        kept alone comes in a list made for the caller)."""
        if self._names is None:
            return self._props.items()  # type: ignore[union-attr]
        return [
            (name, item if item.__class__ is list else [item])
            for name, item in zip(self._names, self._compact_items(), strict=True)
        ]

    def property_values(self) -> Iterable[list[PropertyValue]]:
        """The values of every property written, property by property."""
        if self._names is None:
            return self._props.values()  # type: ignore[union-attr]
        return [item if item.__class__ is list else [item] for item in self._compact_items()]

    def values(self, prop: str) -> list[PropertyValue]:
        names = self._names
        if names is None:
            return self._props.get(prop, [])  # type: ignore[union-attr]
        if len(names) == 1:
            if names[0] != prop:
                return []
            item = self._props
            return item if item.__class__ is list else [item]  # type: ignore[return-value]
        if prop not in names:
            return []
        item = self._props[names.index(prop)]  # type: ignore[index]  (the first of that name)
        return item if item.__class__ is list else [item]

    def written_texts(
        self, props: Container[str]
    ) -> tuple[tuple[str, tuple[str, ...]], ...] | None:
        """(name, texts as written) of those of ``props`` the element has, in the order
        written; None when one of them holds an embedded element (read from the compact form
        as it is, without the lists :meth:`property_items` makes)."""
        if self._names is None:
            pairs: Iterable = self._props.items()  # type: ignore[union-attr]
        else:
            pairs = zip(self._names, self._compact_items(), strict=True)
        found = []
        for name, item in pairs:
            if name not in props:
                continue
            if item.__class__ is not list:  # (compact: one value alone)
                if item.element is not None:
                    return None
                found.append((name, (item.text,)))
                continue
            texts = []
            for value in item:
                if value.element is not None:
                    return None
                texts.append(value.text)
            found.append((name, tuple(texts)))
        return tuple(found)

    def texts(self, prop: str) -> list[str]:
        return [v.stripped for v in self.values(prop)]

    def embedded(self) -> Iterator[ConfigElement]:
        """Embedded elements, depth-first (each before its own embedded elements)."""
        pending = self._embedded_children()
        if not pending:  # (the usual element)
            return
        pending.reverse()
        while pending:
            child = pending.pop()
            yield child
            below = child._embedded_children()
            if below:
                below.reverse()
                pending += below

    def _embedded_children(self) -> list[ConfigElement]:
        """The elements embedded directly in this one's values, in order."""
        items = self._props.values() if self._names is None else self._compact_items()
        children = []
        for item in items:  # a list of values, or (compact) one value alone
            if item.__class__ is list:
                children += [value.element for value in item if value.element is not None]
            elif item.element is not None:
                children.append(item.element)
        return children


@dataclass
class ConfigFile:
    """One configuration file as read: its includes, definition paths and elements."""

    path: Path
    display: str
    includes: list[tuple[str, Location]] = field(default_factory=list)
    definition_dirs: list[tuple[str, Location]] = field(default_factory=list)
    elements: list[ConfigElement] = field(default_factory=list)
    name: str | None = None
    embedded: int = 0  # how many embedded elements (at any depth) its elements hold


@dataclass
class Configuration:
    """One or more files loaded together, includes followed."""

    files: list[ConfigFile] = field(default_factory=list)
    loaded: list[ConfigElement] = field(
        default_factory=list
    )  # every top-level element, in load order
    diagnostics: list[Diagnostic] = field(default_factory=list)
    #: The files given, in order (resolved paths), and each file's resolved includes.
    roots: list[Path] = field(default_factory=list)
    includes: dict[Path, list[Path]] = field(default_factory=dict)
    _effective: tuple[int, list[ConfigElement]] | None = field(
        default=None, init=False, repr=False, compare=False
    )

    def reachable(self, start: Path) -> set[Path]:
        """``start`` and every file it includes, directly or not."""
        seen = {start}
        stack = [start]
        while stack:
            for target in self.includes.get(stack.pop(), ()):
                if target not in seen:
                    seen.add(target)
                    stack.append(target)
        return seen

    @property
    def elements(self) -> list[ConfigElement]:
        """The effective elements: a later element replaces an earlier one of the same name in
        place, as VR Juggler's ``Configuration::add`` does (so an including file overrides
        its includes). Worked out again only when ``loaded`` has changed length (elements are
        only ever appended to it); a fresh list each time, so callers may change theirs."""
        cached = self._effective
        if cached is None or cached[0] != len(self.loaded):
            cached = self._effective = (len(self.loaded), self._effective_elements())
        return list(cached[1])

    def _effective_elements(self) -> list[ConfigElement]:
        result: list[ConfigElement] = []
        index: dict[str, int] = {}
        for element in self.loaded:
            if element.name in index:
                result[index[element.name]] = element
            else:
                index[element.name] = len(result)
                result.append(element)
        return result

    def get(self, name: str) -> ConfigElement | None:
        for element in self.elements:
            if element.name == name:
                return element
        return None

    def by_type(self, type_name: str) -> list[ConfigElement]:
        return [e for e in self.elements if e.type == type_name]

    def may_embed(self) -> bool:
        """Whether some top-level element may hold embedded elements: false only when every
        loaded element was read from a file and none of those files had any, which spares
        checks of 50,000 elements a look into each."""
        files = self.files
        return any(f.embedded for f in files) or len(self.loaded) != sum(
            len(f.elements) for f in files
        )

    def all_elements(self) -> Iterator[ConfigElement]:
        """Effective top-level elements and, after each, its embedded elements."""
        for element in self.elements:
            yield element
            yield from element.embedded()
