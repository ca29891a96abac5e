"""Applying definitions' upgrade transforms (XSLT 1.0) to single elements, safely.

A stylesheet comes from a definition file, which may come from anywhere, so it runs with
an access control that denies every file and network access (``document()``,
``xsl:include``, ``xsl:import`` and output extensions all fail) and is parsed without DTDs,
entities or network.
"""

from __future__ import annotations

import copy
import threading
from collections import OrderedDict
from pathlib import Path

from lxml import etree

from gadgetctl.jccl.namespaces import CONFIG_NS


class TransformError(Exception):
    """A stylesheet that cannot be compiled or applied, or whose result is no element."""


_DENY_ALL = etree.XSLTAccessControl.DENY_ALL
#: Compiled stylesheets kept for reuse, the least recently used dropped first. The bundled
#: definitions have 37; the sandbox child lives as long as its parent and is given every
#: stylesheet of every definition file met, which it used to keep for ever.
COMPILED_LIMIT = 64
_compiled: OrderedDict[bytes, etree.XSLT] = OrderedDict()
_compiled_lock = threading.Lock()


def compile_transform(stylesheet: bytes) -> etree.XSLT:
    with _compiled_lock:
        found = _compiled.get(stylesheet)
        if found is not None:
            _compiled.move_to_end(stylesheet)
            return found
    try:
        found = etree.XSLT(etree.fromstring(stylesheet, _safe_parser()), access_control=_DENY_ALL)
    except (etree.XMLSyntaxError, etree.XSLTParseError) as err:
        raise TransformError(f"the upgrade stylesheet does not compile: {err}") from None
    with _compiled_lock:
        _compiled[stylesheet] = found
        while len(_compiled) > COMPILED_LIMIT:
            _compiled.popitem(last=False)
    return found


def in_namespace(node: etree._Element, namespace: str = CONFIG_NS) -> etree._Element:
    """A deep copy of ``node`` with every element in ``namespace`` as the default namespace
    (whatever namespace or prefix it had), comments and processing instructions dropped."""

    def rebuild(source: etree._Element) -> etree._Element:
        local = etree.QName(source).localname
        target = etree.Element(f"{{{namespace}}}{local}", nsmap={None: namespace})
        for key, value in source.attrib.items():
            target.set(key, value)
        target.text = source.text
        for child in source:
            if isinstance(child.tag, str):
                built = rebuild(child)
                built.tail = child.tail
                target.append(built)
            elif child.tail:  # keep text that followed a dropped comment
                if len(target):
                    target[-1].tail = (target[-1].tail or "") + child.tail
                else:
                    target.text = (target.text or "") + child.tail
        return target

    return rebuild(node)


def apply_transform(
    stylesheet: bytes, element: etree._Element, source: str | None = None
) -> list[etree._Element]:
    """The elements a stylesheet makes of one element: the upgraded element first, then any
    new elements it creates. ``element`` itself is not changed.

    ``source`` is the definition file the stylesheet comes from: one of the bundled
    definitions runs in-process; any other (or an unknown source) runs in a child process
    with bounded time and memory (:mod:`gadgetctl.jccl.xsltsandbox`).
    """
    if source is not None and is_bundled(source):
        transform = compile_transform(stylesheet)
        document = etree.ElementTree(copy.deepcopy(element))
        try:
            result = transform(document)
        except etree.XSLTApplyError as err:
            raise TransformError(f"the upgrade stylesheet failed: {err}") from None
        root = result.getroot()
        if root is None:
            raise TransformError("the upgrade stylesheet produced no element")
        return [root, *(n for n in root.itersiblings() if isinstance(n.tag, str))]
    from gadgetctl.jccl.xsltsandbox import SandboxError, run_sandboxed

    try:
        answer = run_sandboxed(stylesheet, etree.tostring(element))
    except SandboxError as err:
        raise TransformError(
            f"the upgrade stylesheet of {source or 'a definition'} was {err}"
        ) from None
    except ValueError as err:
        raise TransformError(f"{err} (stylesheet of {source or 'a definition'})") from None
    wrapper = etree.fromstring(answer, _safe_parser())
    return [child for child in wrapper if isinstance(child.tag, str)]


def transform_in_process(stylesheet: bytes, element: bytes) -> bytes:
    """What the sandbox's child runs: ``apply_transform`` on a serialised element, the
    resulting elements serialised inside ``<r>``."""
    node = etree.fromstring(element, _safe_parser())
    transform = compile_transform(stylesheet)
    try:
        result = transform(etree.ElementTree(node))
    except etree.XSLTApplyError as err:
        raise TransformError(f"the upgrade stylesheet failed: {err}") from None
    root = result.getroot()
    if root is None:
        raise TransformError("the upgrade stylesheet produced no element")
    wrapper = etree.Element("r")
    for made in [root, *(n for n in root.itersiblings() if isinstance(n.tag, str))]:
        wrapper.append(copy.deepcopy(made))
    return etree.tostring(wrapper)


def _safe_parser() -> etree.XMLParser:
    return etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False, huge_tree=False)


def is_bundled(source: str) -> bool:
    """Whether ``source`` is a definition file of gadgetctl's own (bundled definitions or
    bundled drivers), whose stylesheets run in-process."""
    from gadgetctl.resources import definitions_dir, drivers_dir

    try:
        path = Path(source).resolve()
    except (OSError, RuntimeError):
        return False
    return any(path.is_relative_to(root.resolve()) for root in (definitions_dir(), drivers_dir()))


if __name__ == "__main__":  # the sandbox's child process
    from gadgetctl.jccl.xsltsandbox import serve

    serve(transform_in_process, (TransformError,))
