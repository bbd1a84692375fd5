"""What the figures mark and the plane Figure 9 draws in."""

from types import SimpleNamespace

import numpy as np

from rnnpb.analysis import figures


def _session(n=60):
    steps = np.arange(n)
    phase = 2 * np.pi * steps / 12
    session = {"step": steps.astype(float), "time_s": 0.4 * steps}
    for k, name in enumerate(("lhy", "lhz", "rhy", "rhz")):
        session[name] = 0.5 + 0.2 * np.sin(phase + k)
        session[f"pred_{name}"] = session[name]
    for name in ("lshp", "lshr", "lshy", "lelp", "rshp", "rshr", "rshy", "relp"):
        session[name] = 0.3 * np.sin(phase)
    pb = np.tile([0.2, 0.2, 0.8, 0.8], (n, 1)) + 0.01 * np.sin(phase)[:, None]
    pb[30:] = [0.8, 0.8, 0.2, 0.2]  # a restart to pattern b at step 30
    pb[45:48] = [0.2, 0.2, 0.8, 0.8]  # back at pattern a's value for three steps
    for k in range(4):
        session[f"pb{k}"] = pb[:, k]
    session["truth_pattern"] = np.array(["a"] * 30 + ["b"] * 30, dtype=object)
    return session, pb


def test_pb_jumps_are_the_restarts_not_the_drift():
    _, pb = _session()
    np.testing.assert_array_equal(figures.pb_jumps(pb), [30, 45, 48])
    assert len(figures.pb_jumps(pb[:1])) == 0


def test_nearest_patterns_show_the_fall_back():
    _, pb = _session()
    learned = {"a": np.array([0.2, 0.2, 0.8, 0.8]), "b": np.array([0.8, 0.8, 0.2, 0.2])}
    nearest = figures.nearest_patterns(pb, learned)
    assert nearest[:30] == ["a"] * 30 and nearest[30:45] == ["b"] * 15
    assert nearest[45:48] == ["a"] * 3 and nearest[48:] == ["b"] * 12


def test_session_figure_says_what_it_shows(tmp_path, monkeypatch):
    session, _ = _session()
    captions = []
    monkeypatch.setattr(figures.paper, "_caption", lambda fig, text: captions.append(text))
    figures.plot_session(
        session,
        tmp_path / "s.png",
        marks=[(30, "switch")],
        pattern_pb={"a": [0.2, 0.2, 0.8, 0.8], "b": [0.8, 0.8, 0.2, 0.2]},
    )
    assert (tmp_path / "s.png").read_bytes()[:4] == b"\x89PNG"
    (text,) = captions
    assert "▼ marks 3 jump(s) of the PB" in text and "steps 30, 45, 48" in text
    assert "hatched (3 of 60 steps with a pattern performed, steps 45–47)" in text
    figures.plot_switch_zoom(session, [(20, 50)], tmp_path / "z.png", switches=[30])
    assert "▼ marks a jump of the PB" in captions[-1]


def test_figure_9_axes_do_not_show_the_same_swing_twice(tmp_path):
    t = np.linspace(0, 2 * np.pi, 200)
    rng = np.random.default_rng(0)
    mixing = rng.normal(size=(2, 30)) * 0.05
    # Two context units that swing together (a thin ellipse on the diagonal of their plane).
    mixing[0, :2] = [0.3, 0.29]
    mixing[1, :2] = [0.01, -0.01]
    attractors = {
        name: SimpleNamespace(
            context=0.5 + np.column_stack([np.cos(t + shift), np.sin(2 * t + shift)]) @ mixing
        )
        for name, shift in (("1", 0.0), ("2", 1.0))
    }
    i, j = figures.context_units(attractors)
    stacked = np.concatenate([a.context for a in attractors.values()])
    assert abs(np.corrcoef(stacked[:, i], stacked[:, j])[0, 1]) > 0.9
    mean, plane, explained = figures.context_plane(attractors)
    xy = (stacked - mean) @ plane.T
    assert abs(np.corrcoef(xy[:, 0], xy[:, 1])[0, 1]) < 0.05
    np.testing.assert_allclose(plane @ plane.T, np.eye(2), atol=1e-9)
    assert explained[0] >= explained[1] > 0.01 and explained.sum() <= 1 + 1e-9
    run = SimpleNamespace(
        context=attractors["1"].context, novel_pattern="4", learning_set="1", case=2
    )
    figures.plot_attractors([(run, attractors)], tmp_path / "f9.png", transient=10)
    assert (tmp_path / "f9.png").read_bytes()[:4] == b"\x89PNG"
