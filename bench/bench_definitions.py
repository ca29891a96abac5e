"""Issue 3 benchmark: loading and resolving the bundled definition repository."""

from __future__ import annotations

from common import Report, median_time
from lxml import etree

from gadgetctl.jccl.repository import default_repository
from gadgetctl.resources import definitions_dir

files = sorted(definitions_dir().glob("*.jdef"))


def load_and_resolve():
    repo = default_repository()
    for name in repo.names():
        for version in repo.versions(name):
            repo.effective_properties(name, version)
        repo.ancestors(name)
    return repo


def parse_only():
    parser = etree.XMLParser(resolve_entities=False, no_network=True)
    for path in files:
        etree.parse(str(path), parser)


load_and_resolve()  # warm the file cache
report = Report()
repo = load_and_resolve()
versions = sum(len(repo.versions(n)) for n in repo.names())
print(
    f"bundled repository: {len(files)} files, {len(repo.names())} definitions, {versions} versions"
)
ours = median_time(load_and_resolve, repeat=11)
base = median_time(parse_only, repeat=11)
report.figure("load + resolve all versions and inheritance", ours * 1000, "ms", target=50)
report.figure("lxml parse of the same files (baseline)", base * 1000, "ms")
report.ratio("load+resolve / parse", ours, base)
report.exit()
