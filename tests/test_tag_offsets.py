"""Start tags are located on a line without a regular expression per tag name (issue 27
goal 4); the offsets are those of the pattern used before, ``<(?:[\\w.-]+:)?NAME(?=[\\s/>]|$)``."""

from __future__ import annotations

import re

from hypothesis import given
from hypothesis import strategies as st

from gadgetctl.jccl.xmlload import tag_offsets


def _pattern_offsets(line: str, local: str) -> list[int]:
    pattern = re.compile(r"<(?:[\w.-]+:)?" + re.escape(local) + r"(?=[\s/>]|$)")
    return [m.start() for m in pattern.finditer(line)]


def test_known_lines():
    line = '<device name="a"><device_x/><j:device>< device><x:y:device/><device\t<-:device>'
    assert tag_offsets(line, "device") == _pattern_offsets(line, "device") == [0, 28, 60, 68]
    assert tag_offsets("<a:a>", "a") == [0]
    assert tag_offsets("<:a>", "a") == []
    assert tag_offsets("<ab", "b") == []
    assert tag_offsets("<é.x:name\u00a0", "name") == [0]  # a letter and a no-break space
    assert tag_offsets("<name\n", "name") == [0]


_TEXT = st.text(alphabet="<>/: \t\n\u00a0.-_abé1\u00b7", max_size=40)


@given(line=_TEXT, local=st.sampled_from(["a", "ab", "b_a", "a.b", "é", "a\u00b7b", "-"]))
def test_the_same_offsets_as_the_pattern(line, local):
    assert tag_offsets(line, local) == _pattern_offsets(line, local)


@given(line=_TEXT, local=st.text(alphabet="ab_.-é\u00b7", min_size=1, max_size=3))
def test_the_same_offsets_for_any_name(line, local):
    assert tag_offsets(line, local) == _pattern_offsets(line, local)
