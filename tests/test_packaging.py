"""`pip install .` (a real wheel, not editable) carries schemas, definitions, drivers and examples."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import zipfile

import pytest

from conftest import CORPUS, REPO


@pytest.fixture(scope="module")
def unpacked_wheel(tmp_path_factory):
    out = tmp_path_factory.mktemp("wheel")
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "wheel",
            "--no-deps",
            "--no-build-isolation",
            "-q",
            "-w",
            str(out),
            str(REPO),
        ],
        check=True,
        timeout=120,
        capture_output=True,
    )
    (wheel,) = out.glob("gadgetctl-*.whl")
    target = out / "site"
    with zipfile.ZipFile(wheel) as archive:
        names = archive.namelist()
        archive.extractall(target)
    return target, names


def test_wheel_contains_bundled_data(unpacked_wheel):
    _, names = unpacked_wheel
    for required in (
        "gadgetctl/_data/schemas/configuration-3.0.xsd",
        "gadgetctl/_data/schemas/definition-3.1.xsd",
        "gadgetctl/_data/definitions/dtrack.jdef",
        "gadgetctl/cli/main.py",
    ):
        assert required in names, required
    assert any(n.startswith("gadgetctl/_data/drivers/") for n in names)
    assert any(n.startswith("gadgetctl/_data/examples/") for n in names)
    assert any(n.endswith("entry_points.txt") for n in names)


def test_installed_wheel_validates_the_corpus_from_the_repo_root(unpacked_wheel):
    site, _ = unpacked_wheel
    env = {**os.environ, "PYTHONPATH": str(site)}
    probe = subprocess.run(
        [sys.executable, "-c", "import gadgetctl.resources as r; print(r.data_root())"],
        env=env,
        capture_output=True,
        text=True,
        check=True,
        cwd=REPO,
        timeout=30,
    )
    assert probe.stdout.strip() == str(site / "gadgetctl" / "_data")
    rel = os.path.relpath(CORPUS, REPO)
    proc = subprocess.run(
        [sys.executable, "-m", "gadgetctl", "validate", rel, "--format", "json"],
        env=env,
        capture_output=True,
        text=True,
        cwd=REPO,
        timeout=60,
    )
    assert proc.returncode == 1, proc.stderr
    found = json.loads(proc.stdout)
    assert {d["category"] for d in found} >= {"xml", "schema"}
    assert not proc.stderr
