"""The bundled standard definitions (definitions/*.jdef) against VR Juggler's originals.

The originals are read from the shared corpus next to the repository; these tests fail (they
do not skip) when it is missing. Every interface difference must be listed in
definitions/DEVIATIONS.md, and every listed difference must exist.

Only lxml is used here, not gadgetctl's own definition code, so that the data files are checked
independently of the library that reads them.
"""

from __future__ import annotations

import copy
import dataclasses
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import pytest
from lxml import etree

REPO = Path(__file__).resolve().parents[1]
CORPUS = REPO.parent / "shared" / "corpus" / "vrjuggler"
UPSTREAM_DIR = CORPUS / "modules" / "vrjuggler" / "data" / "definitions"
BUNDLED_DIR = REPO / "definitions"
SCHEMA = REPO / "schemas" / "definition-3.1.xsd"
DEVIATIONS_FILE = BUNDLED_DIR / "DEVIATIONS.md"

DEF_NS = "http://www.vrjuggler.org/jccl/xsd/3.1/definition"
CFG_NS = "http://www.vrjuggler.org/jccl/xsd/3.0/configuration"
XSL_NS = "http://www.w3.org/1999/XSL/Transform"
D = f"{{{DEF_NS}}}"

# Element types of gadgetctl's own that may live next to the standard ones.
GADGETCTL_OWN = {"waveform_device"}

XML_DECL = '<?xml version="1.0" encoding="UTF-8"?>'
SETTINGS_PI = '<?org-vrjuggler-jccl-settings definition.version="3.1"?>'


# --------------------------------------------------------------------------- model
@dataclass(frozen=True)
class Prop:
    name: str
    valuetype: str
    variable: str
    defaults: tuple[str | None, ...]  # one entry per <value> slot
    allowed: tuple[str, ...]
    editable: str | None  # None: no <enumeration>
    enums: tuple[tuple[str, str], ...]
    help: str


@dataclass(frozen=True)
class Version:
    number: int
    abstract: str
    help: str
    parents: tuple[str, ...]  # non-empty <parent> entries, in order
    categories: tuple[str, ...]
    props: tuple[Prop, ...]
    transform: etree._Element | None  # the xsl:stylesheet, if any


@dataclass(frozen=True)
class Definition:
    name: str
    versions: dict[int, Version]


def norm(text: str | None) -> str:
    return " ".join((text or "").split())


def parse_definition(root: etree._Element) -> Definition:
    versions = {}
    for v in root.iterfind(D + "definition_version"):
        props = []
        for p in v.iterfind(D + "property"):
            enum = p.find(D + "enumeration")
            props.append(
                Prop(
                    name=p.get("name"),
                    valuetype=p.get("valuetype"),
                    variable=p.get("variable"),
                    defaults=tuple(s.get("defaultvalue") for s in p.iterfind(D + "value")),
                    allowed=tuple(a.text.strip() for a in p.iterfind(D + "allowed_type")),
                    editable=None if enum is None else (enum.get("editable") or "false").strip(),
                    enums=()
                    if enum is None
                    else tuple((e.get("label"), e.get("value")) for e in enum.iterfind(D + "enum")),
                    help=norm(p.findtext(D + "help")),
                )
            )
        transform = v.find(f"{D}upgrade_transform/{{{XSL_NS}}}stylesheet")
        number = int(v.get("version"))
        versions[number] = Version(
            number=number,
            abstract=(v.findtext(D + "abstract") or "false").strip(),
            help=norm(v.findtext(D + "help")),
            parents=tuple(
                p.text.strip() for p in v.iterfind(D + "parent") if (p.text or "").strip()
            ),
            categories=tuple(c.text or "" for c in v.iterfind(D + "category")),
            props=tuple(props),
            transform=transform,
        )
    return Definition(root.get("name"), versions)


def require_corpus() -> None:
    if not UPSTREAM_DIR.is_dir():
        pytest.fail(f"VR Juggler corpus not found at {UPSTREAM_DIR}; these tests need it")


@cache
def upstream() -> dict[str, Definition]:
    """All upstream definitions by name. flock.jdef is Latin-1 although it claims UTF-8."""
    require_corpus()
    result = {}
    for path in sorted(UPSTREAM_DIR.glob("*.jdef")):
        data = path.read_bytes()
        try:
            data.decode("utf-8")
        except UnicodeDecodeError:
            data = data.decode("latin-1").encode("utf-8")
        definition = parse_definition(etree.fromstring(data))
        result[definition.name] = definition
    return result


def bundled_paths() -> dict[str, Path]:
    return {p.stem: p for p in sorted(BUNDLED_DIR.glob("*.jdef")) if p.stem not in GADGETCTL_OWN}


@cache
def bundled_root(name: str) -> etree._Element:
    data = bundled_paths()[name].read_bytes()
    data.decode("utf-8")  # strict: raises on any invalid byte
    return etree.fromstring(data)


@cache
def bundled(name: str) -> Definition:
    return parse_definition(bundled_root(name))


@cache
def schema() -> etree.XMLSchema:
    return etree.XMLSchema(etree.parse(str(SCHEMA)))


# --------------------------------------------------------------------------- deviations
@dataclass(frozen=True)
class Deviation:
    definition: str
    version: str
    prop: str
    field: str
    upstream: str
    ours: str


@cache
def deviations() -> tuple[Deviation, ...]:
    rows = []
    for line in DEVIATIONS_FILE.read_text(encoding="utf-8").splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if not line.startswith("|") or len(cells) != 7 or cells[0] in ("definition", "---"):
            continue
        rows.append(Deviation(*(c.strip("`") for c in cells[:6])))
    return tuple(rows)


def allowed_type_deviations() -> dict[tuple[str, int, str], Deviation]:
    return {
        (d.definition, int(d.version), d.prop): d for d in deviations() if d.field == "allowed_type"
    }


def added_properties(definition: str, version: int) -> list[str]:
    """Properties gadgetctl adds after the upstream ones (rows with field added_property)."""
    return [
        d.prop
        for d in deviations()
        if d.field == "added_property" and d.definition == definition and d.version == str(version)
    ]


def kept_by_us(definition: str, version: int) -> set[str]:
    """Properties our upgrade keeps where the upstream one drops them (rows with ours = kept)."""
    return {
        d.prop
        for d in deviations()
        if d.field == "upgrade_transform"
        and d.ours == "kept"
        and d.definition == definition
        and d.version == str(version)
    }


def type_list(types: tuple[str, ...]) -> str:
    return " ".join(types) if types else "(none)"


# --------------------------------------------------------------------------- file checks
def test_deviation_table_is_well_formed():
    rows = deviations()
    assert rows, "no rows parsed from DEVIATIONS.md"
    for row in rows:
        assert row.field in {"allowed_type", "upgrade_transform", "encoding", "added_property"}, row
        if row.field == "allowed_type":
            assert row.definition in bundled_paths(), row
            assert row.version.isdigit(), row


def test_same_definition_names_as_upstream():
    names = set(upstream())
    assert len(names) == 88
    assert set(bundled_paths()) == names


@pytest.mark.parametrize("name", sorted(bundled_paths()))
def test_file_is_utf8_valid_and_well_shaped(name):
    path = bundled_paths()[name]
    text = path.read_bytes().decode("utf-8")  # strict
    lines = text.splitlines()
    assert lines[0] == XML_DECL
    assert lines[1] == SETTINGS_PI
    root = bundled_root(name)
    assert root.tag == D + "definition"
    assert root.get("name") == name == path.stem
    assert set(root.attrib) == {"name"}, "no icon_path or xsi:schemaLocation"
    schema().assertValid(etree.ElementTree(root))
    for v in root.iterfind(D + "definition_version"):
        assert v.find(D + "abstract") is not None, "abstract must be written explicitly"


# --------------------------------------------------------------------------- interface
def version_fields(version: Version) -> dict[str, object]:
    return {
        "abstract": version.abstract,
        "parents": version.parents,
        "categories": version.categories,
        "properties": tuple(p.name for p in version.props),
        "has_transform": version.transform is not None,
    }


def prop_fields(prop: Prop) -> dict[str, object]:
    return {
        "valuetype": prop.valuetype,
        "variable": prop.variable,
        "slots": len(prop.defaults),
        "defaults": prop.defaults,
        "allowed_type": prop.allowed,
        "enumeration editable": prop.editable,
        "enumeration": prop.enums,
    }


@pytest.mark.parametrize("name", sorted(bundled_paths()))
def test_interface_matches_upstream(name):
    theirs, ours = upstream()[name], bundled(name)
    assert list(ours.versions) == list(theirs.versions)
    documented = allowed_type_deviations()
    seen = set()
    for number, their_version in theirs.versions.items():
        our_version = ours.versions[number]
        added = added_properties(name, number)
        own = len(our_version.props) - len(added)
        assert [p.name for p in our_version.props[own:]] == added, "added properties come last"
        our_version = dataclasses.replace(our_version, props=our_version.props[:own])
        assert version_fields(our_version) == version_fields(their_version), f"version {number}"
        for their_prop, our_prop in zip(their_version.props, our_version.props, strict=True):
            want, got = prop_fields(their_prop), prop_fields(our_prop)
            key = (name, number, their_prop.name)
            if key in documented:
                row = documented[key]
                assert type_list(their_prop.allowed) == row.upstream, f"{key}: table is stale"
                assert type_list(our_prop.allowed) == row.ours, f"{key}: table is stale"
                assert their_prop.allowed != our_prop.allowed, f"{key}: listed but not changed"
                want.pop("allowed_type")
                got.pop("allowed_type")
                seen.add(key)
            assert got == want, f"{key}"
    assert seen == {k for k in documented if k[0] == name}, "rows that match no property"


def test_no_stale_allowed_types_remain():
    names = set(upstream())
    for name in bundled_paths():
        for version in bundled(name).versions.values():
            for prop in version.props:
                unknown = set(prop.allowed) - names
                assert not unknown, f"{name} v{version.number} {prop.name}: {unknown}"


def test_position_filters_allow_every_filter_type():
    filters = {
        "position_transform_filter",
        "full_position_transform_filter",
        "position_calibration_filter",
    }
    for name in ("positional_device", "position_proxy"):
        (prop,) = [p for p in bundled(name).versions[1].props if p.name == "position_filters"]
        assert set(prop.allowed) == filters


# --------------------------------------------------------------------------- own texts
@cache
def all_upstream_helps() -> frozenset[str]:
    helps = set()
    for definition in upstream().values():
        for version in definition.versions.values():
            helps.add(version.help)
            helps.update(p.help for p in version.props)
    return frozenset(helps)


@pytest.mark.parametrize("name", sorted(bundled_paths()))
def test_help_texts_are_our_own(name):
    theirs, ours = upstream()[name], bundled(name)
    for number, version in ours.versions.items():
        assert version.help, f"v{number}: empty help"
        assert version.help != theirs.versions[number].help
        assert version.help not in all_upstream_helps(), f"v{number}: copied help"
        own = version.props[: len(version.props) - len(added_properties(name, number))]
        for their_prop, our_prop in zip(theirs.versions[number].props, own, strict=True):
            where = f"v{number} {our_prop.name}"
            assert our_prop.help, f"{where}: empty help"
            assert our_prop.help != their_prop.help, where
            assert our_prop.help not in all_upstream_helps(), f"{where}: copied help"


# --------------------------------------------------------------------------- upgrades
def steps(definitions: dict[str, Definition]) -> set[tuple[str, int]]:
    return {
        (d.name, v.number)
        for d in definitions.values()
        for v in d.versions.values()
        if v.transform is not None
    }


def bundled_steps() -> list[tuple[str, int]]:
    return sorted(steps({n: bundled(n) for n in bundled_paths()}))


def test_transforms_exist_for_the_same_version_steps():
    assert bundled_steps() == sorted(steps(upstream()))


@cache
def compiled(origin: str, name: str, version: int) -> etree.XSLT:
    """The upgrade stylesheet of one version, from "upstream" or from our "bundled" file."""
    definition = upstream()[name] if origin == "upstream" else bundled(name)
    sheet = copy.deepcopy(definition.versions[version].transform)
    return etree.XSLT(etree.ElementTree(sheet))


def in_config_ns(element: etree._Element) -> etree._Element:
    """A copy of an element instance with every element in the 3.0 configuration namespace
    (the corpus also has 3.1-namespace and namespace-less files)."""
    result = copy.deepcopy(element)
    for el in result.iter():
        if isinstance(el.tag, str):
            el.tag = f"{{{CFG_NS}}}{etree.QName(el).localname}"
    etree.cleanup_namespaces(result)
    return result


def apply(transform: etree.XSLT, element: etree._Element) -> list[etree._Element]:
    """Run a transform on one element parsed as its own document; returns the result's
    top-level elements (the upgraded element, then any elements the step creates)."""
    doc = etree.ElementTree(copy.deepcopy(element))
    result = transform(doc)
    root = result.getroot()
    assert root is not None, f"transform produced no element: {str(result)!r}"
    return [root, *(s for s in root.itersiblings() if isinstance(s.tag, str))]


def canonical(element: etree._Element, ignore: frozenset[str] = frozenset()) -> tuple:
    """Tag, attributes, child elements in order and leaf text, ignoring whitespace, comments
    and text that sits directly inside an element next to child elements."""
    children = [
        c for c in element if isinstance(c.tag, str) and etree.QName(c).localname not in ignore
    ]
    text = None if children else norm(element.text)
    return (
        element.tag,
        tuple(sorted(element.attrib.items())),
        text,
        tuple(canonical(c) for c in children),
    )


def synthetic(definition: Definition, version: int, depth: int = 0) -> etree._Element:
    """An element of the given version holding every own property of that version with its
    default values; configelement slots embed a synthetic element of the first allowed type
    when that type is defined (one level deep)."""
    element = etree.Element(
        f"{{{CFG_NS}}}{definition.name}",
        nsmap={None: CFG_NS},
        name=f"synthetic {definition.name}",
        version=str(version),
    )
    for prop in definition.versions[version].props:
        for default in prop.defaults:
            if prop.valuetype == "configelement":
                inner = [t for t in prop.allowed if t in upstream()]
                if depth or not inner:
                    continue
                child = upstream()[inner[0]]
                holder = etree.SubElement(element, f"{{{CFG_NS}}}{prop.name}")
                holder.append(synthetic(child, max(child.versions), depth + 1))
            else:
                etree.SubElement(element, f"{{{CFG_NS}}}{prop.name}").text = default or ""
    return element


@cache
def corpus_instances() -> dict[tuple[str, int], tuple[etree._Element, ...]]:
    """Every element instance (top-level or embedded) of the corpus .jconf files, by type
    and version."""
    require_corpus()
    found: dict[tuple[str, int], list[etree._Element]] = {}
    for path in sorted(CORPUS.rglob("*.jconf")):
        for el in etree.parse(str(path)).iter():
            version = el.get("version") if isinstance(el.tag, str) else None
            if version and version.isdigit() and el.get("name") is not None:
                key = (etree.QName(el).localname, int(version))
                found.setdefault(key, []).append(in_config_ns(el))
    return {k: tuple(v) for k, v in found.items()}


def children(element: etree._Element, prop: str) -> list[etree._Element]:
    """The child elements of one property (comments and other nodes skipped)."""
    return [c for c in element if isinstance(c.tag, str) and etree.QName(c).localname == prop]


def element_from(text: str) -> etree._Element:
    return etree.fromstring(f'<wrap xmlns="{CFG_NS}">{text}</wrap>')[0]


# Hand-written old elements that exercise the branches of the version steps.
BRANCH_CASES: dict[tuple[str, int], list[str]] = {
    ("fastrak", 2): [
        '<fastrak name="f" version="1"><port>/dev/ttyS1</port><baud>38400</baud>'
        "<hem1>0.0</hem1><hem1>0.0</hem1><hem1>-1.0</hem1><device_host/></fastrak>",
        '<fastrak name="f" version="1"><hem1>1.0</hem1><hem1>0.0</hem1><hem1>0.0</hem1>'
        '<position_filters><position_transform_filter name="x" version="1">'
        "<custom_scale>2.0</custom_scale></position_transform_filter></position_filters>"
        "</fastrak>",
    ],
    ("flock", 2): [
        '<flock name="f" version="1"><port>COM1</port><hemisphere>FRONT_HEM</hemisphere>'
        "<filter>AC_WIDE</filter><report>Q</report></flock>",
        '<flock name="f" version="1"><hemisphere>AFT_HEM</hemisphere></flock>',
        '<flock name="f" version="1"><hemisphere>2</hemisphere></flock>',
    ],
    ("motion_star", 2): [
        f'<motion_star name="m" version="1"><server_type>{role}</server_type></motion_star>'
        for role in ("Master", "Slave", "1", "0", "true", "false")
    ],
    ("opengl_frame_buffer_config", 3): [
        f'<opengl_frame_buffer_config name="o" version="2"><red_size>8</red_size>'
        f"<fsaa_enable>{v}</fsaa_enable></opengl_frame_buffer_config>"
        for v in ("true", "1", "false")
    ],
    ("input_manager", 2): [
        '<input_manager name="im" version="1">'
        "<driver>${VJ_BASE_DIR}/lib/gadgeteer/drivers/libFlock.so</driver>"
        "<driver>${VJ_BASE_DIR}/lib/gadgeteer/drivers/Wanda.dll</driver>"
        "<driver_directory>/opt/drivers</driver_directory>"
        "<dso_file_extension>so</dso_file_extension></input_manager>",
        '<input_manager name="im" version="1"><driver>/usr/lib/x/libPinch.dylib</driver>'
        "</input_manager>",
    ],
    ("cluster_manager", 2): [
        '<cluster_manager name="c" version="1">'
        "<plugin>/opt/vj/lib/gadgeteer/plugins/libRIMPlugin.so</plugin>"
        "<plugin>/opt/vj/lib/gadgeteer/plugins/ApplicationDataManager.dll</plugin>"
        "<cluster_nodes>node1</cluster_nodes><cluster_nodes>node2</cluster_nodes>"
        "<barrier_master>node1</barrier_master></cluster_manager>",
    ],
    ("cluster_manager", 3): [
        '<cluster_manager name="c" version="2"><plugin_path>/p</plugin_path>'
        "<plugin>RIMPlugin</plugin><plugin>StartBarrierPlugin</plugin>"
        "<plugin>SwapLockTCPPlugin</plugin><plugin>SwapLockWiredPlugin</plugin>"
        "<plugin>EventManager</plugin><cluster_node>a</cluster_node></cluster_manager>",
    ],
    ("display_window", 4): [
        '<display_window name="w" version="3"><origin>1</origin><origin>2</origin>'
        "<size>3</size><size>4</size><act_as_event_source>true</act_as_event_source>"
        '<event_window_device><event_window name="ev" version="1"><lock_key>KEY_L</lock_key>'
        "<start_locked>true</start_locked><sleep_time>10</sleep_time></event_window>"
        "</event_window_device><active>true</active></display_window>",
        '<display_window name="w" version="3"><act_as_event_source>1</act_as_event_source>'
        '<event_window_device><event_window name="ev2" version="1"/></event_window_device>'
        "</display_window>",
    ],
    ("surface_viewport", 2): [
        '<surface_viewport name="s" version="1"><origin>0</origin><origin>0</origin>'
        + "".join(
            f'<corners><vec3 name="c{i}" version="1"><x>{i}.1</x><y>{i}.2</y>'
            f"<z>{i}.3</z></vec3></corners>"
            for i in range(4)
        )
        + "<user>u</user></surface_viewport>",
    ],
    ("simulated_positional_device", 3): [
        '<simulated_positional_device name="s" version="2">'
        "<event_window_proxy>Keyboard Proxy</event_window_proxy>"
        "<translation_delta>0.5</translation_delta><position_filters/>"
        "</simulated_positional_device>",
    ],
    ("data_glove_ultra_wireless", 2): [
        '<data_glove_ultra_wireless name="g" version="1"><port>COM3</port>'
        "<device_host>node1</device_host></data_glove_ultra_wireless>",
    ],
    ("optitrack", 2): [
        '<optitrack name="o" version="1"><server>10.0.0.1</server>'
        '<rigid_body><optitrack_rigid_body name="rb" version="1"><body_index>3</body_index>'
        "</optitrack_rigid_body></rigid_body><position_filters>"
        '<position_transform_filter name="p" version="1"/></position_filters></optitrack>',
    ],
}


def upgrade_inputs(name: str, version: int) -> list[etree._Element]:
    """Old elements for one version step: corpus instances of version-1, a synthetic one
    built from the older version's properties, and the hand-written branch cases."""
    old = version - 1
    inputs = list(corpus_instances().get((name, old), ()))
    inputs.append(synthetic(upstream()[name], old))
    inputs += [element_from(text) for text in BRANCH_CASES.get((name, version), [])]
    return inputs


@pytest.mark.parametrize(("name", "version"), bundled_steps())
def test_upgrade_matches_upstream(name, version):
    theirs = compiled("upstream", name, version)
    ours = compiled("bundled", name, version)
    definition = upstream()[name]
    added = {p.name for p in definition.versions[version].props} - {
        p.name for p in definition.versions[version - 1].props
    }
    exercised = set()
    for element in upgrade_inputs(name, version):
        source = etree.tostring(element, encoding="unicode")
        exercised.update(prop for prop in kept_by_us(name, version) if children(element, prop))
        # Documented differences: properties upstream drops but ours keeps, and new
        # properties the old element already has (upstream adds a second value, ours not).
        present = {prop for prop in added if children(element, prop)}
        extra = frozenset(kept_by_us(name, version) | present)
        want = apply(theirs, element)
        got = apply(ours, element)
        assert got[0].get("version") == str(version), source
        assert [canonical(e, extra) for e in got] == [canonical(e, extra) for e in want], source
        for prop in extra:  # ours keeps these unchanged
            before = [canonical(c) for c in children(element, prop)]
            after = [canonical(c) for c in children(got[0], prop)]
            assert after == before, f"{prop} not kept: {source}"
    assert exercised == kept_by_us(name, version), "a documented kept property is never tested"


def test_branch_cases_belong_to_real_steps():
    assert set(BRANCH_CASES) <= set(bundled_steps())


def test_documented_transform_rows_name_real_steps():
    for row in deviations():
        if row.field == "upgrade_transform" and row.definition != "*":
            assert (row.definition, int(row.version)) in bundled_steps(), row


def decorated(element: etree._Element) -> etree._Element:
    """The element with a comment before every child, a trailing comment and an unknown child."""
    result = copy.deepcopy(element)
    for child in list(result):
        child.addprevious(etree.Comment(f" about {etree.QName(child).localname} "))
    etree.SubElement(result, f"{{{CFG_NS}}}gadgetctl_note").text = "keep me"
    result.append(etree.Comment(" trailing "))
    return result


def comments(element: etree._Element) -> list[str]:
    return sorted(c.text for c in element.iter(etree.Comment))


@pytest.mark.parametrize(("name", "version"), bundled_steps())
def test_upgrade_keeps_comments_and_unknown_children(name, version):
    ours = compiled("bundled", name, version)
    element = decorated(synthetic(upstream()[name], version - 1))
    (got,) = apply(ours, element)
    assert comments(got) == comments(element)
    assert [n.text for n in children(got, "gadgetctl_note")] == ["keep me"]


@pytest.mark.parametrize(("name", "version"), bundled_steps())
def test_upgrade_keeps_attributes_and_refuses_other_types(name, version):
    ours = compiled("bundled", name, version)
    element = synthetic(upstream()[name], version - 1)
    element.set("note", "x")
    (got,) = apply(ours, element)
    assert got.tag == element.tag
    assert dict(got.attrib) == {**element.attrib, "version": str(version)}
    with pytest.raises(etree.XSLTApplyError):
        ours(etree.ElementTree(etree.Element(f"{{{CFG_NS}}}not_{name}", version="1")))


def upgrade_ours(name: str, version: int, text: str) -> etree._Element:
    (got,) = apply(compiled("bundled", name, version), element_from(text))
    return got


def values(element: etree._Element, prop: str) -> list[str]:
    return [norm(c.text) for c in children(element, prop)]


def test_input_manager_upgrade_keeps_bare_names_and_all_directories():
    got = upgrade_ours(
        "input_manager",
        2,
        (
            '<input_manager name="im" version="1"><driver>/a/libFlock.so</driver>'
            "<driver>/b/Wanda_drv.dll</driver><driver>/a/IS900_drv.so</driver>"
            "<driver>PinchGlove_drv</driver><dso_file_extension>so</dso_file_extension>"
            "</input_manager>"
        ),
    )
    assert values(got, "driver_path") == ["/a/", "/b/"]
    assert values(got, "driver") == ["libFlock", "Wanda_drv", "IS900_drv", "PinchGlove_drv"]
    assert values(got, "dso_file_extension") == []
    assert norm(got.text) == ""


def test_cluster_manager_upgrade_keeps_bare_names_and_all_directories():
    got = upgrade_ours(
        "cluster_manager",
        2,
        (
            '<cluster_manager name="c" version="1"><plugin>/a/libRIMPlugin.so</plugin>'
            "<plugin>EventManager</plugin><plugin>/b/libApplicationDataManager.so</plugin>"
            "</cluster_manager>"
        ),
    )
    assert values(got, "plugin_path") == ["/a/", "/b/"]
    assert values(got, "plugin") == ["RIMPlugin", "EventManager", "ApplicationDataManager"]


def test_fastrak_upgrade_compares_the_hemisphere_vector_as_numbers():
    got = upgrade_ours(
        "fastrak",
        2,
        ('<fastrak name="f" version="1"><hem1>0</hem1><hem1> 1 </hem1><hem1>0.00</hem1></fastrak>'),
    )
    assert values(got, "hemisphere") == ["Right"]


def test_upgrades_leave_missing_old_values_to_the_defaults():
    flock = upgrade_ours("flock", 2, '<flock name="f" version="1"><port>COM1</port></flock>')
    assert values(flock, "hemisphere") == []
    star = upgrade_ours("motion_star", 2, '<motion_star name="m" version="1"/>')
    assert values(star, "is_master") == []


def test_added_properties_are_not_duplicated():
    got = upgrade_ours(
        "display_window",
        6,
        (
            '<display_window name="w" version="5">'
            "<allow_mouse_locking>false</allow_mouse_locking></display_window>"
        ),
    )
    assert values(got, "allow_mouse_locking") == ["false"]
