"""The learning presets as data: typed values, each with its evidence, and one-line errors."""

from __future__ import annotations

import re

import pytest

from rnnpb.errors import ConfigError
from rnnpb.presets import (
    PRESET_NAMES,
    Source,
    load_preset,
    read_overrides,
    read_preset,
    recorded_versions,
)
from rnnpb.presets import __file__ as presets_init

SECTIONS = (
    "learning",
    "online",
    "recognition",
    "recognition_untaught",
    "consolidation",
    "teaching",
)

# The values whose evidence cannot be repeated (:func:`_not_kept`): a figure measured by a
# search or harness that was not kept, or a command that repeats only *such* a search. This
# list may only shrink: a value chosen from now on names the command that measured it, and a
# value whose measure becomes repeatable leaves the list.
NOT_KEPT = {
    "paper": {
        "learning": ("learning_rate",),
        "learning.pb": ("learning_rate", "k_nb"),
        "online": (
            "optimize_onset",
            "onset_learning_rate",
            "restart_span",
            "motor_input",
            "surprise_gate",
            "gate_power",
            "phase_restarts",
            "phase_restart_ratio",
            "phase_restart_level",
        ),
        "online.pb": ("learning_rate", "k_nb", "integration_length"),
        "recognition": (
            "evidence_steps",
            "match_scale",
            "match_level",
            "pb_steps",
            "pb_scale",
            "pb_level",
            "confidence_level",
            "structure_level",
            "switch_steps",
            "release_steps",
            "template_scale",
            "template_level",
        ),
        "recognition_untaught": (
            "evidence_steps",
            "match_scale",
            "match_level",
            "pb_steps",
            "pb_scale",
            "pb_level",
            "confidence_level",
            "structure_level",
            "switch_steps",
            "release_steps",
        ),
        "consolidation": (
            "iterations",
            "input_noise",
            "function_rehearsal_input_noise",
            "hold_old_pb",
            "new_pb_start",
            "rehearsal_target",
        ),
    },
    "fast": {
        "learning": ("iterations", "optimizer", "learning_rate", "input_noise"),
        "learning.pb": ("learning_rate", "k_nb"),
        "online": (
            "optimize_onset",
            "onset_learning_rate",
            "restart_span",
            "motor_input",
            "surprise_gate",
            "gate_power",
            "phase_restarts",
            "phase_restart_ratio",
            "phase_restart_level",
        ),
        "online.pb": ("learning_rate", "k_nb", "integration_length"),
        "recognition": (
            "evidence_steps",
            "match_scale",
            "match_level",
            "pb_steps",
            "pb_scale",
            "pb_level",
            "confidence_level",
            "structure_level",
            "switch_steps",
            "release_steps",
            "template_scale",
            "template_level",
        ),
        "recognition_untaught": (
            "evidence_steps",
            "match_scale",
            "match_level",
            "pb_steps",
            "pb_scale",
            "pb_level",
            "confidence_level",
            "switch_steps",
            "release_steps",
        ),
        "consolidation": (
            "input_noise",
            "function_rehearsal_input_noise",
            "hold_old_pb",
            "new_pb_start",
            "rehearsal_target",
        ),
    },
}


def _claims_a_measure(source: Source) -> bool:
    """Whether a source says a value was measured: it gives a figure or the draws."""
    return bool(source.figure or source.draws)


def _not_kept(source: Source) -> bool:
    """Evidence that cannot be repeated: a measure with no command, or a command that only
    repeats a search like the one that chose the value, which was not kept."""
    return (not source.command and _claims_a_measure(source)) or "not kept" in source.note


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_every_value_has_evidence_from_a_named_source(name):
    preset = load_preset(name)
    assert isinstance(preset.version, int) and not isinstance(preset.version, bool)
    assert set(SECTIONS) <= set(preset.sections)
    used = set()
    for section in preset.sections:
        assert preset.section(section), section
        for key in preset.section(section):
            source = preset.evidence(section, key)
            assert source.id in preset.sources
            # Every source says where the value comes from: the command that measured it, or
            # a note. A note alone is evidence only for a value that claims no measure (the
            # paper's, a reading of it, set when built, unused: no figure, no draws) or one
            # of the known values whose measure was not kept (NOT_KEPT, below).
            assert source.command or source.note, (section, key)
            if not source.command and _claims_a_measure(source):
                assert key in NOT_KEPT[name].get(section, ()), (
                    f"[{section}] {key}: its evidence {source.id!r} gives a figure but no "
                    "command that measures it"
                )
            assert all(isinstance(draw, int) for draw in source.draws)
            used.add(source.id)
    assert used == set(preset.sources), f"sources no value names: {set(preset.sources) - used}"


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_values_whose_evidence_was_not_kept_are_a_list_that_only_shrinks(name):
    preset = load_preset(name)
    found = {
        (section, key)
        for section in preset.sections
        for key in preset.section(section)
        if _not_kept(preset.evidence(section, key))
    }
    known = {(section, key) for section, keys in NOT_KEPT[name].items() for key in keys}
    new = sorted(found - known)
    assert not new, (
        f"values of the {name} preset chosen on evidence that was not kept: {new}; name the "
        "command that measures them"
    )
    gone = sorted(known - found)
    assert not gone, f"the {name} preset's {gone} can be repeated now: drop them from NOT_KEPT"


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_a_preset_s_values_do_not_change_without_a_new_version(name):
    preset = load_preset(name)
    recorded = recorded_versions().get((name, preset.version))
    assert recorded is not None and recorded.fingerprint == preset.fingerprint, (
        f"the {name} preset's values changed under version {preset.version}: raise its "
        f'version and record it in presets/versions.toml: fingerprint = "{preset.fingerprint}"'
    )
    versions = sorted(v for (n, v) in recorded_versions() if n == name)
    assert versions == list(range(1, preset.version + 1))


def test_the_fingerprint_covers_the_values_not_the_evidence(tmp_path):
    text = _shipped_text()
    path = tmp_path / "paper.toml"
    path.write_text(text.replace("draws = [100]", "draws = [100, 101]", 1), encoding="utf-8")
    assert read_preset(path).fingerprint == load_preset("paper").fingerprint
    path.write_text(text.replace("window = 30", "window = 31", 1), encoding="utf-8")
    assert read_preset(path).fingerprint != load_preset("paper").fingerprint


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_values_are_typed(name):
    preset = load_preset(name)
    learning = preset.section("learning")
    assert isinstance(learning["iterations"], int) and isinstance(learning["learning_rate"], float)
    assert learning["learn_initial_context"] in (True, False)
    recognition = preset.section("recognition")
    # Lists come back as tuples: the compiled code hashes its static settings.
    assert recognition["lags"] == (5, 40)
    assert all(isinstance(speed, float) for speed in recognition["template_speeds"])
    assert isinstance(preset.section("online.pb")["integration_length"], int)
    with pytest.raises(TypeError):
        preset.section("online")["window"] = 10  # type: ignore[index]


def test_the_presets_differ_where_their_learning_does():
    paper, fast = load_preset("paper"), load_preset("fast")
    assert paper.section("learning")["optimizer"] == "momentum"
    assert fast.section("learning")["optimizer"] == "adam"
    assert paper.section("online")["surprise_gate"] > 0 == fast.section("online")["surprise_gate"]
    assert "paper_online" in paper.sections


def test_loading_is_cached():
    assert load_preset("paper") is load_preset("paper")


def test_an_unknown_preset_is_one_line():
    with pytest.raises(ConfigError, match="unknown learning preset 'slow'") as error:
        load_preset("slow")
    assert "\n" not in str(error.value)


def _version(text: str, value: str) -> str:
    """The preset file's text with its version written as ``value``."""
    changed = re.sub(r"(?m)^version = \d+$", f"version = {value}", text, count=1)
    assert changed != text
    return changed


def _shipped_text() -> str:
    from pathlib import Path

    return (Path(presets_init).parent / "paper.toml").read_text(encoding="utf-8")


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda t: _version(t, '"2"'), "'version' must be a whole number"),
        (lambda t: _version(t, "true"), "'version' must be a whole number"),
        (lambda t: t.replace("[learning]\n", "[learning\n", 1), "not TOML"),
        (
            lambda t: t.replace('surprise_gate = "surprise-gate"', ""),
            r"\[online\] surprise_gate has no evidence",
        ),
        (
            lambda t: t.replace('surprise_gate = "surprise-gate"', 'surprise_gate = "nowhere"'),
            "names no source",
        ),
        (lambda t: t.replace("draws = [100]", 'draws = ["100"]', 1), "draws must be whole"),
        (lambda t: t + '\n[evidence.online]\nwindw = "paper"\n', "not TOML"),
        (
            lambda t: t.replace("[evidence.online]\n", '[evidence.online]\nwindw = "paper"\n'),
            "evidence for 'windw'",
        ),
        (lambda t: t.replace('figure = ""\n', "", 1), "must hold exactly command, draws"),
    ],
)
def test_a_malformed_preset_file_is_one_line(tmp_path, change, message):
    text = change(_shipped_text())
    path = tmp_path / "paper.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ConfigError, match=message) as error:
        read_preset(path)
    assert "\n" not in str(error.value)
    assert str(path) in str(error.value)


def test_the_shipped_file_reads_as_it_loads(tmp_path):
    path = tmp_path / "paper.toml"
    path.write_text(_shipped_text(), encoding="utf-8")
    read = read_preset(path)
    assert read.name == "paper"
    assert {s: dict(read.section(s)) for s in read.sections} == {
        s: dict(load_preset("paper").section(s)) for s in read.sections
    }


def test_overrides_replace_values_and_name_their_file(tmp_path):
    path = tmp_path / "research.toml"
    path.write_text("[online]\nsurprise_gate = 0\n[online.pb]\nk_nb = 0.1\n", encoding="utf-8")
    preset = load_preset("paper").overridden(read_overrides(path), str(path))
    assert preset.section("online")["surprise_gate"] == 0.0
    assert isinstance(preset.section("online")["surprise_gate"], float)
    assert preset.section("online.pb")["k_nb"] == 0.1
    assert preset.evidence("online", "surprise_gate").note == f"set by {path}"
    assert preset.section("online")["window"] == 30
    assert load_preset("paper").section("online")["surprise_gate"] == 0.035


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("[online]\nsurprise_gat = 0.0\n", "unknown setting 'surprise_gat' in \\[online\\]"),
        ("[onlin]\nsurprise_gate = 0.0\n", "unknown setting 'surprise_gate' in \\[onlin\\]"),
        ('[online]\nwindow = "long"\n', "\\[online\\] window must be a int"),
        ("[online]\noptimize_onset = 1\n", "\\[online\\] optimize_onset must be a bool"),
        ("window = 3\n", "unknown setting 'window'"),
        ("[online\n", "not TOML"),
    ],
)
def test_a_bad_override_is_one_line_naming_file_and_key(tmp_path, text, message):
    path = tmp_path / "research.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ConfigError, match=message) as error:
        load_preset("paper").overridden(read_overrides(path), str(path))
    assert "\n" not in str(error.value) and str(path) in str(error.value)
