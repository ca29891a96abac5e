"""Issue 4 acceptance on the VR Juggler corpus: configuration-level findings (pinned, each
reviewed as a real problem of its file), the same findings without the bundled definitions,
and upgrades of every element older than its definition.

The pinned list is tests/data/corpus_config_findings.txt (code, file relative to the corpus,
line). To regenerate it after a deliberate change: ``python tests/test_config_corpus.py``,
then review every difference.
"""

from __future__ import annotations

import collections
import os
import shutil
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from gadgetctl.diagnostics import Category  # noqa: E402
from gadgetctl.validate import ValidateOptions, validate_paths  # noqa: E402

from conftest import CORPUS, CORPUS_DEFINITIONS  # noqa: E402

PINNED = HERE / "data" / "corpus_config_findings.txt"
MODULES = CORPUS / "modules"
EXTRA = [
    MODULES / "vrjuggler/samples/OGL/simple/ConfigApp",
    MODULES / "jackal/test/TestSuite/TestFiles/definitions",
]
ENVIRONMENT = {"HOME": "/home/user"}  # DATA_DIR, VJ_BASE_DIR and the rest unset


def findings(root: Path, *, bundled: bool = True, together: bool = False, paths=None) -> list:
    options = ValidateOptions(
        bundled=bundled,
        definition_dirs=EXTRA if bundled else [],
        together=together,
        environ=ENVIRONMENT,
    )
    result = validate_paths(paths or [root], options)
    return [d for d in result.diagnostics if d.category is Category.CONFIG]


def keys(found, root: Path = CORPUS) -> collections.Counter:
    return collections.Counter(
        (d.code, Path(d.path).resolve().relative_to(root.resolve()).as_posix(), d.line)
        for d in found
    )


def pinned() -> collections.Counter:
    entries = collections.Counter()
    for line in PINNED.read_text(encoding="utf-8").splitlines():
        if line and not line.startswith("#"):
            code, path, number = line.split("\t")
            entries[(code, path, int(number))] += 1
    return entries


@pytest.fixture(autouse=True)
def clean_environment(monkeypatch):
    for name in ("VJ_BASE_DIR", "JCCL_DEFINITION_PATH", "DATA_DIR"):
        monkeypatch.delenv(name, raising=False)


def test_corpus_findings_are_the_pinned_ones(corpus):
    assert keys(findings(corpus)) == pinned()


def test_same_findings_with_the_corpus_definitions_instead_of_the_bundled_ones(corpus, monkeypatch):
    dirs = [CORPUS_DEFINITIONS, *EXTRA]
    monkeypatch.setenv("JCCL_DEFINITION_PATH", os.pathsep.join(map(str, dirs)))
    assert keys(findings(corpus, bundled=False)) == pinned()


def at(found, code: str, name: str):
    return sorted(d.line for d in found if d.code == code and Path(d.path).name == name)


def test_named_examples(corpus):
    found = findings(corpus)
    # the empty <command_port/> of an integer property, read as 0 without a word
    (dtrack,) = [d for d in found if Path(d.path).name == "example.dtrack.jconf"]
    assert (dtrack.code, dtrack.line) == ("CFG025", 11) and "command_port" in dtrack.message
    # a version 4 frame buffer configuration carrying a property only version 5 defines
    (standalone,) = [d for d in found if d.code == "CFG022"]
    assert Path(standalone.path).name == "standalone.jconf" and standalone.line == 455
    assert "gl_context_profile_mask" in standalone.message
    # device_host, dropped by input_device version 2, in many test configurations
    dropped = [d for d in found if d.code == "CFG021"]
    assert len(dropped) >= 20 and all("device_host" in d.message for d in dropped)


def test_c4_closed_with_its_includes(corpus):
    config_dir = MODULES / "vrjuggler/data/configFiles"
    found = findings(corpus, paths=[config_dir / "C4.closed.jconf"])
    (missing,) = [d for d in found if d.code == "CFG031"]
    assert "AppDigitalSim" in missing.message and Path(missing.path).name == "C4.base.jconf"
    # C4.mstar.jconf repeats C4.base.jconf's VJHead alias byte for byte: info, not a warning
    (twice,) = [d for d in found if d.code == "CFG042"]
    assert "VJHead" in twice.message and (Path(twice.path).name, twice.line) == (
        "C4.mstar.jconf",
        36,
    )
    assert "C4.base.jconf:5" in twice.message and "identical copy" in twice.message
    assert not [d for d in found if d.code == "CFG040"]


def test_clean_files_have_no_findings(corpus):
    clean = [
        "vrjuggler/data/configFiles/example.flock.jconf",
        "vrjuggler/data/configFiles/example.wanda.jconf",
        "vrjuggler/data/configFiles/example.mstar.2pack.jconf",
        "vrjuggler/data/configFiles/sim.trackd.jconf",
        "vrjuggler/data/configFiles/sim.wand.mixin.jconf",
        "jackal/test/TestSuite/TestFiles/cfg/enumerations_test.jconf",
    ]
    for name in clean:
        assert findings(corpus, paths=[MODULES / name]) == [], name


def test_upgrade_check_lists_every_older_element_and_upgrading_removes_them(corpus, tmp_path, cli):
    older = {(path, line) for (code, path, line) in pinned() if code == "CFG012"}
    result = cli("upgrade", "--check", "--format", "json", corpus)
    assert result.exit_code == 1
    import json

    listed = {
        (Path(entry["path"]).resolve().relative_to(corpus.resolve()).as_posix(), element["line"])
        for entry in json.loads(result.stdout)
        for element in entry["elements"]
    }
    assert listed == older

    copy = tmp_path / "corpus"
    shutil.copytree(corpus, copy)
    upgraded = cli("upgrade", "--in-place", "--no-backup", copy)
    # the one file it cannot check (jackal's test elements have no definition) fails it
    assert upgraded.exit_code == 1
    errors = [line for line in upgraded.stderr.splitlines() if " error " in line]
    unchecked = copy / "modules/jackal/test/TestSuite/TestFiles/cfg/ConfigurationTest.jconf"
    assert errors and all(
        line.startswith(f"{unchecked}:") and " CFG010 " in line for line in errors
    )
    after = findings(copy)
    assert not [d for d in after if d.code == "CFG012"]
    # every element that was listed now carries its definition's newest version
    from gadgetctl.jccl.configload import load_configuration
    from gadgetctl.jccl.repository import default_repository

    repo = default_repository()
    for path in {p for p, _ in older}:
        config = load_configuration([copy / path])
        for element in (e for top in config.loaded for e in (top, *top.embedded())):
            if element.file == str(copy / path) and element.type in repo:
                assert element.version == repo.versions(element.type)[-1], (path, element.full_name)


def test_drop_removed_leaves_no_dropped_property_in_the_config_files(corpus, tmp_path, cli):
    copy = tmp_path / "configFiles"
    shutil.copytree(MODULES / "vrjuggler/data/configFiles", copy)
    before = findings(copy, paths=[copy])
    assert [d for d in before if d.code == "CFG021"]
    assert cli("upgrade", "--in-place", "--no-backup", "--drop-removed", copy).exit_code == 0
    after = findings(copy, paths=[copy])
    assert not [d for d in after if d.code in ("CFG021", "CFG012")]
    # nothing else appeared (the version-4 frame buffer config carrying a version-5 property,
    # CFG022, is version 5 now): the other findings are those of the files before
    gone = ("CFG021", "CFG012", "CFG022")
    remaining = collections.Counter(d.code for d in after)
    assert remaining == collections.Counter(d.code for d in before if d.code not in gone)


def test_upgrade_diff_of_a_file_with_one_outdated_element_changes_only_its_lines(corpus, cli):
    result = cli("upgrade", "--diff", MODULES / "vrjuggler/data/configFiles/example.vrpn.jconf")
    changed = [
        line
        for line in result.stdout.splitlines()
        if line[:1] in "+-" and line[:3] not in ("+++", "---")
    ]
    assert changed == [
        '-      <vrpn name="Vrpn" version="2">',
        '+      <vrpn name="Vrpn" version="3">',
    ]


def regenerate() -> None:
    found = keys(findings(CORPUS))
    lines = [
        "# code\tfile (relative to the corpus)\tline: configuration-level findings on the corpus,",
        "# each reviewed as a real problem of its file. Regenerate: python tests/test_config_corpus.py",
    ]
    for (code, path, line), count in sorted(
        found.items(), key=lambda item: (item[0][1], item[0][2], item[0][0])
    ):
        lines += [f"{code}\t{path}\t{line}"] * count
    PINNED.parent.mkdir(parents=True, exist_ok=True)
    PINNED.write_text("\n".join(lines) + "\n", encoding="utf-8")
    print(f"{sum(found.values())} findings written to {PINNED}")


if __name__ == "__main__":
    for name in ("VJ_BASE_DIR", "JCCL_DEFINITION_PATH", "DATA_DIR"):
        os.environ.pop(name, None)
    regenerate()
