"""`upgrade --check` never passes a file it cannot check (issue 25 item 3): an element whose
type has no definition on the search path is CFG010, as `validate` says, and the file is not
"up to date"."""

from __future__ import annotations

from conftest import write

UNKNOWN = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="c">
  <elements>
    <acme_tracker name="Lab Tracker" version="1"><port>/dev/ttyS0</port></acme_tracker>
  </elements>
</configuration>
"""


def test_check_fails_a_file_with_a_type_it_cannot_check(cli, tmp_path):
    config = write(tmp_path / "lab.jconf", UNKNOWN)
    result = cli("upgrade", "--check", config)
    assert result.exit_code == 1
    assert "all up to date" not in result.stdout
    assert (
        f"{config}:5: error CFG010 acme_tracker 'Lab Tracker': no definition of acme_tracker on "
        "the search path" in result.stderr
    )
    assert "1 of 1 file could not be upgraded" in result.stdout
    validated = cli("validate", config)
    assert validated.exit_code == 1 and "CFG010" in validated.stdout  # the same verdict


def test_in_place_leaves_such_a_file_as_it_was(cli, tmp_path):
    config = write(tmp_path / "lab.jconf", UNKNOWN)
    result = cli("upgrade", "--in-place", config)
    assert result.exit_code == 1
    assert config.read_text() == UNKNOWN
