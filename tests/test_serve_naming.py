"""VRPN names of served elements (docs/serve.md): derived by one rule, collisions resolved
deterministically, `--name` renames checked, and `serve --list` printing them."""

from __future__ import annotations

import json
import random

import pytest

from gadgetctl.serve.naming import (
    MAX_NAME,
    NamingError,
    assign_names,
    derive_name,
    is_valid_name,
    parse_renames,
)

from conftest import REPO


def test_valid_names_are_kept_and_others_derived():
    names = assign_names(
        ["VJWand", "Waveform Sticks", "Tracker0", "a@b:c/d", "Ünïcode pad", "x.y-z_1"]
    )
    assert names == {
        "VJWand": "VJWand",
        "Waveform Sticks": "Waveform_Sticks",
        "Tracker0": "Tracker0",
        "a@b:c/d": "a_b_c_d",
        "Ünïcode pad": "_n_code_pad",
        "x.y-z_1": "x.y-z_1",
    }
    assert all(is_valid_name(n) for n in names.values())


def test_runs_of_invalid_characters_become_one_underscore_and_empty_names_get_one():
    assert derive_name("Head   Proxy\t2") == "Head_Proxy_2"
    assert derive_name("") == "unnamed"
    assert len(derive_name("n" * 300)) == MAX_NAME


def test_collisions_get_numbered_suffixes_and_exact_names_win():
    # "Wand Proxy" and "Wand@Proxy" both derive Wand_Proxy, which an element already has
    names = assign_names(["Wand@Proxy", "Wand_Proxy", "Wand Proxy", "Wand_Proxy_2"])
    assert names["Wand_Proxy"] == "Wand_Proxy"
    assert names["Wand_Proxy_2"] == "Wand_Proxy_2"
    assert names["Wand Proxy"] == "Wand_Proxy_3"  # " " sorts before "@"
    assert names["Wand@Proxy"] == "Wand_Proxy_4"
    assert len(set(names.values())) == 4


def test_the_result_does_not_depend_on_the_order_of_elements():
    elements = ["A B", "A_B", "A-B", "A:B", "A/B", "A  B", "B", "b", "long " * 30, "long_" * 30]
    expected = assign_names(elements)
    for seed in range(5):
        shuffled = elements[:]
        random.Random(seed).shuffle(shuffled)
        assert assign_names(shuffled) == expected
    assert len(set(expected.values())) == len(elements)
    assert all(is_valid_name(n) for n in expected.values())


def test_renames_apply_first_and_are_checked():
    names = assign_names(
        ["Waveform Tracker", "Tracker0"],
        parse_renames(["Waveform Tracker=Tracker0", "Tracker0=Old_Tracker"]),
    )
    assert names == {"Waveform Tracker": "Tracker0", "Tracker0": "Old_Tracker"}
    with pytest.raises(NamingError, match="not a VRPN name"):
        parse_renames(["Wand=My Wand"])
    with pytest.raises(NamingError, match="expected OLD=NEW"):
        parse_renames(["Wand"])
    with pytest.raises(NamingError, match="did you mean 'Wand Proxy'"):
        assign_names(["Wand Proxy"], {"Wand Proxi": "W"})
    with pytest.raises(NamingError, match="both be served as 'W'"):
        assign_names(["A", "B"], {"A": "W", "B": "W"})


def test_an_element_name_with_an_equals_sign_can_be_renamed():
    assert parse_renames(["a=b=c"]) == {"a=b": "c"}


@pytest.mark.timeout(60)
def test_serve_list_prints_every_device_proxy_and_alias(cli):
    result = cli("serve", "examples/waveform.jconf", "--list", cwd=REPO)
    assert result.exit_code == 0, result.stderr
    lines = {line.split()[0]: line for line in result.stdout.splitlines()}
    assert "Tracker (3 sensors)" in lines["Waveform_Tracker"]
    assert (
        "Button (2 buttons)" in lines["Waveform_Sticks"]
        and "Analog (2 channels)" in lines["Waveform_Sticks"]
    )
    assert "Tracker (1 sensor)" in lines["VJWand"]
    assert "analog 0..1" in lines["VJAnalog0"]
    assert "(element 'Stick X Proxy')" in lines["Stick_X_Proxy"]


@pytest.mark.timeout(60)
def test_serve_list_json_with_renames_and_a_selection(cli):
    result = cli(
        "serve",
        "examples/waveform.jconf",
        "Waveform Tracker",
        "VJ*",
        "--list",
        "--format",
        "json",
        "--name",
        "Waveform Tracker=Tracker0",
        cwd=REPO,
    )
    assert result.exit_code == 0, result.stderr
    served = {e["element"]: e for e in json.loads(result.stdout)["served"]}
    assert served["Waveform Tracker"]["vrpn_name"] == "Tracker0"
    assert served["Waveform Tracker"]["vrpn"] == ["tracker", "text"]  # events: strings, commands
    assert served["Waveform Tracker"]["units"] == {"tracker": 3}
    assert served["VJButton0"] == {
        "element": "VJButton0",
        "vrpn_name": "VJButton0",
        "kind": "alias",
        "type": "alias",
        "vrpn": ["button"],
        "units": {"button": 1},
        "source": "Trigger Proxy",
    }
    assert set(served) == {
        "Waveform Tracker",
        "VJAnalog0",
        "VJAnalog1",
        "VJButton0",
        "VJButton1",
        "VJWand",
        "VJHead",
        "VJNoise",
    }


@pytest.mark.timeout(60)
@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--name", "Nobody=X"], "no served element is called 'Nobody'"),
        (["--name", "VJWand=V J"], "is not a VRPN name"),
        (["--bind", "localhost"], "give an IPv4 address"),
        (["--port", "70000"], "between 0"),
        (["--allow", "10.0.0.0/33"], "expected an IPv4 network"),
        (["Nobody"], "no device, proxy or alias matches 'Nobody'"),
    ],
)
def test_serve_usage_errors_are_one_line_with_exit_2(cli, args, message):
    result = cli("serve", "examples/waveform.jconf", "--list", *args, cwd=REPO)
    assert result.exit_code == 2
    assert message in result.stderr and "Traceback" not in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1


HOSTILE_NAMES = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="hostile">
   <elements>
      <waveform_device name="Dev&#10;::error::forged&#13;&#x202E;x&#x85;y&#x2028;z" version="1">
         <rate>100.0</rate><position_path>circle</position_path>
      </waveform_device>
      <position_proxy name="Prox&#10;::error::f&#x2028;orged" version="1">
         <device>Dev&#10;::error::forged&#13;&#x202E;x&#x85;y&#x2028;z</device>
         <unit>0</unit>
      </position_proxy>
      <alias name="Wand" version="1">
         <proxy>Prox&#10;::error::f&#x2028;orged</proxy>
      </alias>
   </elements>
</configuration>
"""


@pytest.mark.timeout(60)
def test_serve_list_escapes_names_from_the_configuration(cli, tmp_path):
    from conftest import write

    config = write(tmp_path / "hostile.jconf", HOSTILE_NAMES)
    result = cli("serve", str(config), "--list", "--no-check")
    assert result.exit_code == 0, result.stderr
    lines = result.stdout.splitlines()
    assert len(lines) == 3  # one line per served element, whatever the names hold
    assert not any(line.startswith("::") for line in lines)
    for unsafe in ("\r", "\u202e", "\x85", "\u2028"):
        assert unsafe not in result.stdout
    by_name = {line.split()[0]: line for line in lines}
    assert "of Prox\\n::error::f\\u2028orged:" in by_name["Wand"]  # the alias's proxy
    proxy = next(line for name, line in by_name.items() if name.startswith("Prox"))
    assert "of Dev\\n::error::forged\\r\\u202ex\\x85y\\u2028z unit 0" in proxy
    assert "(element 'Prox\\n::error::f\\u2028orged')" in proxy


@pytest.mark.timeout(60)
def test_serve_list_shows_text_for_string_and_command_units_before_any_event(cli):
    # Waveform Tracker's events (strings and commands) come every 2 s, after --list's
    # warm-up; clients receive them as Text, so --list says so. Waveform Sticks makes none.
    result = cli("serve", "examples/waveform.jconf", "--list", "--format", "json", cwd=REPO)
    assert result.exit_code == 0, result.stderr
    served = {e["element"]: e for e in json.loads(result.stdout)["served"]}
    assert served["Waveform Tracker"]["vrpn"] == ["tracker", "text"]
    assert "text" not in served["Waveform Sticks"]["vrpn"]
    assert served["Tracker String Proxy"]["vrpn"] == ["text"]
    text = cli("serve", "examples/waveform.jconf", "--list", cwd=REPO).stdout
    tracker = next(line for line in text.splitlines() if line.startswith("Waveform_Tracker "))
    assert "Tracker (3 sensors), Text," in tracker


@pytest.mark.timeout(60)
def test_serve_given_a_directory_names_serve(cli):
    result = cli("serve", "examples/", cwd=REPO)
    assert result.exit_code == 2
    assert "examples/: is a directory; serve takes configuration files" in result.stderr
    assert "monitor" not in result.stderr
