"""The report's figures over several draws of the user's imperfection: per-draw counts and the
targets over all draws pooled, from constructed job results whose answer is known."""

import pytest

from rnnpb.errors import ConfigError
from rnnpb.experiments import ExperimentConfig
from rnnpb.experiments.report import draws_summary


def _sync(pattern, lock, settle, relock):
    return {"pattern": pattern, "steps_to_lock": lock, "pb_settle_steps": settle,
            "pause_steps_to_relock": relock, "recognized_pattern": pattern}


def _job(first, other):
    """One learning set's job: patterns 1 and 2; ``first`` and ``other`` are
    (lock, settle, relock, switch 1->2, switch 2->1) for the report's draw and draw 200."""
    def draw(values):
        lock, settle, relock, s12, s21 = values
        return ([_sync("1", lock, settle, relock), _sync("2", 3, 10, 2)],
                {"pairs": {"1->2": s12, "2->1": s21}})
    sync, switching = draw(first)
    sync2, switching2 = draw(other)
    return {"synchronization": sync, "switching": switching,
            "draws": {200: {"synchronization": sync2, "switching": switching2}}}


def test_counts_per_draw_and_pooled():
    config = ExperimentConfig(scenario_seed=100, extra_scenario_seeds=(200,))
    results = {"1": _job((4, 15, 5, 7, 15), (12, None, 6, 16, 3))}
    larger = [{"follows_all": True, "steps_to_follow": {"1": 5},
               "draws": {200: {"follows_all": False, "steps_to_follow": {"1": 16}}}},
              {"follows_all": True, "steps_to_follow": {"1": 6},
               "draws": {200: {"follows_all": True, "steps_to_follow": {"1": 7}}}}]
    out = draws_summary(results, larger, config)
    assert out["scenario_seeds"] == [100, 200]
    first, second = out["by_seed"]["100"], out["by_seed"]["200"]
    assert first["sync_steps_to_lock"] == {"1": {"1": 4, "2": 3}}
    assert first["targets"]["lock_within_10"] == {"met": True, "detail": "2/2 within 10"}
    assert first["targets"]["relock_within_5"]["met"]
    assert first["targets"]["switch_within_15"] == {"met": True, "detail": "2/2 within 15"}
    assert first["larger_set_success"] == 2
    assert second["pb_settle_steps"] == {"1": {"1": None, "2": 10}}
    assert second["targets"]["lock_within_10"] == {"met": False, "detail": "1/2 within 10"}
    assert second["targets"]["pb_settles_within_20"]["detail"] == "1/2 within 20"
    assert second["targets"]["switch_within_15"]["detail"] == "1/2 within 15"
    assert second["larger_set_success"] == 1
    assert second["targets"]["larger_set_9_of_10"] == {"met": False, "detail": "1/2"}
    pooled = out["targets"]
    assert pooled["lock_within_10"] == {"met": False, "detail": "3/4 within 10"}
    assert pooled["relock_within_5"] == {"met": False, "detail": "3/4 within 5"}
    assert pooled["larger_set_9_of_10"] == {"met": False, "detail": "3/4"}


def test_one_draw_only():
    config = ExperimentConfig(extra_scenario_seeds=())
    results = {"1": {"synchronization": [_sync("1", 4, 15, 5)],
                     "switching": {"pairs": {}}, "draws": {}}}
    out = draws_summary(results, [], config)
    assert out["scenario_seeds"] == [100]
    assert out["targets"]["lock_within_10"]["met"]
    assert "larger_set_9_of_10" not in out["targets"]


def test_a_draw_given_twice_is_refused():
    with pytest.raises(ConfigError, match="scenario seeds must differ"):
        ExperimentConfig(scenario_seed=100, extra_scenario_seeds=(200, 100))
