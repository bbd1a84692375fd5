"""``rnnpb study teach --quick``: a new shape is noticed, kept, consolidated and followed."""

from __future__ import annotations

import json

import pytest

from rnnpb.analysis import metrics
from rnnpb.experiments.studies import StudyOptions, load_study


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("teach")
    outcome = load_study("teach").run(out, StudyOptions(quick=True))
    return out, outcome, json.loads((out / "results.json").read_text())


def test_the_new_shape_is_kept_learned_and_followed_and_nothing_unstructured_is_kept(study):
    out, outcome, results = study
    (run,) = results["runs"]
    assert run["shape"] == "figure-eight"
    episodes = run["episodes"]
    # one episode of whole cycles of the new shape, none with the random walk or jerky
    # movement of the timeline's unstructured part
    assert episodes and all(set(e["movements"]) == {"figure-eight"} for e in episodes)
    # noticed while the shape was being performed (how soon is the novelty study's measure)
    assert run["detection_delay"] is not None and run["detection_delay"] < 96
    # consolidated in the background process, then swapped in between two steps
    (consolidation, *_) = run["consolidations"]
    assert consolidation["state"] == "done" and consolidation["cpu_s"] > 0
    assert run["new_pattern"] == "new-1" and run["swaps"]
    assert run["swaps"][0] > episodes[0]["kept_at"]
    # the new shape's next performance is recognised as the new pattern on some steps
    assert 0 < run["recognised_next"] <= 1
    assert outcome.targets["nothing_kept_from_unstructured"].met


def test_the_new_shape_is_called_novel_within_three_cycles(study):
    _, _, results = study
    (run,) = results["runs"]
    assert run["detection_delay"] is not None and run["detection_delay"] < 3 * 12


def test_the_new_shape_is_followed_on_its_next_performance(study):
    _, _, results = study
    (run,) = results["runs"]
    assert run["lock_next"] is not None and run["lock_next"] <= metrics.LOCK_LIMIT
    assert run["follow_s"] == pytest.approx(sum(run["follow_steps"].values()) * 0.4)


def test_teaching_consolidates_with_its_own_start(study):
    """The taught version was learned by rehearsal of the old network's function from the
    centre with every PB learning (teaching's own start, not the consolidation's defaults),
    with teaching's iterations and noise (more than the fast model's own or the function's)."""
    from rnnpb.model import TrainedModel
    from rnnpb.model.consolidation import consolidation_config

    out, _, _ = study
    versions = sorted(out.glob("runs/*/*.v2.npz"))  # the run's, and the paced run's if done
    assert versions
    for version in versions:
        grown = TrainedModel.load(version)
        last = grown.history[-1]
        assert last.method == "rehearsal" and last.added == ("new-1",)
        assert (last.details["hold_old_pb"], last.details["new_pb_start"]) == ("off", "centre")
        assert last.details["rehearsal_target"] == "function"
        policy = consolidation_config(grown, "teach")
        assert policy.train is not None
        assert (last.details["hold_old_pb"], last.details["new_pb_start"]) == (
            policy.hold_old_pb,
            policy.new_pb_start,
        )
        assert last.train_config["input_noise"] == policy.train.input_noise == 0.03
        assert last.iterations == policy.train.iterations == 1_000


def test_the_paced_run_and_the_files(study):
    out, outcome, results = study
    paced = results["paced"]
    assert paced["steps"] == 8 and paced["dt"] == 0.4
    assert paced["missed_deadlines"] >= 0 and paced["max_lateness_ms"] >= 0
    assert set(outcome.targets) == {
        "follow_within_90s",
        "no_missed_deadline",
        "old_patterns_keep_paper_targets",
        "nothing_kept_from_unstructured",
    }
    report = (out / "report.md").read_text()
    assert "figures/timeline_set1_figure-eight.png" in report
    assert (out / "figures" / "timeline_set1_figure-eight.png").stat().st_size > 10_000
    assert results["jobs_done"] == results["jobs"]
    assert results["config"]["consolidation_iterations"] is None  # the consolidation's own


def test_the_full_form_names_a_missing_models_directory(tmp_path):
    from rnnpb.errors import ConfigError

    with pytest.raises(ConfigError, match="no model set1.npz"):
        load_study("teach").run(tmp_path, StudyOptions(models=str(tmp_path / "none")))


def test_following_needs_the_papers_lock_on_as_well_as_the_time():
    """A shape locked onto after more than LOCK_LIMIT steps of its next performance is not
    followed, however soon; one never locked onto is not either."""
    from rnnpb.experiments.studies.teach import TeachConfig, TeachRun, judge

    def run(lock: int | None, follow_s: float | None) -> TeachRun:
        return TeachRun(
            learning_set="1",
            shape="figure-eight",
            new_pattern="new-1",
            segments=[],
            detection_delay=10,
            episodes=[],
            consolidations=[],
            swaps=[],
            lock_next=lock,
            recognised_next=1.0,
            lock_in_timeline={},
            follow_s=follow_s,
            follow_steps={},
            after=None,
            loop_steps=0,
            seconds=0.0,
            timeline={},
        )

    config = TeachConfig(quick=True, models=None, shipped=True, paper_measures=False)
    limit = metrics.LOCK_LIMIT
    followed = judge([run(limit, 60.0)], {}, None, config)["follow_within_90s"]
    assert followed.met and followed.detail.startswith("1/1 runs locked on within")
    late = judge([run(limit, 60.0), run(limit + 1, 60.0)], {}, None, config)["follow_within_90s"]
    assert not late.met and "1/2" in late.detail and f"locked on later ({limit + 1}" in late.detail
    slow = judge([run(3, 95.0)], {}, None, config)["follow_within_90s"]
    assert not slow.met and slow.detail.startswith("0/1")
    never = judge([run(None, None)], {}, None, config)["follow_within_90s"]
    assert not never.met and "1 never followed" in never.detail
