"""Cutting a new movement out of the stream by the novelty words of each step."""

from __future__ import annotations

import numpy as np
import pytest

from rnnpb.demonstrator import Imperfection, MirrorMapping, PatternConfig, perform
from rnnpb.errors import ConfigError
from rnnpb.interaction.teaching import (
    KEPT,
    RECORDING,
    WATCHING,
    EpisodeCutter,
    TeachingConfig,
)
from rnnpb.robot.camera import RobotCamera


def _stream(pattern, steps, seed=0, perfect=False):
    config = PatternConfig(imperfection=Imperfection.none()) if perfect else PatternConfig()
    motion = perform([(pattern, steps)], config, np.random.default_rng(seed))
    return motion, RobotCamera().sensory_from_hands(motion.measured)


def test_four_whole_cycles_of_a_novel_movement_are_kept_once():
    motion, sensory = _stream("3", 100, perfect=True)
    words = [""] * 10 + ["novel"] * 90
    cutter = EpisodeCutter(TeachingConfig().with_tuning(episode_cycles=4))
    kept, states = [], []
    for t in range(100):
        episode = cutter.observe(t, sensory[t], words[t])
        states.append(cutter.status.state)
        if episode is not None:
            kept.append(episode)
    assert len(kept) == 1
    (episode,) = kept
    assert episode.n_cycles == 4
    # whole cycles: the perfect user's period is 12 steps
    assert len(episode.sensory) == 48
    assert np.array_equal(episode.sensory, sensory[episode.first_step : episode.last_step + 1])
    truth = MirrorMapping().motor_from_hands(motion.measured)
    assert np.abs(episode.motor - truth[episode.first_step : episode.last_step + 1]).max() < 1e-4
    assert episode.first_step >= 10  # nothing from before the detector said novel
    assert states[:10] == [WATCHING] * 10 and RECORDING in states and states[-1] == KEPT
    assert (
        "recording a new movement (cycle"
        in next(s for s in _statuses(sensory, words) if s.state == RECORDING).describe()
    )


def test_a_performance_that_goes_on_after_it_was_kept_comes_back_whole_when_it_ends():
    _, sensory = _stream("3", 140, perfect=True)
    words = [""] * 10 + ["novel"] * 100 + ["familiar"] * 30
    cutter = EpisodeCutter()
    out = []
    for t in range(140):
        episode = cutter.observe(t, sensory[t], words[t])
        if episode is not None:
            out.append((t, episode))
    (_, kept), (ended, grown) = out
    assert not kept.extends and kept.n_cycles == TeachingConfig().episode_cycles
    # returned when the run ended (the interruption outlasted), after the last novel step
    assert grown.extends and ended > 109
    assert grown.first_step <= kept.first_step + 12 and grown.last_step <= 109
    assert grown.n_cycles >= 7 and len(grown.sensory) == 12 * grown.n_cycles
    assert np.array_equal(grown.sensory, sensory[grown.first_step : grown.last_step + 1])


def test_a_kept_performance_grows_to_at_most_max_run_steps():
    _, sensory = _stream("3", 300, perfect=True)
    cutter = EpisodeCutter(TeachingConfig(max_run_steps=60))
    out = [cutter.observe(t, sensory[t], "novel") for t in range(300)]
    grown = [e for e in out if e is not None and e.extends]
    (one,) = grown
    assert 3 < one.n_cycles and len(one.sensory) <= 60
    assert cutter.status.state == KEPT  # one performance, one episode: the run goes on


def test_an_episode_a_consolidation_is_learning_does_not_grow(tmp_path):
    from types import SimpleNamespace

    from rnnpb.interaction.teaching import EpisodeKeeper
    from rnnpb.memory import MemoryStore

    _, shape = _stream("3", 80, seed=4)
    rest = np.full((20, 4), 0.5)
    stream = [(row, "novel") for row in shape] + [(row, "still") for row in rest]
    for learning in (False, True):
        with MemoryStore(tmp_path / f"m{learning}.npz") as memory:
            keeper = EpisodeKeeper(memory, model="m.npz", source="s")
            for t, (row, word) in enumerate(stream):
                keeper(SimpleNamespace(step=t, observed=row, novelty=word))
                if learning:  # as the teacher says once it starts a consolidation of it
                    keeper.learning = frozenset(keeper.kept)
            (episode,) = memory.episodes()
        extended = [e for e in keeper.events if e.kind == "extended"]
        cycles = TeachingConfig().episode_cycles
        if learning:
            assert episode.n_cycles == cycles and not extended
        else:
            assert episode.n_cycles > cycles


def test_a_grown_episode_stops_where_the_person_switched_though_the_detector_lagged(tmp_path):
    from types import SimpleNamespace

    from rnnpb.interaction.teaching import EpisodeKeeper, episode_steps
    from rnnpb.memory import MemoryStore

    _, shape = _stream("3", 84, seed=4)
    _, other = _stream("1", 14, seed=4)
    rest = np.full((10, 4), 0.5)
    # the detector still says novel for the first 14 steps of the next movement
    stream = [(row, "novel") for row in (*shape, *other)] + [(row, "still") for row in rest]
    with MemoryStore(tmp_path / "m.npz") as memory:
        keeper = EpisodeKeeper(memory, model="m.npz", source="s")
        for t, (row, word) in enumerate(stream):
            keeper(SimpleNamespace(step=t, observed=row, novelty=word))
        (episode,) = memory.episodes()
        steps = episode_steps(episode.note)
        assert steps is not None and steps[1] < 84  # nothing of the other movement
        assert episode.n_cycles > 3
        back = memory.episode(episode.id)
        assert np.array_equal(back.sensory, shape[steps[0] : steps[1] + 1])
    assert [e.kind for e in keeper.events].count("extended") == 1


def _statuses(sensory, words):
    cutter = EpisodeCutter()
    for t, word in enumerate(words):
        cutter.observe(t, sensory[t], word)
        yield cutter.status


def test_a_short_performance_is_kept_when_it_ends_with_the_cycles_the_novel_call_rested_on():
    # A movement shown for four cycles, then stopped (the detector says still); the detector
    # says novel from the third cycle on, having found the last cycle repeating the one before
    # it (24 steps, this one included), and the novel steps hold less than two whole cycles.
    _, sensory = _stream("3", 64, perfect=True)
    words = [""] * 24 + ["novel"] * 22 + ["still"] * 4

    def kept(words, repeating=24, data=sensory, learned=None):
        cutter = EpisodeCutter()
        cutter.learned = learned
        return [
            (t, e)
            for t, w in enumerate(words)
            if (e := cutter.observe(t, data[t], w, repeating=repeating if w == "novel" else 0))
        ]

    ((t, episode),) = kept(words)
    # kept as the run ends (the stop outlasts a hesitation), with every whole cycle: some from
    # before the first novel call
    assert t == 46 + TeachingConfig().interruption_steps
    assert episode.n_cycles >= 2 and episode.first_step < 24
    assert not episode.extends and episode.last_step < 46
    # without the evidence, the novel steps alone hold too few whole cycles to keep
    assert kept(words, repeating=0) == []
    # steps called familiar are looked back through (recognition holds a little after the
    # movement changed), unless their cycles are a learned pattern's shape; steps called still
    # are never taken in, nor steps before a lost hand
    assert kept(["familiar"] * 24 + words[24:]) != []
    assert kept(["familiar"] * 24 + words[24:], learned=lambda cycle: "3") == []
    assert kept(["still"] * 24 + words[24:]) == []
    lost = sensory.copy()
    lost[23, 0] = np.nan
    assert kept([""] * 23 + ["novel"] * 23 + ["still"] * 4, data=lost) == []
    # only as many steps as the call rests on: the two cycles, not the whole history
    ((_, episode),) = kept(words, repeating=13)
    assert episode.first_step >= 12
    # one call alone keeps nothing, however much it rests on: the detector must itself call a
    # whole cycle novel
    assert kept([""] * 48 + ["novel"] * 3 + ["unstructured"] * 13, repeating=48) == []
    # a performance long enough to keep on its own is kept as before, from its own cycles
    _, longer = _stream("3", 100, perfect=True)
    ((t, episode), *_) = kept([""] * 24 + ["novel"] * 76, data=longer)
    assert t < 99 and episode.first_step >= 24


def test_the_stream_s_end_ends_the_run_as_if_the_person_stopped():
    _, sensory = _stream("3", 100, perfect=True)
    # a short performance still going: kept at the end, with the cycles the call rested on
    cutter = EpisodeCutter()
    words = [""] * 24 + ["novel"] * 22
    assert all(
        cutter.observe(t, sensory[t], w, repeating=24 if w else 0) is None
        for t, w in enumerate(words)
    )
    ended = cutter.end()
    assert ended is not None and ended.n_cycles >= 2 and ended.first_step < 24
    assert cutter.end() is None  # and the run is over
    # a kept performance still going: given back grown, as when its run ends
    cutter = EpisodeCutter()
    kept = [e for t in range(100) if (e := cutter.observe(t, sensory[t], "novel"))]
    assert len(kept) == 1 and not kept[0].extends
    grown = cutter.end()
    assert grown is not None and grown.extends and grown.n_cycles > kept[0].n_cycles
    # nothing going: nothing
    assert EpisodeCutter().end() is None


def test_unstructured_movement_is_never_kept():
    rng = np.random.default_rng(3)
    walk = np.clip(0.5 + np.cumsum(0.02 * rng.standard_normal((150, 4)), axis=0), 0, 1)
    _, cyclic = _stream("4", 155, seed=1)
    cutter = EpisodeCutter()
    # the detector's word: unstructured
    assert all(cutter.observe(t, walk[t], "unstructured") is None for t in range(150))
    # a detector mistaking it for novel still gives no whole cycles to keep
    assert all(cutter.observe(t, walk[t], "novel") is None for t in range(150))
    # a novel run broken by unstructured steps (longer than a hesitation) starts again from
    # nothing each time
    words = (["novel"] * 20 + ["unstructured"] * 3) * 6
    assert all(cutter.observe(t, cyclic[t], w) is None for t, w in enumerate(words))
    # and one called unstructured on every third step is not novel enough to keep, though
    # each interruption alone would be forgiven
    words = ["novel", "novel", "unstructured"] * 50
    cutter = EpisodeCutter()
    assert all(cutter.observe(t, cyclic[t], w) is None for t, w in enumerate(words))


def test_a_hesitating_detector_does_not_break_the_run_but_a_pause_does():
    _, sensory = _stream("2", 90, seed=4)
    words = ["novel"] * 90
    doubts = {15: "still", 30: "familiar", 31: "familiar", 45: "unstructured", 60: "still"}
    for t, word in doubts.items():  # a step where the hands turn, a moment's doubt
        words[t] = word
    words[75] = "familiar"

    def kept(cutter, words):
        return [e for t, w in enumerate(words) if (e := cutter.observe(t, sensory[t], w))]

    (episode,) = kept(EpisodeCutter(), words)
    assert episode.n_cycles == TeachingConfig().episode_cycles
    assert episode.first_step <= 15 < episode.last_step
    # the same with the hesitations not forgiven: no run holds two whole cycles
    assert kept(EpisodeCutter(TeachingConfig().with_tuning(interruption_steps=0)), words) == []
    # a pause (more still steps than a hesitation) ends the run each time
    paused = ((["novel"] * 15 + ["still"] * 3) * 5)[:90]
    assert kept(EpisodeCutter(), paused) == []


def test_a_moment_without_evidence_does_not_break_the_run_but_a_lost_hand_does():
    _, sensory = _stream("1", 90, seed=2)
    words = ["novel"] * 90
    for t in (20, 21, 40):
        words[t] = ""
    cutter = EpisodeCutter()
    assert any(cutter.observe(t, sensory[t], w) is not None for t, w in enumerate(words))
    lost = sensory.copy()
    lost[15::15, 0] = np.nan  # a hand lost every 15 steps: never two cycles in a row
    cutter = EpisodeCutter()
    assert all(cutter.observe(t, lost[t], "novel") is None for t in range(90))


def test_teaching_config_is_validated_and_its_searched_values_are_the_presets():
    from rnnpb.model._tuned import user_names
    from rnnpb.presets import load_preset

    with pytest.raises(ConfigError, match="confirm_cycles"):
        TeachingConfig(confirm_cycles=5)  # more than the episode's 3 cycles
    with pytest.raises(ConfigError, match="confirm_cycles"):
        TeachingConfig(confirm_cycles=3).with_tuning(episode_cycles=2)
    with pytest.raises(ConfigError, match="no tuned setting 'plane_x'"):
        TeachingConfig().with_tuning(plane_x=0.3)
    assert user_names(TeachingConfig) == (
        "confirm_cycles",
        "tolerance_steps",
        "max_run_steps",
        "plane_x",
    )
    config = TeachingConfig()
    for name in ("paper", "fast"):
        for key, value in load_preset(name).section("teaching.cutter").items():
            assert getattr(config, key) == value
    longer = config.with_tuning(episode_cycles=4)
    assert longer.episode_cycles == 4 and longer.min_novel_share == config.min_novel_share


def test_the_keeper_stores_each_novel_movement_once_and_merges_a_repeat(tmp_path):
    from types import SimpleNamespace

    from rnnpb.interaction.teaching import EpisodeKeeper, episode_steps, merged_with
    from rnnpb.memory import MemoryStore

    _, shape = _stream("3", 80, seed=4)
    _, again = _stream("3", 80, seed=9)  # the same shape by another draw of the user
    _, other = _stream("1", 80, seed=4)
    rng = np.random.default_rng(5)
    walk = np.clip(0.5 + np.cumsum(0.02 * rng.standard_normal((60, 4)), axis=0), 0, 1)
    stream = (
        [(row, "novel") for row in shape]
        + [(row, "unstructured") for row in walk]
        + [(row, "novel") for row in again]
        + [(row, "unstructured") for row in walk]
        + [(row, "novel") for row in other]
    )
    with MemoryStore(tmp_path / "m.npz") as memory:
        keeper = EpisodeKeeper(memory, model="m.npz", source="scenario:held:3")
        for t, (row, word) in enumerate(stream):
            keeper(SimpleNamespace(step=t, observed=row, novelty=word))
        episodes = memory.episodes()
        # the repeat joins the first movement; another shape is a movement of its own
        assert [e.pattern for e in episodes] == ["new-1", "new-1", "new-2"]
        assert merged_with(episodes[1].note) == episodes[0].id
        assert merged_with(episodes[0].note) is None and merged_with(episodes[2].note) is None
        assert memory.group("new-1") == [episodes[0].id, episodes[1].id]
        assert all(e.status == "kept" for e in episodes)
        # A performance that went on after it was kept holds every whole cycle of it once it
        # ended; the last one, still going when the stream stops, holds the three it was kept
        # with.
        assert episodes[0].n_cycles > 3 and episodes[1].n_cycles > 3
        assert episodes[2].n_cycles == TeachingConfig().episode_cycles
        for e in episodes:
            assert e.n_steps == memory.episode(e.id).sensory.shape[0]
        assert all(e.source == "scenario:held:3" and e.model == "m.npz" for e in episodes)
        # nothing from the unstructured stretches (steps 80-139 and 220-279)
        for e in episodes:
            steps = episode_steps(e.note)
            assert steps is not None
            first, last = steps
            assert not (first <= 139 and last >= 80) and not (first <= 279 and last >= 220)
    kinds = [event.kind for event in keeper.events]
    assert kinds.count("kept") == 3 and "recording" in kinds
    extended = [event for event in keeper.events if event.kind == "extended"]
    assert [event.episode_id for event in extended] == [episodes[0].id, episodes[1].id]
    assert f"({episodes[0].n_cycles} cycles, {episodes[0].n_steps} steps)" in extended[0].text
    kept = [event for event in keeper.events if event.kind == "kept"]
    assert [event.repeat_of for event in kept] == [None, episodes[0].id, None]
    assert [event.performances for event in kept] == [1, 2, 1]
    assert "seen twice" in kept[1].text


def test_a_camera_sources_hands_reach_the_keeper():
    from rnnpb.interaction import open_source
    from rnnpb.interaction.teaching import tracked_hands

    with open_source("synthetic:1", steps=3, seed=0) as source:
        hands_of = tracked_hands(source)
        assert hands_of(None) is None  # nothing read yet
        source.read()
        hands = hands_of(None)
        truth = source.frames.hands[0]
    assert hands.shape == (2, 3) and np.abs(hands - truth).max() < 0.03
    assert tracked_hands(object())(None) is None


def test_a_new_version_is_made_ready_off_the_loop_and_a_broken_one_says_why(tmp_path):
    from rnnpb.interaction.background import PreparedMirror
    from rnnpb.model import MirrorSystem
    from rnnpb.models import SHIPPED_MODEL

    prepared = PreparedMirror(str(SHIPPED_MODEL), MirrorSystem)
    prepared._thread.join(120)
    assert prepared.done and prepared.error == ""
    assert prepared.mirror is not None and prepared.mirror.steps == 0  # compiled, then reset
    assert prepared.mirror.model.patterns == prepared.model.patterns
    broken = tmp_path / "broken.npz"
    broken.write_bytes(b"not a model")
    failed = PreparedMirror(str(broken), MirrorSystem)
    failed._thread.join(60)
    assert failed.mirror is None and failed.error.startswith("ModelFileError")


def test_the_keeper_never_keeps_a_movement_whose_joint_angles_collide(tmp_path):
    from types import SimpleNamespace

    from rnnpb.interaction.teaching import EpisodeKeeper
    from rnnpb.memory import MemoryStore
    from rnnpb.robot import SelfCollision, inverse_kinematics

    class ThroughTheChest(MirrorMapping):
        """A mapping that bypasses the safe retargeting: the hands go inside the chest."""

        def motor_from_hands(self, hands):
            inside = np.array([[0.02, 0.03, 0.33], [0.02, -0.03, 0.33]])
            return np.repeat(inverse_kinematics(inside[None]).joints, len(hands), axis=0)

    assert SelfCollision().collides(ThroughTheChest().motor_from_hands(np.zeros((1, 2, 3)))[0])
    _, shape = _stream("3", 80, seed=4)
    with MemoryStore(tmp_path / "m.npz") as memory:
        keeper = EpisodeKeeper(memory, "m.npz", "test", mapping=ThroughTheChest())
        for t, row in enumerate(shape):
            keeper(SimpleNamespace(step=t, observed=row, novelty="novel"))
        assert memory.episodes() == []
    refused = [event for event in keeper.events if event.kind == "refused"]
    assert len(refused) == 1 and "unsafe for the robot (collision:" in refused[0].text
    # The same stream through the real mapping is kept.
    with MemoryStore(tmp_path / "n.npz") as memory:
        keeper = EpisodeKeeper(memory, "m.npz", "test")
        for t, row in enumerate(shape):
            keeper(SimpleNamespace(step=t, observed=row, novelty="novel"))
        assert len(memory.episodes()) == 1


def _teacher_on(path, memory, **options):
    """A Teacher subscribed to a stand-in loop: the test feeds it steps by hand."""
    from types import SimpleNamespace

    from rnnpb.interaction.teaching import Teacher

    subscribers = []
    loop = SimpleNamespace(
        config=SimpleNamespace(dt=0.4, paced=False),
        subscribe=subscribers.append,
        mirror=None,
        steps=0,
    )
    teacher = Teacher(loop, path, memory, make_mirror=None, auto=False, **options)

    def perform(rows, start):
        for t, row in enumerate(rows, start):
            loop.steps = t
            for subscriber in subscribers:
                subscriber(SimpleNamespace(step=t, observed=row, novelty="novel"))

    return teacher, perform


def test_a_repeat_of_a_taught_pattern_is_more_data_for_it_and_a_new_shape_waits(
    set1_model, tmp_path
):
    from rnnpb.memory import MemoryStore

    path = tmp_path / "m.npz"
    set1_model.renamed("3", "new-1").save(path)  # as if teaching had learned pattern 3
    _, taught = _stream("3", 36, seed=1)
    _, again = _stream("3", 80, seed=7)  # another draw of the user, long after
    _, other = _stream("1", 80, seed=7)
    with MemoryStore(path) as memory:
        learned = memory.add_episode(
            taught, np.zeros((36, 8)), source="s", model=str(path), pattern="new-1", n_cycles=3
        )
        memory.set_status(learned, "learned")
        teacher, perform = _teacher_on(path, memory)
        perform(again, 0)
        (repeat,) = teacher.pending
        assert memory.episode_summary(repeat).pattern == "new-1"  # never a second pattern
        # more data for a pattern the running version holds: ready at once
        assert teacher.ready() == [repeat] and teacher.waiting_for_confirm()
        perform([np.full(4, np.nan)], 80)  # the run ends
        perform(other, 81)
        fresh = teacher.pending[-1]
        assert memory.episode_summary(fresh).pattern == "new-2"
        # a new shape seen once waits for its next performance
        assert teacher.ready() == [repeat]
        waiting = [e for e in teacher.events if e.kind == "waiting"]
        assert [e.pattern for e in waiting] == ["new-2"] and "seen once" in waiting[0].text
    with MemoryStore(path) as memory:
        # told to learn from one performance, it does not wait
        teacher, _ = _teacher_on(path, memory, performances=1)
        teacher.pending = [repeat, fresh]
        assert teacher.ready() == [repeat, fresh]
        with pytest.raises(ConfigError, match="performances"):
            _teacher_on(path, memory, performances=0)


def test_two_draws_of_a_shape_are_one_movement_and_other_shapes_are_not():
    from rnnpb.demonstrator import demonstration
    from rnnpb.interaction.teaching import shape_distance
    from rnnpb.model.recognition import RecognitionConfig

    def take(pattern, seed):
        return demonstration(pattern, np.random.default_rng(seed), 36).sensory

    level = RecognitionConfig().template_level
    eight = take("figure-eight", 1)
    assert shape_distance(eight, take("figure-eight", 2)) < level
    # another phase and size of the same draw: the same shape
    assert shape_distance(eight[5:], 0.5 + 0.6 * (eight - 0.5)) < 0.05
    for other in ("1", "diagonal", "one-arm", "asymmetric"):
        far = shape_distance(eight, take(other, 1))
        assert far > level and far == shape_distance(take(other, 1), eight)


def test_the_paper_measures_lock_definition_is_the_one_growth_goes_by():
    from rnnpb.analysis import metrics
    from rnnpb.interaction.keeper import LOCK_ERROR, LOCK_STEPS

    assert (LOCK_ERROR, LOCK_STEPS) == (metrics.SENSORY_LOCK_THRESHOLD, metrics.LOCK_HOLD)


def test_a_taught_pattern_followed_loosely_grows_and_one_followed_closely_does_not(tmp_path):
    """A performance recognised as a pattern teaching learned, predicted poorly, is kept
    under that pattern's name as more data for it; followed closely, or a pattern the model
    had before teaching, nothing is kept."""
    from types import SimpleNamespace

    from rnnpb.interaction.keeper import GROWS, EpisodeKeeper
    from rnnpb.memory import MemoryStore

    _, rows = _stream("3", 80, seed=4)

    def kept(recognised: str, error: float) -> list:
        with MemoryStore(tmp_path / f"{recognised}-{error}.npz") as memory:
            keeper = EpisodeKeeper(memory, model="m.npz", source="test")
            keeper.taught = frozenset({"new-1"})
            for t, row in enumerate(rows):
                keeper(
                    SimpleNamespace(
                        step=t,
                        observed=row,
                        novelty="familiar",
                        recognised=recognised,
                        prediction_error=error**2,
                    )
                )
            return memory.episodes()

    (grown,) = kept("new-1", 0.045)  # the "0.017-0.044 RMS" of a one-take pattern
    assert grown.pattern == "new-1" and f"{GROWS}new-1" in grown.note
    assert grown.status == "kept" and grown.n_cycles == TeachingConfig().episode_cycles
    assert kept("new-1", 0.01) == []  # locked on: nothing to learn
    assert kept("3", 0.045) == []  # a pattern of the first version: not teaching's to grow


def test_the_teacher_grows_only_what_teaching_learned(set1_model, tmp_path):
    from types import SimpleNamespace

    from rnnpb.memory import MemoryStore

    first, second = tmp_path / "m.npz", tmp_path / "m.v2.npz"
    set1_model.save(first)
    set1_model.renamed("3", "new-1").save(second)  # as if teaching had learned pattern 3
    _, rows = _stream("3", 80, seed=6)
    with MemoryStore(first) as memory:
        teacher, _ = _teacher_on(first, memory)
        assert teacher.taught_patterns() == frozenset()
        teacher.versions.append(str(second))
        assert teacher.taught_patterns() == {"new-1"}
        for t, row in enumerate(rows):
            teacher._on_step(
                SimpleNamespace(
                    step=t,
                    observed=row,
                    novelty="familiar",
                    recognised="new-1",
                    prediction_error=0.04**2,
                )
            )
        (grown,) = teacher.pending
        assert memory.episode_summary(grown).pattern == "new-1"
        assert teacher.ready() == [grown]  # more data for a learned pattern: ready at once
