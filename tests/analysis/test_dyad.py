"""The measures of mutual interaction give known answers on constructed signals."""

from __future__ import annotations

import numpy as np
import pytest

from rnnpb.analysis import dyad
from rnnpb.demonstrator import PatternConfig, pattern_offsets
from rnnpb.robot.camera import RobotCamera

LEARNED = ("1", "2", "3")


def performed(labels: list[tuple[str, int]], phase0: float = 0.0) -> np.ndarray:
    """Ideal views of patterns one after another (``""``: still), (n, 4)."""
    config = PatternConfig()
    camera = RobotCamera()
    out, theta = [], phase0
    for label, n in labels:
        for _ in range(n):
            offsets = pattern_offsets(label, np.array(theta), config) if label else np.zeros((2, 3))
            out.append(camera.sensory_from_hands(config.body.hand_centres + offsets))
            theta += 2 * np.pi / 12
    return np.array(out)


def test_movement_class_names_each_pattern_and_stillness():
    templates = dyad.movement_templates()
    for name in ("1", "2", "3", "4"):
        found = dyad.classify_movement(performed([(name, 30)], phase0=1.0), templates)
        assert set(found.pattern[11:]) == {name}
        assert set(found.pattern[:11]) == {""}  # not a cycle yet
    still = dyad.classify_movement(performed([("", 30)]), templates)
    assert set(still.pattern) == {""}


def test_coherence_episode_and_leader_of_a_known_shift():
    # A moves 1 then switches to 2 at step 60; B follows 5 steps later (and a step behind).
    a = performed([("1", 60), ("2", 60)])
    b = np.concatenate([a[:1], a[:-1]])  # one step late
    b[60:65] = performed([("1", 65)])[60:65]  # still on 1 for five more steps
    measures = dyad.measure_dyad(a, b, LEARNED)
    patterns = [e.pattern for e in measures.episodes]
    assert patterns == ["1", "2"]
    assert len(measures.shifts) == 1
    shift = measures.shifts[0]
    assert (shift.before, shift.after, shift.leader) == ("1", "2", "a")
    assert shift.lead >= 4
    # The new episode starts once both have moved 2 for a cycle.
    assert 65 <= shift.step <= 65 + 12 + 2
    assert measures.phase_shifts == 3  # 1 starts (the run starts incoherent) and ends, 2 starts
    assert measures.leader_index == 1.0
    assert int(measures.found[-1]) == 2


def test_no_coherence_on_a_pattern_not_learned_or_out_of_phase():
    a = performed([("4", 60)])
    assert not dyad.measure_dyad(a, a, LEARNED).coherent.any()
    one = performed([("1", 60)])
    half_cycle = performed([("1", 60)], phase0=np.pi)
    measures = dyad.measure_dyad(one, half_cycle, LEARNED)
    assert not measures.coherent.any()
    assert measures.coherent_share == 0.0


def test_transfer_entropy_finds_the_driver():
    rng = np.random.default_rng(0)
    x = rng.standard_normal(3000)
    y = np.concatenate([[0.0], x[:-1]]) + 0.3 * rng.standard_normal(3000)  # y follows x
    forward, backward = dyad.transfer_entropy(x, y), dyad.transfer_entropy(y, x)
    assert forward > 0.3
    assert backward < 0.05


def test_patterns_found_counts_first_episodes_of_learned_patterns():
    episodes = [
        dyad.Episode(10, 30, "2"),
        dyad.Episode(40, 60, "2"),
        dyad.Episode(70, 90, "4"),
        dyad.Episode(100, 130, "1"),
    ]
    found = dyad.patterns_found(episodes, 140, LEARNED, min_steps=12)
    assert found[20] == 0 and found[21] == 1 and found[110] == 1 and found[111] == 2
    assert found[-1] == 2  # pattern 4 is not learned


@pytest.mark.parametrize("gap, expected", [(2, 1), (5, 2)])
def test_short_gaps_do_not_end_an_episode(gap, expected):
    coherent = np.ones(60, dtype=bool)
    coherent[30 : 30 + gap] = False
    joint = np.full(60, "1", dtype=object)
    assert len(dyad.episodes(coherent, joint, min_steps=12, bridge=3)) == expected


def test_the_dyad_figures_are_drawn(tmp_path):
    from rnnpb.analysis import figures

    a = performed([("1", 40), ("2", 40)])
    run = {
        "a_shown": a,
        "b_shown": a,
        "a_pb": np.full((80, 4), 0.3),
        "b_pb": np.full((80, 4), np.nan),
    }
    coherent = dyad.measure_dyad(a, a, LEARNED).coherent
    figures.plot_dyad(run, coherent, tmp_path / "run.png", shifts=[(52, "a")])
    grid = np.array([[0.9, 0.5], [0.2, np.nan]])
    figures.plot_phase_diagram(
        (0.1, 1.0),
        {"x": {"coherent share": grid, "shifts per 200 steps": grid, "leader index": grid}},
        tmp_path / "phase.png",
    )
    figures.plot_patterns_found({"s": np.arange(80) // 30}, 0.4, 3, tmp_path / "found.png")
    for name in ("run.png", "phase.png", "found.png"):
        assert (tmp_path / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_robots_own_playing_of_a_pattern_counts_as_that_pattern():
    # Both agents move in synchrony a cycle the demonstrator's templates do not know (pattern
    # 1 with the right hand's swing turned round: both hands swing together): only when it is
    # given as how a robot plays pattern 1 (its closed loop) are they coherent on 1.
    a = performed([("1", 60)])
    a[:, 2] = 2 * a[:, 2].mean() - a[:, 2]
    played = {"1": a[5:41]}  # three cycles of it, at another phase than the run's
    assert not dyad.measure_dyad(a, a, LEARNED).coherent.any()
    both = dyad.measure_dyad(a, a, LEARNED, references_a=played, references_b=played)
    assert both.coherent[11 + dyad.MAX_LAG + dyad.LOCK_STEADY :].all()
    assert set(both.class_a[11:]) == {"1"}
    # Only one of the two known to play it so: not the same pattern.
    assert not dyad.measure_dyad(a, a, LEARNED, references_a=played).coherent.any()
    still = np.repeat(a[:1], 60, axis=0)  # not moving: no movement, whatever it fits
    assert not dyad.measure_dyad(
        still, still, LEARNED, references_a={"1": still}, references_b={"1": still}
    ).coherent.any()


def test_phase_lock_finds_a_steady_lag_and_loses_it_when_the_lag_jumps():
    a = performed([("2", 90)])
    b = np.concatenate([a[:2], a[:-2]])  # two steps behind ...
    b[50:] = a[50 - 5 : 90 - 5]  # ... then five steps behind: no longer in step
    lock = dyad.phase_lock(a, b)
    settled = 11 + dyad.MAX_LAG + dyad.LOCK_STEADY
    assert lock.locked[settled:48].all()
    assert set(lock.lag[settled:48]) == {2}  # B two steps behind A
    assert not lock.locked[50 + 11 :].any()
    # Mirror-image roles: A behind B.
    assert set(dyad.phase_lock(b[:48], a[:48]).lag[settled:48]) == {-2}
