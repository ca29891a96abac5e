"""Output formats and exit codes of `gadgetctl validate`."""

from __future__ import annotations

import json

from conftest import write
from jccl_samples import jconf

BROKEN = jconf('      <alias name="a" version="1">\n')
WARN = jconf().replace('<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n', "")


def test_text_format_line_shape_and_summary(cli, tmp_path):
    path = write(tmp_path / "b.jconf", BROKEN)
    result = cli("validate", path)
    assert result.exit_code == 1
    first = result.stdout.splitlines()[0]
    assert first.startswith(f"{path}:6:") and ": error XML001 " in first
    assert result.stdout.splitlines()[-1] == "1 file checked: 1 error, 0 warnings in 1 file"
    assert "\x1b[" not in result.stdout  # not a terminal: no colour


def test_colour_only_when_asked_or_on_a_tty(cli, tmp_path):
    path = write(tmp_path / "b.jconf", BROKEN)
    assert "\x1b[" in cli("validate", path, "--color", "always").stdout


def test_clean_exit_zero_and_warnings_with_strict(cli, tmp_path):
    clean = write(tmp_path / "c.jconf", jconf())
    assert cli("validate", clean).exit_code == 0
    warn = write(tmp_path / "w.jconf", WARN)
    assert cli("validate", warn).exit_code == 0
    assert cli("validate", warn, "--strict").exit_code == 1


def test_json_fields(cli, tmp_path):
    path = write(tmp_path / "b.jconf", BROKEN)
    (item,) = json.loads(cli("validate", path, "-f", "json").stdout)
    assert item == {
        "code": "XML001",
        "severity": "error",
        "category": "xml",
        "path": str(path),
        "line": 6,
        "column": item["column"],
        "message": item["message"],
        "hint": None,
    }


def test_github_annotations(cli, tmp_path):
    path = write(tmp_path / "b,c.jconf", BROKEN)
    out = cli("validate", path, "-f", "github").stdout.strip()
    assert (
        out.startswith("::error file=")
        and "%2C" in out
        and ",line=6," in out
        and "title=XML001::" in out
    )


def test_sarif_required_structure(cli, tmp_path):
    path = write(tmp_path / "b.jconf", BROKEN)
    log = json.loads(cli("validate", path, "-f", "sarif").stdout)
    assert log["version"] == "2.1.0" and "$schema" in log
    (run,) = log["runs"]
    driver = run["tool"]["driver"]
    assert driver["name"] == "gadgetctl" and driver["rules"][0]["id"] == "XML001"
    (res,) = run["results"]
    assert res["ruleId"] == "XML001" and res["level"] == "error" and res["message"]["text"]
    assert driver["rules"][res["ruleIndex"]]["id"] == res["ruleId"]
    loc = res["locations"][0]["physicalLocation"]
    assert loc["artifactLocation"]["uri"].endswith("b.jconf") and loc["region"]["startLine"] == 6


def test_missing_path_is_a_usage_error(cli, tmp_path):
    result = cli("validate", tmp_path / "nope.jconf")
    assert result.exit_code == 2
    assert (
        result.stderr.strip()
        == f"gadgetctl: error: {tmp_path / 'nope.jconf'}: no such file or directory"
    )


def test_bad_option_is_a_usage_error(cli, tmp_path):
    result = cli("validate", tmp_path, "--format", "yaml")
    assert result.exit_code == 2 and "Traceback" not in result.stderr


def test_unreadable_file(cli, tmp_path):
    import os

    path = write(tmp_path / "secret.jconf", jconf())
    path.chmod(0)
    try:
        if os.access(path, os.R_OK):  # running as root: permissions do not apply
            result = cli("validate", tmp_path / "missing-dir" / "x.jconf")
        else:
            result = cli("validate", path)
        assert result.exit_code == 2 and result.stderr.count("\n") == 1
    finally:
        path.chmod(0o644)


def test_directory_recursion_picks_jccl_files_only(cli, tmp_path):
    write(tmp_path / "a" / "one.jconf", jconf())
    write(tmp_path / "a" / "b" / "two.jdef", BROKEN.replace("configuration", "definition"))
    write(tmp_path / "a" / "notes.txt", "<not xml")
    result = cli("validate", tmp_path / "a")
    assert "2 files checked" in result.stdout


def test_explain_every_code_and_unknown(cli):
    from gadgetctl.diagnostics import all_codes

    for code in all_codes():
        result = cli("explain", code)
        assert result.exit_code == 0 and result.stdout.startswith(code + ":")
        assert "Example:" in result.stdout
    bad = cli("explain", "XML99")
    assert bad.exit_code == 2 and "did you mean" in bad.stderr


def test_version(cli):
    from gadgetctl import __version__

    assert cli("--version").stdout.strip() == f"gadgetctl {__version__}"
