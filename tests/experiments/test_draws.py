"""The report's figures over several draws of the user's imperfection: per-draw counts and the
targets over all draws pooled, from constructed job results whose answer is known."""

import math

import pytest

from rnnpb.errors import ConfigError
from rnnpb.experiments import (
    Draw,
    ExperimentConfig,
    FollowsEveryPattern,
    Switching,
    Synchronization,
    Target,
    draws_summary,
)


def _sync(pattern, lock, settle, relock):
    return Synchronization(
        pattern=pattern,
        steps_to_lock=lock,
        pb_settle_steps=settle,
        phase_lag_steps=math.nan,
        recognized_pattern=pattern,
        pb_distance_to_learned=0.0,
        pause_relative_motion=1.0,
        pause_steps_to_relock=relock,
        pause_start=75,
        pause_end=80,
        run=None,
    )


def _job(first, other):
    """One learning set's draws: patterns 1 and 2; ``first`` and ``other`` are
    (lock, settle, relock, switch 1->2, switch 2->1) for the report's draw and draw 200."""

    def draw(values):
        lock, settle, relock, s12, s21 = values
        return Draw(
            [_sync("1", lock, settle, relock), _sync("2", 3, 10, 2)],
            Switching({"1->2": s12, "2->1": s21}),
        )

    return {100: draw(first), 200: draw(other)}


def _follows(*draws):
    return {
        seed: FollowsEveryPattern({"1": steps}, ok)
        for seed, (steps, ok) in zip((100, 200), draws, strict=True)
    }


def test_counts_per_draw_and_pooled():
    sets = {"1": _job((4, 15, 5, 7, 15), (12, None, 6, 16, 3))}
    larger = [_follows((5, True), (16, False)), _follows((6, True), (7, True))]
    out = draws_summary(sets, larger, (100, 200))
    assert out.scenario_seeds == [100, 200]
    first, second = out.by_seed["100"], out.by_seed["200"]
    assert first.sync_steps_to_lock == {"1": {"1": 4, "2": 3}}
    assert first.targets["lock_within_10"] == Target(True, "2/2 within 10")
    assert first.targets["relock_within_5"].met
    assert first.targets["switch_within_15"] == Target(True, "2/2 within 15")
    assert first.larger_set_success == 2
    assert second.pb_settle_steps == {"1": {"1": None, "2": 10}}
    assert second.targets["lock_within_10"] == Target(False, "1/2 within 10")
    assert second.targets["pb_settles_within_20"].detail == "1/2 within 20"
    assert second.targets["switch_within_15"].detail == "1/2 within 15"
    assert second.larger_set_success == 1
    assert second.targets["larger_set_9_of_10"] == Target(False, "1/2")
    pooled = out.targets
    assert pooled["lock_within_10"] == Target(False, "3/4 within 10")
    assert pooled["relock_within_5"] == Target(False, "3/4 within 5")
    assert pooled["larger_set_9_of_10"] == Target(False, "3/4")
    # results.json keeps exactly these values, in this order.
    assert list(out.to_json()["by_seed"]["200"]) == [
        "sync_steps_to_lock",
        "pb_settle_steps",
        "pause_steps_to_relock",
        "switch_steps",
        "larger_set_success",
        "larger_set_steps_to_follow",
        "targets",
    ]
    assert out.to_json()["targets"]["larger_set_9_of_10"] == {"met": False, "detail": "3/4"}


def test_one_draw_only():
    sets = {"1": {100: Draw([_sync("1", 4, 15, 5)], Switching({}))}}
    out = draws_summary(sets, [], (100,))
    assert out.scenario_seeds == [100]
    assert out.targets["lock_within_10"].met
    assert "larger_set_9_of_10" not in out.targets


def test_a_draw_given_twice_is_refused():
    with pytest.raises(ConfigError, match="scenario seeds must differ"):
        ExperimentConfig(scenario_seed=100, extra_scenario_seeds=(200, 100))
