"""Exam versions: a value changed without a new version fails here, and no two exams (nor two
judged versions of one) share a draw."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import pytest

from rnnpb._fingerprint import values_fingerprint
from rnnpb.errors import ConfigError
from rnnpb.experiments.exams import (
    check_recorded,
    exam_fingerprint,
    exam_names,
    load_exam,
    parse_exam,
    recorded_versions,
)
from rnnpb.experiments.exams import ledger as exam_ledger

ROOT = Path(__file__).resolve().parents[2]
EXAMS = ROOT / "src" / "rnnpb" / "experiments" / "exams"

# Seeds a study derives from its exam's draws: the teach study's run teaching the k-th shape
# takes the user's seed + k, and its paced run the seed + 7 (exams/teach.toml).
DERIVED = {("teach", "user"): range(8)}


@pytest.mark.parametrize("name", exam_names())
def test_every_exam_version_is_recorded_with_the_fingerprint_of_its_values(name):
    exam = load_exam(name)
    recorded = recorded_versions().get((name, exam.version))
    assert recorded is not None, (
        f"record the {name} exam's version {exam.version} in exams/versions.toml: "
        f'fingerprint = "{exam.fingerprint}"'
    )
    assert recorded.fingerprint == exam.fingerprint, (
        f"the {name} exam's values changed under version {exam.version} (now "
        f"{exam.fingerprint}, recorded {recorded.fingerprint}): make a new version with fresh "
        "draws, its old draws excluded"
    )
    check_recorded(exam)
    # Every earlier version is recorded too, and the versions count up from 1.
    versions = sorted(v for (study, v) in recorded_versions() if study == name)
    assert versions == list(range(1, exam.version + 1))


def test_the_fingerprint_covers_the_values_and_nothing_else():
    text = (EXAMS / "novelty.toml").read_text(encoding="utf-8")
    data = tomllib.loads(text)
    base = exam_fingerprint(data)
    assert parse_exam(data).fingerprint == base
    # Comments, the version, the excluded draws and the order of a table's keys: the same.
    assert exam_fingerprint(tomllib.loads("# a comment\n" + text)) == base
    moved = {**data, "exam": {**data["exam"], "version": 9}, "excluded": []}
    assert exam_fingerprint(moved) == base
    reordered = {**data, "targets": dict(reversed(list(data["targets"].items())))}
    assert exam_fingerprint(reordered) == base
    # A limit, a draw, a parameter, a count written as a float: another fingerprint.
    targets = data["targets"]
    for changed in (
        {
            **data,
            "targets": {
                **targets,
                "still_called_still": {**targets["still_called_still"], "limit": 0.91},
            },
        },
        {**data, "draws": {**data["draws"], "user": [7010, 7012]}},
        {**data, "draws": {**data["draws"], "user": [7011, 7010]}},
        {**data, "parameters": {"settle_steps": 24.0}},
    ):
        assert exam_fingerprint(changed) != base
    with pytest.raises(ConfigError, match="values changed under version 2"):
        check_recorded(parse_exam({**data, "draws": {**data["draws"], "user": [7012, 7013]}}))
    with pytest.raises(ConfigError, match="not recorded"):
        check_recorded(parse_exam({**data, "exam": {"study": "novelty", "version": 99}}))


def test_the_versions_file_is_no_exam():
    assert "versions" not in exam_names()


def _judged_seeds() -> dict[tuple[str, int], frozenset[int]]:
    """The seeds of every judged run in the ledger, by (study, version)."""
    seeds: dict[tuple[str, int], set[int]] = {}
    for entry in exam_ledger.entries():
        if entry.judged:
            seeds.setdefault((entry.study, entry.version), set()).update(entry.seeds())
    return {key: frozenset(value) for key, value in seeds.items()}


def _exam_seeds(study: str, kinds: dict[str, list[int]] | dict[str, tuple[int, ...]]) -> set[int]:
    """Every seed an exam's draws make the study use, derived ones included."""
    out: set[int] = set()
    for kind, values in kinds.items():
        for seed in values:
            out.update(seed + k for k in DERIVED.get((study, kind), range(1)))
    return out


GAME_DRAWS = ROOT / "benchmarks" / "game_players_final.json"


def _game() -> dict:
    """The mirror game's judged draws as their file holds them (its current version)."""
    return json.loads(GAME_DRAWS.read_text(encoding="utf-8"))


def _all_versions() -> dict[tuple[str, int], set[int]]:
    """Each study's current exam, the mirror game's current draws and every judged version in
    the ledger, with its seeds."""
    versions: dict[tuple[str, int], set[int]] = {}
    for name in exam_names():
        exam = load_exam(name)
        versions[name, exam.version] = _exam_seeds(name, dict(exam.seeds))
    game = _game()
    versions["game", game["version"]] = set(game["player_seeds"]) | set(game["scribbler_seeds"])
    for entry in exam_ledger.entries():
        if entry.judged:
            kinds = {
                k: v
                for k, v in entry.draws.items()
                if isinstance(v, list) and all(isinstance(s, int) for s in v)
            }
            versions.setdefault((entry.study, entry.version), set()).update(
                _exam_seeds(entry.study, kinds)
            )
    return versions


def test_no_two_exams_share_a_draw():
    """A seed seeds one exam's runs only: two studies never judge on the same draw, and a
    study's versions never judge twice on one (a new version draws fresh seeds)."""
    versions = _all_versions()
    shared = []
    keys = sorted(versions)
    for i, a in enumerate(keys):
        for b in keys[i + 1 :]:
            common = versions[a] & versions[b]
            if common:
                shared.append(f"{a[0]} v{a[1]} and {b[0]} v{b[1]}: {sorted(common)}")
    assert not shared, "exams share draws: " + "; ".join(shared)


def test_a_judged_version_s_draws_are_excluded_by_its_study_s_exam():
    for (study, version), seeds in _all_versions().items():
        if study not in exam_names() or version == load_exam(study).version:
            continue
        exam = load_exam(study)
        free = sorted(s for s in seeds if not any(s in r for r in exam.excluded))
        assert not free, f"the {study} exam does not exclude version {version}'s draws {free}"


def test_excluded_ranges_do_not_overlap_within_an_exam():
    for name in exam_names():
        ranges = sorted((r.first, r.last) for r in load_exam(name).excluded)
        for (_, last), (first, _) in zip(ranges, ranges[1:], strict=False):
            assert first > last, f"the {name} exam's excluded ranges overlap at {first}"


def test_the_dyad_exam_left_the_safety_exam_s_draws():
    dyad, safety = load_exam("dyad"), load_exam("safety")
    assert not dyad.draws() & safety.draws()
    # Version 1's draws (never judged) stay excluded.
    assert all(any(s in r for r in dyad.excluded) for s in range(7200, 7212))


def test_the_mirror_game_s_draws_are_versioned_as_the_ledger_records_them():
    """The game's judged runs carry the fingerprint its versions.toml entry records for their
    version; the draws file's version is recorded with the fingerprint of its seed lists,
    was judged at most once by a run of its own, and excludes every earlier version's seeds."""
    game = _game()
    draws = {k: game[k] for k in ("player_seeds", "scribbler_seeds")}
    recorded = recorded_versions()
    assert recorded["game", game["version"]].fingerprint == values_fingerprint(draws)
    runs = [e for e in exam_ledger.entries("game") if e.judged]
    assert runs and all(e.fingerprint == recorded["game", e.version].fingerprint for e in runs)
    judged = exam_ledger.judged_versions("game")
    assert max(judged) <= game["version"] and set(range(1, game["version"])) <= judged
    this = [e for e in runs if e.version == game["version"]]
    assert len(this) <= 1 and all(e.recorded == "run" for e in this)
    excluded = [range(first, last + 1) for first, last, _ in game["excluded"]]
    for entry in runs:
        if entry.version < game["version"]:
            assert all(any(s in r for r in excluded) for s in entry.seeds()), entry.run
    assert not any(s in r for r in excluded for v in draws.values() for s in v)


def test_the_mirror_game_is_an_exam_the_ledger_knows(tmp_path):
    """benchmarks/game_players.py --draws reads the file as an exam of study "game": its
    version may run until judged, then is refused, as version 1's draws, judged twice, are."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "game_players", ROOT / "benchmarks" / "game_players.py"
    )
    assert spec is not None and spec.loader is not None
    players = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(players)
    exam = players.game_exam(GAME_DRAWS)
    assert exam.study == "game" and exam.version == _game()["version"]
    if exam.version in exam_ledger.judged_versions("game"):
        with pytest.raises(ConfigError, match=f"game exam's version {exam.version} was judged"):
            exam_ledger.check_may_run(exam, exam_ledger.ledger_paths())
    else:
        assert exam_ledger.check_may_run(exam, exam_ledger.ledger_paths()) == ()
    first = {
        "version": 1,
        "player_seeds": list(range(1000, 1020)),
        "scribbler_seeds": list(range(1000, 1006)),
        "excluded": [[0, 9, "development"]],
    }
    old = tmp_path / "game_v1.json"
    old.write_text(json.dumps(first), encoding="utf-8")
    with pytest.raises(ConfigError, match="game exam's version 1 was judged already"):
        exam_ledger.check_may_run(players.game_exam(old), exam_ledger.ledger_paths())
    old.write_text(json.dumps({**first, "player_seeds": [1000, 1001]}), encoding="utf-8")
    with pytest.raises(SystemExit, match="values changed under version 1"):
        players.game_exam(old)
