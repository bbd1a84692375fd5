"""Two agents coupled through their senses: the body mapping, symmetry, a leader and a
follower, the scripted subject and the two-agent recording."""

from __future__ import annotations

import numpy as np
import pytest

from rnnpb.analysis import dyad as measures
from rnnpb.analysis.metrics import LOCK_LIMIT
from rnnpb.demonstrator import MirrorMapping, learning_set
from rnnpb.errors import ConfigError
from rnnpb.interaction.dyad import AgentConfig, Dyad, RobotAgent
from rnnpb.interaction.person_space import pattern_references, person_hands, robot_to_person_scale
from rnnpb.interaction.recorder import DyadRecorder, dyad_columns, read_dyad_session
from rnnpb.interaction.subject import ScriptedSubject, SubjectConfig, robot_and_subject
from rnnpb.model import OnlineConfig
from rnnpb.robot.camera import RobotCamera


@pytest.fixture(scope="module")
def model(set1_model):
    return set1_model


def test_a_robot_is_seen_as_the_person_it_imitates():
    demo = learning_set("1")[4]  # pattern 3: circles, where left and right matter
    seen = RobotCamera().sensory_from_hands(person_hands(demo.motor))
    assert np.abs(seen - demo.sensory).max() < 1e-9
    # Physically turned half a turn, the circles turn the other way: not what was learned.
    turned = RobotCamera().sensory_from_hands(person_hands(demo.motor, view="physical"))
    assert np.abs(turned - demo.sensory).max() > 0.05
    assert robot_to_person_scale() == pytest.approx(1 / MirrorMapping().effective_scale)


def test_identical_agents_from_identical_starts_stay_identical(model):
    start = model.pattern_pb["2"]
    a, b = (
        RobotAgent(model, AgentConfig(patience=5), seed=3, initial_pb=start, name=n) for n in "ab"
    )
    run = Dyad(a, b).run(30)
    assert np.array_equal(run["a_motor"], run["b_motor"])
    assert np.array_equal(run["a_pb"], run["b_pb"])
    assert np.array_equal(run["a_initiative"], run["b_initiative"])


def test_an_adaptive_follower_locks_on_to_a_leader_that_does_not_adapt(model):
    online = OnlineConfig.ungated()  # the fast preset's models (docs/model.md)
    leader = RobotAgent(
        model,
        AgentConfig(adaptation=0.0),
        initial_pb=model.pattern_pb["3"],
        online=online,
        name="a",
    )
    follower = RobotAgent(
        model, AgentConfig(alone_steps=None), online=online, initial_pb=np.full(4, 0.5), name="b"
    )
    run = Dyad(leader, follower).run(60)
    found = measures.measure_dyad(
        run["a_shown"], run["b_shown"], model.patterns, run["a_pb"], run["b_pb"]
    )
    leader_on = int(np.flatnonzero(found.class_a == "3")[0])
    assert found.first_coherent is not None
    # Locked within the paper's limit once the leader's first cycle is there to be seen.
    assert found.first_coherent - leader_on <= LOCK_LIMIT
    assert found.coherent[found.first_coherent :].mean() > 0.8


def test_a_robot_taking_the_initiative_is_judged_on_that_pattern_by_what_it_does(model):
    references = pattern_references(model)
    assert set(references) == set(model.patterns)
    assert all(r.shape == (240, 4) and np.isfinite(r).all() for r in references.values())
    robot = RobotAgent(model, AgentConfig(alone_steps=None), name="a")
    robot.take_initiative("2")
    held = robot.config.lead_steps  # then it looks again: nobody follows it here
    shown = np.array(
        [RobotCamera().sensory_from_hands(robot.act(np.full(4, 0.5)).hands) for _ in range(held)]
    )
    assert np.allclose(shown, references["2"][:held], atol=1e-6)  # it plays its closed loop
    classes = measures.classify_movement(
        shown, measures.movement_templates(), references=references
    ).pattern
    assert set(classes[11:]) == {"2"}


def test_the_subject_explores_and_the_session_is_recorded_per_agent(model, tmp_path):
    dyad = robot_and_subject(model, AgentConfig(), SubjectConfig(patience=10), seed=1)
    path = tmp_path / "dyad.csv"
    with DyadRecorder(path) as recorder:
        run = dyad.run(60, on_step=recorder.write)
    assert isinstance(dyad.b, ScriptedSubject)
    assert run["b_initiative"].any()  # it tried something new when they could not match
    assert set(run["b_intent"]) <= set(SubjectConfig().repertoire)
    session = read_dyad_session(path)
    assert list(session) == dyad_columns(4)
    assert {"a_lhy", "b_lhy", "a_pb0", "b_intent", "a_initiative"} <= set(session)
    assert np.allclose(session["a_pb0"], run["a_pb"][:, 0], atol=1e-5)
    assert np.isnan(session["b_lshp"]).all()  # a subject has no motors
    assert np.allclose(session["b_shown_lhy"], run["b_shown"][:, 0], atol=1e-5)


@pytest.mark.parametrize(
    "changes, message",
    [
        ({"adaptation": -1}, "adaptation"),
        ({"persistence": 0}, "persistence"),
        ({"noise": float("nan")}, "noise"),
        ({"patience": 0}, "patience"),
    ],
)
def test_bad_agent_settings(changes, message):
    with pytest.raises(ConfigError, match=message):
        AgentConfig(**changes)


def test_a_robot_takes_only_its_own_patterns(model):
    robot = RobotAgent(model)
    with pytest.raises(ConfigError, match="not one this robot learned"):
        robot.take_initiative("4")


def _pair(model, side_by_side):
    from rnnpb.interaction.dyad import robot_pair

    dyad = robot_pair(model, model, AgentConfig(patience=5), AgentConfig(persistence=20), seed=4)
    dyad.side_by_side = side_by_side
    return dyad


def test_two_robots_step_the_same_side_by_side_as_one_after_the_other(model):
    together = _pair(model, True).run(40)
    in_turn = _pair(model, False).run(40)
    for key in ("a_motor", "b_motor", "a_pb", "b_pb", "a_shown", "b_shown", "b_initiative"):
        assert np.array_equal(together[key], in_turn[key]), key
    # Robots are side by side where two cores may be used; a subject acts in the caller's.
    assert robot_and_subject(model, seed=1).side_by_side is False


def test_an_error_in_the_agent_acting_beside_reaches_the_caller(model):
    dyad = _pair(model, True)

    def broken(view):
        raise RuntimeError("b broke")

    dyad.b.act = broken  # type: ignore[method-assign]
    with pytest.raises(RuntimeError, match="b broke"):
        dyad.step()


def test_a_subject_keeps_to_its_initiative_before_following_the_robot(model):
    # The robot plays pattern 1 and never follows; the subject starts on its pattern 2.
    def first_follow(commit):
        robot = RobotAgent(model, AgentConfig(adaptation=0.0), initial_pb=model.pattern_pb["1"])
        config = SubjectConfig(repertoire=("1", "2"), commit_steps=commit, patience=500)
        seed = next(k for k in range(50) if ScriptedSubject(config, seed=k).pattern == "2")
        intents = Dyad(robot, ScriptedSubject(config, seed=seed)).run(80)["b_intent"]
        assert intents[0] == "2"
        return int(np.flatnonzero(intents == "1")[0])

    assert first_follow(0) < 30  # it takes up the robot's movement as soon as it sees it
    assert first_follow(40) >= 40  # ... or only after keeping to its own for 40 steps
    with pytest.raises(ConfigError, match="commit_steps"):
        SubjectConfig(commit_steps=-1)


def test_a_robot_leading_gives_way_to_a_partner_leading_another_pattern(model):
    # The partner plays pattern 2 and never follows; the robot takes the initiative on 1.
    def intents(yield_steps):
        partner = RobotAgent(model, AgentConfig(adaptation=0.0), initial_pb=model.pattern_pb["2"])
        robot = RobotAgent(model, AgentConfig(yield_steps=yield_steps), name="a")
        robot.take_initiative("1")
        return Dyad(robot, partner).run(24)["a_intent"]

    assert (intents(None) == "1").all()  # it holds its initiative for lead_steps
    gave_way = intents(2)
    assert gave_way[0] == "1" and (gave_way[-6:] == "").all()  # ... or it follows the partner
    with pytest.raises(ConfigError, match="yield_steps"):
        AgentConfig(yield_steps=0)


def test_a_movement_both_predict_but_neither_knows_runs_out_the_patience(model):
    from dataclasses import replace

    def initiatives(familiar_only):
        robot = RobotAgent(model, AgentConfig(patience=4, familiar_only=familiar_only))
        step = robot.mirror.step
        # What it sees is predicted well, and its detector calls it none of its patterns.
        robot.mirror.step = lambda u: replace(  # type: ignore[method-assign]
            step(u), prediction_error=0.0, novelty="unstructured"
        )
        partner = RobotAgent(model, AgentConfig(adaptation=0.0), initial_pb=model.pattern_pb["2"])
        return Dyad(robot, partner).run(30)["a_initiative"]

    assert initiatives(True)[:9].any()  # within the patience (4 to 8 steps)
    assert not initiatives(False).any()


def test_an_unseen_first_step_is_not_being_left_alone_but_stillness_and_absence_are(model):
    """A person whose page is heard from one step late moves on every step seen after: the
    robot follows and does not take the initiative; a partner unseen or still all along is
    left alone."""
    steps = AgentConfig().alone_steps
    t = np.arange(3 * steps)
    moving = 0.5 + 0.1 * np.stack([np.sin(t / 2), np.cos(t / 2), -np.sin(t / 2), np.cos(t / 2)], 1)

    def initiatives(views) -> int:
        robot = RobotAgent(model, AgentConfig(), name="a")
        return sum(robot.act(v).initiative for v in views)

    late = moving.copy()
    late[0] = np.nan
    assert initiatives(late) == 0
    assert initiatives(moving) == 0
    assert initiatives(np.full((steps + 1, 4), np.nan)) == 1
    assert initiatives(np.full((steps + 1, 4), 0.5)) == 1
    flicker = moving[: steps + 1].copy()
    flicker[::2] = np.nan  # seen every other step, moving when seen
    assert initiatives(flicker) == 0
