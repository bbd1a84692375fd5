"""The learning presets as data: typed values, each with its evidence, and one-line errors."""

from __future__ import annotations

import re

import pytest

from rnnpb.errors import ConfigError
from rnnpb.presets import (
    KINDS,
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

# The values whose evidence is ``unmeasured`` and yet gives a figure or draws: chosen on a
# measure that cannot be repeated (a search or harness that was not kept; a command, where one
# is given, repeats only *such* a search, whose figure may differ). This list may only shrink:
# a value chosen from now on names the harness that measured it (kind "measured"), and a value
# whose measure becomes repeatable leaves the list.
UNMEASURED = {
    "paper": {
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
    },
    "fast": {
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
    },
}


def _measured_once(source: Source) -> bool:
    """Evidence that cannot be repeated: a measure made once, by a search or harness that was
    not kept."""
    return source.kind == "unmeasured" and source.claims_a_measure


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
            assert source.kind in KINDS, (section, key)
            # A value claims a measure only as "measured", with the command that repeats it,
            # or as one of the known values measured once by what was not kept (UNMEASURED).
            if source.kind == "measured":
                assert source.command and source.figure, (section, key)
            elif source.claims_a_measure:
                assert key in UNMEASURED[name].get(section, ()), (
                    f"[{section}] {key}: its evidence {source.id!r} gives a figure or draws but "
                    "no harness that repeats them: measure it, or say it claims none"
                )
            else:
                assert source.note, (section, key)
            assert all(isinstance(draw, int) for draw in source.draws)
            used.add(source.id)
    assert used == set(preset.sources), f"sources no value names: {set(preset.sources) - used}"


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_values_measured_once_are_a_list_that_only_shrinks(name):
    preset = load_preset(name)
    found = {
        (section, key)
        for section in preset.sections
        for key in preset.section(section)
        if _measured_once(preset.evidence(section, key))
    }
    known = {(section, key) for section, keys in UNMEASURED[name].items() for key in keys}
    new = sorted(found - known)
    assert not new, (
        f"values of the {name} preset chosen on evidence that cannot be repeated: {new}; name "
        "the harness that measures them"
    )
    gone = sorted(known - found)
    assert not gone, f"the {name} preset's {gone} can be repeated now: drop them from UNMEASURED"


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


def _source_field(text: str, source: str, key: str, value: str) -> str:
    """The preset file's text with ``[sources.<source>]``'s ``key`` set to ``value`` (TOML)."""
    head = f"[sources.{source}]\n"
    start = text.index(head) + len(head)
    end = text.find("\n[", start)
    block = text[start:end]
    changed, count = re.subn(rf"(?m)^{key} = .*$", f"{key} = {value}", block)
    if not count:
        changed = block + f"{key} = {value}\n"
    return text[:start] + changed + text[end:]


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
        (lambda t: t.replace('figure = ""\n', "", 1), "must hold exactly kind, command, draws"),
        (lambda t: t.replace('\nkind = "paper"', '\nkind = "guessed"', 1), "kind must be one of"),
        (
            lambda t: t.replace(
                'kind = "documented"\ncommand = ""',
                'kind = "documented"\ncommand = "python tools/structure_periods.py"',
                1,
            ),
            "is documented: it claims no measure",
        ),
        (
            lambda t: _source_field(t, "structure-periods", "command", '""'),
            "is measured: it needs the command and the figure",
        ),
        (
            lambda t: _source_field(t, "structure-periods", "command", '"rnnpb study novelty"'),
            "command must run a harness of the checkout",
        ),
        (
            lambda t: _source_field(t, "structure-periods", "cost", '"free"'),
            "cost must be one of cheap, costly",
        ),
        (
            lambda t: _source_field(
                t, "structure-periods", "command", '"python tools/structure_periods.py"'
            ),
            "expect needs the command to name JSON",
        ),
        (
            lambda t: _source_field(
                t, "structure-periods", "expect", "{ shapes_max = 0.244, tolerance = -1 }"
            ),
            "expect.tolerance must be a number >= 0",
        ),
        (
            lambda t: _source_field(t, "structure-periods", "expect", "{ shapes_max = [1] }"),
            "expect.shapes_max must be a number",
        ),
        (
            lambda t: t.replace(
                'kind = "unmeasured"\ncommand = ""',
                'kind = "unmeasured"\ncost = "cheap"\ncommand = ""',
                1,
            ),
            "only a measured source has a cost",
        ),
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
