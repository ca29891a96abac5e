"""One truth about pending elements (issue 12 item 5): `validate`'s predictions for VR
Juggler and the input manager's pending list (`config pending`, `monitor`) follow the same
rules (gadgetctl.jccl.activation), checked over every configuration of the VR Juggler
corpus. They differ only where a documented difference applies (activation.DIFFERENCES),
and then both outputs say which run time they describe."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from gadgetctl.input.dependencies import pointer_targets
from gadgetctl.input.manager import InputManager, ManagerOptions
from gadgetctl.input.pending import PendingKind
from gadgetctl.jccl.activation import DIFFERENCES, Node, RunTime, settle, too_old
from gadgetctl.validate import ValidateOptions, validate_paths

from conftest import CORPUS, REPO

#: Reasons the rules model; every other reason is the input manager's own verdict on the
#: element itself (no driver, a configuration or start failure, no definition...).
RULE_KINDS = {PendingKind.WAITING, PendingKind.MISSING_TARGET}
DESCRIBED = re.compile(r"^(\S+) '(.*?)' would stay pending")


def corpus_configurations() -> list[Path]:
    return sorted(CORPUS.rglob("*.jconf"))


class Story:
    """What validate and the input manager say about one configuration. Only the answers
    are kept, not the manager or its definition repository: the fixture holds a story for
    every corpus configuration at once (a repository each, 110 MB in all when kept)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        options = ManagerOptions(start_devices=False, retry_interval=None)
        manager, self.configuration = InputManager.from_files([path], options=options)
        with manager:
            manager.configure(self.configuration)
        repo = manager.repo
        self.elements = {e.name: e for e in self.configuration.elements}
        self.statuses = {s.name: s for s in manager.statuses()}
        self.pending = {e.name: e for e in manager.pending()}
        self.differences = {
            name: why for name in self.statuses if (why := manager.vrjuggler_difference(name))
        }
        self.targets = {
            element.name: tuple(target for _, target in pointer_targets(element, repo))
            for element in self.elements.values()
        }
        self.nodes = []
        for element in self.elements.values():
            definition = repo.get(element.type)
            handled = definition is not None and not definition.abstract
            self.nodes.append(
                Node(
                    element.name,
                    element.type,
                    element.version,
                    self.targets[element.name],
                    None if handled else "no handler",
                )
            )
        self._versions = {e.type: repo.versions(e.type) for e in self.configuration.elements}
        self.validated = validate_paths([path], ValidateOptions()).diagnostics

    def versions(self, type_name: str) -> list[int]:
        """The definition versions the manager's repository has of ``type_name``."""
        return self._versions.get(type_name, [])

    def own_verdicts(self) -> set[str]:
        """Elements the manager refuses for reasons outside the rules, and elements it does
        not handle at all (displays, users: not about input)."""
        ignored = set(self.elements) - set(self.statuses)
        own = {
            name
            for name, entry in self.pending.items()
            if entry.kind not in RULE_KINDS
            and not (
                entry.kind is PendingKind.TOO_OLD
                and too_old(entry.type, entry.element.version, self.versions(entry.type))
            )
        }
        return ignored | own

    def validate_pending(self) -> dict[str, str]:
        """Element name -> message, for validate's CFG041 findings."""
        found = {}
        for d in self.validated:
            match = DESCRIBED.match(d.message) if d.code == "CFG041" else None
            if match:
                found[match.group(2)] = d.message
        return found

    def missing_pointer_messages(self) -> dict[str, str]:
        """Top-level element name -> message, for validate's CFG031 findings (a pointer
        naming nothing)."""
        found = {}
        for d in self.validated:
            if d.code == "CFG031":
                name = re.match(r"^\S+ '(.*?)'", d.message).group(1).split("/")[0]
                found.setdefault(name, d.message)
        return found


@pytest.fixture(scope="module")
def stories(corpus) -> list[Story]:
    return [Story(path) for path in corpus_configurations()]


@pytest.mark.timeout(600)
def test_the_corpus_has_configurations_with_pending_elements_and_differences(stories):
    assert len(stories) > 100
    assert sum(bool(s.pending) for s in stories) > 20
    assert any(s.differences for s in stories)


@pytest.mark.timeout(600)
def test_the_input_manager_leaves_pending_exactly_what_the_rules_say(stories):
    wrong = []
    for story in stories:
        fate = settle(story.nodes, RunTime.GADGETCTL, story.versions, refused=story.own_verdicts())
        for name, status in story.statuses.items():
            if name not in fate:
                continue
            predicted = fate[name] is not None
            if predicted != (name in story.pending):
                wrong.append(
                    f"{story.path.relative_to(CORPUS)}: {name}: rules say "
                    f"{'pending' if predicted else 'active'}, manager says {status.state}"
                )
    assert wrong == []


@pytest.mark.timeout(600)
def test_validate_predicts_exactly_what_the_rules_say_for_vr_juggler(stories):
    wrong = []
    for story in stories:
        vrj = settle(story.nodes, RunTime.VRJUGGLER, story.versions)
        said = story.validate_pending()
        missing = story.missing_pointer_messages()
        where = story.path.relative_to(CORPUS)
        for name, why in vrj.items():
            if why is None and name in said:
                wrong.append(f"{where}: {name}: validate says pending, the rules say active")
            if why is not None and why != "no handler" and name not in said and name not in missing:
                wrong.append(
                    f"{where}: {name}: the rules say pending ({why}), validate says nothing"
                )
    assert wrong == []


@pytest.mark.timeout(600)
def test_where_the_run_times_differ_both_outputs_say_which_one_they_describe(stories):
    wrong = []
    differing_seen = 0
    for story in stories:
        vrj = settle(story.nodes, RunTime.VRJUGGLER, story.versions)
        ours = settle(story.nodes, RunTime.GADGETCTL, story.versions)
        differing = {
            name for name, why in vrj.items() if why is not None and ours.get(name, "") is None
        }
        said = {**story.missing_pointer_messages(), **story.validate_pending()}
        where = story.path.relative_to(CORPUS)
        for name in differing:
            differing_seen += 1
            # every difference traces back to a documented one
            element = story.elements[name]
            assert element.type in DIFFERENCES or any(
                t in differing for t in story.targets[name]
            ), name
            message = said.get(name, "")
            if "gadgetctl runs it" not in message:
                wrong.append(
                    f"{where}: {name}: validate does not say gadgetctl runs it: {message!r}"
                )
            status = story.statuses.get(name)
            if (
                status is not None
                and status.state not in ("pending", "unknown type")
                and not status.note
            ):
                wrong.append(
                    f"{where}: {name}: {status.state} in gadgetctl without the VR Juggler note"
                )
        for name, message in story.validate_pending().items():
            if "gadgetctl runs it" in message and name not in differing:
                wrong.append(f"{where}: {name}: validate says gadgetctl runs it, the rules do not")
        for name, status in story.statuses.items():
            if status.note and name not in differing:
                wrong.append(
                    f"{where}: {name}: noted as pending in VR Juggler, the rules do not say so"
                )
    assert differing_seen > 0
    assert wrong == []


EXAMPLE = REPO / "examples" / "all_devices.jconf"


def test_the_gesture_proxy_of_the_example_tells_one_story(cli):
    validated = cli("validate", EXAMPLE)
    assert (
        "gesture_proxy 'Gesture Proxy' would stay pending in VR Juggler (gadgetctl runs it)"
        in validated.stdout
    )
    assert (
        "alias 'VJGesture' would stay pending in VR Juggler (gadgetctl runs it)" in validated.stdout
    )
    pending = cli("config", "pending", EXAMPLE)
    assert pending.exit_code == 0
    assert (
        "Gesture Proxy (gesture_proxy) is active (VR Juggler would leave it pending: VR Juggler never "
        "handles gesture proxies" in pending.stdout
    )
    assert (
        "VJGesture (alias) is active (VR Juggler would leave it pending: it waits for gesture_proxy "
        "'Gesture Proxy'" in pending.stdout
    )
    assert "2 active that VR Juggler would leave pending" in pending.stdout


@pytest.mark.timeout(60)
def test_monitor_says_what_vr_juggler_would_do(cli):
    result = cli(
        "monitor",
        EXAMPLE,
        "Gesture Proxy",
        "Analog Proxy",
        "--duration",
        "0.3",
        "--format",
        "table",
    )
    assert result.exit_code == 0, result.stderr
    assert (
        "note: Gesture Proxy: active (VR Juggler would leave it pending: VR Juggler never handles"
        in result.stdout
    )
    assert "note: Analog Proxy" not in result.stdout and "Analog Proxy" in result.stdout


def test_a_command_proxy_without_its_device(tmp_path, cli):
    from conftest import write

    config = write(
        tmp_path / "cmd.jconf",
        """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="c">
  <elements>
    <command_proxy name="Speech" version="1"><device>Recogniser</device><unit>0</unit></command_proxy>
    <alias name="VJSpeech" version="1"><proxy>Speech</proxy></alias>
  </elements>
</configuration>
""",
    )
    validated = cli("validate", config)
    assert "keeps it pending forever (gadgetctl runs it)" in validated.stdout
    assert (
        "alias 'VJSpeech' would stay pending in VR Juggler (gadgetctl runs it)" in validated.stdout
    )
    pending = cli("config", "pending", config)
    assert (
        "Speech (command_proxy) is stupefied (VR Juggler would leave it pending: unlike most proxies"
        in pending.stdout
    )
    assert (
        "VJSpeech (alias) is active (VR Juggler would leave it pending: it waits for command_proxy "
        "'Speech'" in pending.stdout
    )
