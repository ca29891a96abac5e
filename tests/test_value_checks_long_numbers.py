"""Numbers thousands of digits long are checked in linear time (found by make fuzz: the float
pattern backtracked quadratically, about 2 s per 5,000-digit value)."""

from __future__ import annotations

import pytest

from gadgetctl.jccl.valuecheck import is_number

HEAD = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="long">
<elements>
"""


@pytest.mark.timeout(30)  # a hang guard: this took minutes
def test_a_configuration_of_long_bad_numbers_validates(tmp_path, cli) -> None:
    # each compared with every enumeration value as a number (and all different)
    elements = "".join(
        f'<flock name="F{i}" version="1"><hemisphere>{"1" * 5000}{i}x</hemisphere></flock>\n'
        for i in range(20)
    )
    path = tmp_path / "long.jconf"
    path.write_text(HEAD + elements + "</elements>\n</configuration>\n")
    result = cli("validate", path, "--format", "json")
    assert result.exit_code == 1
    assert result.stdout.count('"CFG028"') == 20


@pytest.mark.parametrize(
    ("text", "number"),
    [("1", True), ("1.", True), (".5", True), ("-1.5E-3", True), ("+.5", True), ("1" * 5000, True),
     ("1e", False), ("e5", False), (".", False), ("1.2.3", False), ("1" * 5000 + "x", False)],
)  # fmt: skip
def test_float_syntax(text: str, number: bool) -> None:
    from gadgetctl.jccl.definitions import ValueType

    assert is_number(ValueType.FLOAT, text) is number


def test_an_integer_of_thousands_of_digits_reads_saturated(tmp_path, cli) -> None:
    from gadgetctl.jccl.access import read_int

    assert read_int("9" * 5000 + "x") == 2**63 - 1 and read_int("-" + "9" * 5000) == -(2**63)
    assert read_int(" 0000000000000000000000042z") == 42 and read_int("x1") == 0
    path = tmp_path / "huge.jconf"
    element = f'<dtrack name="T" version="1"><receive_port>{"9" * 5000}x</receive_port></dtrack>'
    path.write_text(HEAD + element + "\n</elements>\n</configuration>\n")
    result = cli("validate", path)
    assert result.exit_code == 1 and "Traceback" not in result.stderr
    assert "9223372036854775807" in result.stdout  # what it is read as, said in the finding
