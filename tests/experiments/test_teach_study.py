"""``rnnpb study teach --quick``: a new shape is noticed, kept, consolidated and followed, end
to end; the judge on runs made here. Whether the study meets its targets (how soon a new shape
is noticed and followed) is judged by `rnnpb study teach --exam`, not here."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from rnnpb.analysis import metrics
from rnnpb.experiments.exams import load_exam
from rnnpb.experiments.scenarios.teaching_measures import TeachRun
from rnnpb.experiments.scenarios.teaching_scenario import TeachConfig, segments
from rnnpb.experiments.studies import StudyOptions, load_study
from rnnpb.experiments.studies.teach import judge, judge_results


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


def test_the_new_shapes_next_performance_is_measured_and_judged(study):
    """The next performance's lock-on and following time are recorded (the time in 0.4 s
    steps), and the verdict on following is the one the judge gives those figures."""
    _, outcome, results = study
    (run,) = results["runs"]
    # The next performance is the run's last segment; its lock-on is counted from its start
    # and is a lock by the measure's definition: the robot's motor error under the lock
    # threshold for LOCK_HOLD steps from there, and no sooner by the motor error alone.
    shape, again = run["segments"][-1]
    assert shape == run["shape"]
    start = sum(steps for _, steps in run["segments"]) - again
    motor = np.asarray(run["motor_error"], dtype=float)
    assert len(motor) == start + again
    if run["lock_next"] is None:
        assert run["follow_s"] is None and run["follow_steps"] == {}
    else:
        locked = start + run["lock_next"]
        assert 0 <= run["lock_next"] <= again - metrics.LOCK_HOLD
        assert np.all(motor[locked : locked + metrics.LOCK_HOLD] < metrics.MOTOR_LOCK_THRESHOLD)
        assert metrics.steps_to_lock(motor, None, start, len(motor)) <= run["lock_next"]
        assert run["follow_steps"]["lock_on"] == run["lock_next"]
    assert run["follow_s"] == pytest.approx(sum(run["follow_steps"].values()) * 0.4)
    target = load_exam("teach").target("follow_within_90s")
    seconds = target.parameter("seconds")
    followed = (
        run["lock_next"] is not None
        and run["lock_next"] <= target.parameter("lock_steps")
        and run["follow_s"] is not None
        and run["follow_s"] <= seconds
    )
    assert outcome.targets["follow_within_90s"].met == followed


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
    # A missed deadline is a step whose own work took longer than dt, a late step one that
    # started more than 40 ms after its slot: each count agrees with the longest time it
    # rests on, and no count exceeds the steps.
    assert (paced["missed_deadlines"] > 0) == (paced["max_step_ms"] > paced["dt"] * 1e3)
    assert (paced["late_steps"] > 0) == (paced["max_lateness_ms"] > 40.0)
    assert 0 <= paced["late_steps"] < paced["steps"] and paced["overrun_steps"] < paced["steps"]
    assert 0 < paced["p99_step_ms"] <= paced["max_step_ms"]
    assert set(outcome.targets) == {
        "follow_within_90s",
        "follow_next_performance",
        "next_performance_recognised",
        "no_duplicate_patterns",
        "consolidation_cpu",
        "old_patterns_within_limits",
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
    limit = metrics.LOCK_LIMIT
    followed = judge([_run(limit, 60.0)], None)["follow_within_90s"]
    assert followed.met and followed.detail.startswith("1/1 runs locked on within")
    late = judge([_run(limit, 60.0), _run(limit + 1, 60.0)], None)["follow_within_90s"]
    assert not late.met and "1/2" in late.detail and f"locked on later ({limit + 1}" in late.detail
    slow = judge([_run(3, 95.0)], None)["follow_within_90s"]
    assert not slow.met and slow.detail.startswith("0/1")
    never = judge([_run(None, None)], None)["follow_within_90s"]
    assert not never.met and "1 never followed" in never.detail


def test_the_judge_reads_every_threshold_from_the_exam():
    """A run followed in 60 s within 5 steps meets the teach exam's definitions and misses
    stricter ones; an old pattern locked on in 8 steps misses a lock-on limit of 6."""
    run = replace(_run(5, 60.0), lock_in_timeline={"2:2": 8, "6:figure-eight": 5})
    default = judge([run], None)
    assert default["follow_within_90s"].met and default["old_patterns_keep_paper_targets"].met
    exam = load_exam("teach")
    exam = _stricter(exam, "follow_within_90s", seconds=30.0)
    exam = _stricter(exam, "old_patterns_keep_paper_targets", lock_steps=6)
    strict = judge([run], None, exam)
    assert (
        not strict["follow_within_90s"].met and "within 30 s" in strict["follow_within_90s"].detail
    )
    old = strict["old_patterns_keep_paper_targets"]
    assert not old.met and "lock 2:2 8" in old.detail


def test_the_scripted_user_leads_with_another_learned_pattern_per_shape():
    config = TeachConfig(quick=True, models=None, shipped=True, paper_measures=False)
    first = segments(("1", "2", "3"), "diagonal", 0, config)
    second = segments(("1", "2", "3"), "one-arm", 1, config)
    # the new shape in two performances (another learned pattern between them), then its next
    assert [m for m, _ in first] == [
        "1",
        "diagonal",
        "2",
        "diagonal",
        "3",
        "random-walk",
        "jerky",
        "diagonal",
    ]
    assert [m for m, _ in second][:4] == ["2", "one-arm", "1", "one-arm"]
    assert first[1][1] == first[3][1] == config.new_steps
    assert first[-1][1] == config.again_steps


def test_the_judge_reads_a_finished_results_file(study):
    """The exam's judge of a finished ``results.json`` gives the run's own verdicts."""
    _, outcome, results = study
    assert judge_results(results, load_exam("teach")) == outcome.targets


def _stricter(exam, name: str, **parameters):
    target = exam.target(name)
    target = replace(target, parameters={**target.parameters, **parameters})
    return replace(exam, targets={**exam.targets, name: target})


def _run(lock: int | None, follow_s: float | None) -> TeachRun:
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


def test_the_models_of_a_directory_are_taken_by_the_names_the_demo_writes(tmp_path):
    import shutil

    from rnnpb.errors import ConfigError
    from rnnpb.experiments.scenarios.study_models import study_models
    from rnnpb.models import SHIPPED_MODEL

    def never_learned(name: str):
        raise AssertionError(f"learned {name}, though the directory holds it")

    shutil.copyfile(SHIPPED_MODEL, tmp_path / "set1.npz")
    shutil.copyfile(SHIPPED_MODEL, tmp_path / "full_seed0.npz")
    paths = study_models(("1", "full"), tmp_path, tmp_path / "out", never_learned)
    assert paths == {"1": str(tmp_path / "set1.npz"), "full": str(tmp_path / "full_seed0.npz")}
    with pytest.raises(ConfigError, match="no model set2.npz for learning set 2"):
        study_models(("2",), tmp_path, tmp_path / "out", never_learned)


def test_the_exam_runs_the_full_form_on_its_own_user_shapes_and_sets():
    from rnnpb.experiments.studies.teach import study_config

    exam = load_exam("teach")
    config = study_config(StudyOptions(exam=exam, models="models"))
    assert not config.quick and config.models == "models" and config.paper_measures
    assert config.scenario_seed == exam.seed_list("user")[0]
    assert config.shapes == exam.shapes and config.learning_sets == exam.learning_sets
    # Without an exam the user is drawn from --seed, and no --models means learned here.
    free = study_config(StudyOptions(seed=3))
    assert free.scenario_seed == 103 and free.models is None and not free.shipped


def test_models_not_given_are_learned_under_the_demos_names(tmp_path, monkeypatch):
    """With no directory each learning set's model is learned with its own learning, on the
    data draw given, and saved under the name the demo gives it — in the pool when given."""
    from rnnpb.experiments.scenarios import study_models as module
    from rnnpb.experiments.studies._pool import InProcess
    from rnnpb.model import TrainConfig

    learned = []

    def learn(name, config, path, seed):
        learned.append((name, config.iterations, path.name, seed))
        return str(path)

    monkeypatch.setattr(module, "learn_model", learn)

    def learning(name: str) -> TrainConfig:
        return TrainConfig.fast(iterations=30 if name == "full" else 20)

    for pool in (None, InProcess()):
        learned.clear()
        paths = module.study_models(("2", "full"), None, tmp_path, learning, 5, pool=pool)
        assert paths == {"2": str(tmp_path / "set2.npz"), "full": str(tmp_path / "full.npz")}
        assert learned == [("2", 20, "set2.npz", 5), ("full", 30, "full.npz", 5)]
    # The full forms learn as the demo does: the paper's algorithm, the larger set its own.
    assert module.paper_training("1").optimizer == "momentum"
    assert module.paper_training("full", seed=2).seed == 2


def test_the_next_performance_duplicates_and_consolidations_are_judged_by_the_exam():
    from rnnpb.experiments.scenarios.teaching_measures import ConsolidationTime

    exam = load_exam("teach")
    settle = int(exam.target("next_performance_recognised").parameter("settle_steps"))
    recognised = ["1"] * 40 + ["new-1"] * settle + ["new-1"] * 20 + [""] * 4  # last 36: next
    run = replace(
        _run(5, 60.0),
        segments=[("1", 40), ("figure-eight", 36)],
        timeline={"recognised": recognised, "taught": {"new-1": "figure-eight"}},
        consolidations=[ConsolidationTime(10, 12.5, 20.0, 1, "done")],
    )
    twice = replace(run, timeline={**run.timeline, "taught": {"new-1": "x", "new-2": "x"}})
    slow = replace(run, consolidations=[ConsolidationTime(10, 15.5, 20.0, 1, "done")])
    targets = judge([run], None, exam)
    # of the 24 settled steps of the next performance, 20 recognised as new-1
    assert targets["next_performance_recognised"].detail.startswith("mean 83.3 %")
    assert not targets["next_performance_recognised"].met
    assert targets["no_duplicate_patterns"].met and targets["consolidation_cpu"].met
    assert not judge([twice], None, exam)["no_duplicate_patterns"].met
    assert not judge([slow], None, exam)["consolidation_cpu"].met
    assert targets["follow_next_performance"].met
    assert not judge([run, _run(None, None)], None, exam)["follow_next_performance"].met
