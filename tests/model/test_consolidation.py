"""Incremental learning: rehearsal and consolidation, the alternatives, history and bad input."""

from dataclasses import replace

import numpy as np
import pytest

from rnnpb.analysis import metrics
from rnnpb.errors import ConfigError, ModelFileError
from rnnpb.experiments.paper import learned_attractors, synchronization
from rnnpb.model import OnlineConfig, TrainConfig, TrainedModel, train
from rnnpb.model.consolidation import (
    ConsolidationConfig,
    consolidate,
    model_joint_limits,
    rehearse,
)
from rnnpb.model.learning import prepare_data

from .synthetic import LIMITS, make_sequences

CONSOLIDATION = TrainConfig.fast(iterations=500)


@pytest.fixture(scope="module")
def two_patterns():
    """Demonstrator patterns 1 and 2 learned with the fast preset, and pattern 3's data."""
    from rnnpb.demonstrator import pattern_dataset
    from rnnpb.robot import JOINT_LIMITS

    model = train(
        pattern_dataset(0, ("1", "2")), JOINT_LIMITS, config=TrainConfig.fast(iterations=1200)
    )
    return model, pattern_dataset(0, ("3",))


def _keeps_and_follows(before: TrainedModel, after: TrainedModel) -> bool:
    """Every pattern followed (locked on and recognised) and the old patterns' closed-loop
    cycles where they were."""
    limits = model_joint_limits(after)
    for pattern in after.patterns:
        sync = synchronization(
            after, pattern, OnlineConfig.ungated(), limits, seed=100, before=30, after=10
        )
        if (
            sync.steps_to_lock is None
            or sync.steps_to_lock > metrics.LOCK_LIMIT
            or sync.recognized_pattern != pattern
        ):
            return False
    old, new = learned_attractors(before, 200, 100), learned_attractors(after, 200, 100)
    return all(
        new[p].period is not None and metrics.cycle_distance(new[p].cycle, old[p].cycle) <= 0.05
        for p in before.patterns
    )


@pytest.mark.slow
def test_rehearsal_adds_a_pattern_and_finetuning_forgets(two_patterns):
    model, new = two_patterns
    rehearsed = consolidate(model, new, ConsolidationConfig(train=CONSOLIDATION))
    assert rehearsed.patterns == ("1", "2", "3")
    assert _keeps_and_follows(model, rehearsed)
    finetuned = consolidate(model, new, ConsolidationConfig("finetune", train=CONSOLIDATION))
    assert finetuned.patterns == ("1", "2", "3")
    assert not _keeps_and_follows(model, finetuned)  # the check can fail: interference


@pytest.mark.parametrize("source", ["patterns", "sequences"])
def test_rehearsed_sequences_are_what_the_network_predicts(two_patterns, source):
    model, _ = two_patterns
    rehearsed = rehearse(model, n_steps=20, transient=30, source=source)
    assert [s.pattern for s in rehearsed] == list(model.sequence_patterns)
    if source == "patterns":
        # from the pattern's PB, its sequences are consecutive stretches of one closed loop
        first, second = rehearsed[0], rehearsed[1]
        assert np.array_equal(first.meta["pb"], model.pattern_pb["1"])
        assert not np.allclose(first.motor, second.motor)
    # From the recorded context and PB, the network predicts its rehearsal exactly: learning
    # starts with no error on the old patterns.
    from rnnpb.model.learning import per_output_mse
    from rnnpb.model.network import logit_numpy

    data = prepare_data(rehearsed, model_joint_limits(model))
    pb = np.stack([s.meta["pb"] for s in rehearsed])
    rho = np.broadcast_to(logit_numpy(pb)[:, None], (len(pb), 19, pb.shape[1]))
    context = logit_numpy(np.stack([s.meta["initial_context"] for s in rehearsed]))
    error = per_output_mse(
        (model.params, context.astype(np.float32)),
        rho.astype(np.float32),
        data.inputs.astype(np.float32),
        data.valid,
    )
    assert float(np.max(error)) < 1e-9


def test_history_records_each_step_and_survives_a_file(two_patterns, tmp_path):
    model, new = two_patterns
    model.save(tmp_path / "start.npz")
    start = TrainedModel.load(tmp_path / "start.npz")
    grown = consolidate(
        start,
        new,
        ConsolidationConfig(train=TrainConfig.fast(iterations=50)),
        parent=str(tmp_path / "start.npz"),
    )
    grown.save(tmp_path / "grown.npz")
    loaded = TrainedModel.load(tmp_path / "grown.npz")
    assert [e.method for e in loaded.history] == ["train", "rehearsal"]
    last = loaded.history[-1]
    assert last.added == ("3",) and last.patterns == ("1", "2", "3")
    assert last.parent == "start.npz" and last.parent_fingerprint == start.fingerprint
    assert last.train_config["iterations"] == 50 and last.created
    assert loaded.fingerprint == grown.fingerprint != start.fingerprint


def test_seeded_consolidations_repeat_bit_for_bit(two_patterns):
    model, new = two_patterns
    config = ConsolidationConfig(train=TrainConfig.fast(iterations=100, seed=3))
    a, b = consolidate(model, new, config), consolidate(model, new, config)
    for x, y in zip(a.params, b.params, strict=True):
        assert np.array_equal(np.asarray(x), np.asarray(y))
    assert np.array_equal(a.sequence_pb, b.sequence_pb)
    assert np.array_equal(a.initial_context, b.initial_context)
    assert a.fingerprint == b.fingerprint


def test_interrupted_consolidation_resumes_to_the_same_model(two_patterns, tmp_path):
    model, new = two_patterns
    config = ConsolidationConfig(train=TrainConfig.fast(iterations=300, checkpoint_every=100))
    checkpoint = tmp_path / "c.npz"

    def stop(progress):
        if progress.iteration >= 200:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        consolidate(model, new, config, progress=stop, checkpoint_path=checkpoint)
    resumed = consolidate(model, new, config, checkpoint_path=checkpoint, resume=True)
    # It went on from the checkpoint at 200: one chunk of 100 iterations.
    assert [i for i, _ in resumed.meta["training"]["history"]] == [300]
    whole = consolidate(model, new, config)
    assert resumed.fingerprint == whole.fingerprint
    # A checkpoint resumes only the consolidation of the same model: fine-tuning learns the
    # same data from any model, so the start is checked apart from the data.
    finetune = ConsolidationConfig("finetune", train=config.train)
    with pytest.raises(KeyboardInterrupt):
        consolidate(model, new, finetune, progress=stop, checkpoint_path=tmp_path / "f.npz")
    other = replace(model, params=type(model.params)(*(np.asarray(w) * 1.01 for w in model.params)))
    with pytest.raises(ModelFileError, match="another starting model or method"):
        consolidate(other, new, finetune, checkpoint_path=tmp_path / "f.npz", resume=True)


def test_held_old_pbs_stay_where_they_were_learned(two_patterns, tmp_path):
    model, new = two_patterns
    config = ConsolidationConfig(
        train=TrainConfig.fast(iterations=200, checkpoint_every=100)
    ).with_tuning(hold_old_pb="all")
    held = consolidate(model, new, config)
    # Rehearsed from each pattern's PB: every old sequence starts, and stays, there.
    n_old = len(model.sequence_patterns)
    for pb, pattern in zip(held.sequence_pb[:n_old], model.sequence_patterns, strict=True):
        assert np.array_equal(pb, model.pattern_pb[pattern])
    for pattern in model.patterns:
        assert np.array_equal(held.pattern_pb[pattern], model.pattern_pb[pattern])
    assert not np.allclose(held.sequence_pb[n_old:], 0.5)  # the new PB learned
    assert not np.array_equal(np.asarray(held.params[0]), np.asarray(model.params[0]))
    # The option is in the history, through a file.
    held.save(tmp_path / "held.npz")
    assert TrainedModel.load(tmp_path / "held.npz").history[-1].details["hold_old_pb"] == "all"
    free = consolidate(model, new, config.with_tuning(hold_old_pb="off"))
    assert free.history[-1].details["hold_old_pb"] == "off"
    assert not np.array_equal(free.sequence_pb[0], model.pattern_pb["1"])
    # Held for the first half: the chunk ends where the PBs are let go, and they then move.
    half = consolidate(model, new, config.with_tuning(hold_old_pb="first-half"))
    assert [i for i, _ in half.meta["training"]["history"]] == [0, 100, 200]
    assert not np.array_equal(half.sequence_pb[0], model.pattern_pb["1"])

    # A checkpoint of one hold never resumes another.
    def stop(progress):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        consolidate(model, new, config, progress=stop, checkpoint_path=tmp_path / "c.npz")
    for other in ("off", "first-half"):
        with pytest.raises(ModelFileError, match="another starting model or method"):
            consolidate(
                model,
                new,
                config.with_tuning(hold_old_pb=other),
                checkpoint_path=tmp_path / "c.npz",
                resume=True,
            )
    resumed = consolidate(model, new, config, checkpoint_path=tmp_path / "c.npz", resume=True)
    assert resumed.fingerprint == held.fingerprint
    with pytest.raises(ConfigError, match="hold_old_pb must be one of"):
        ConsolidationConfig().with_tuning(hold_old_pb="half")


def test_the_alternatives_run_the_same_way(two_patterns):
    from rnnpb.demonstrator import pattern_dataset

    model, new = two_patterns
    original = pattern_dataset(0, ("1", "2"))
    short = TrainConfig.fast(iterations=30)
    for method in ("finetune", "replay", "scratch"):
        grown = consolidate(
            model, new, ConsolidationConfig(method, train=short), replay_data=original
        )
        assert grown.patterns == ("1", "2", "3") and grown.history[-1].method == method
        assert len(grown.sequence_patterns) == 6
    # The replayed data are those the model learned, bit for bit.
    replayed = consolidate(
        model, new, ConsolidationConfig("replay", train=short), replay_data=original
    )
    assert replayed.history[-1].details["replay_data_matches_record"] is True
    # The hands as taught: a rehearsal or fine-tuning keeps the old patterns' own (the
    # rehearsed sequences are the network's generation, not what was shown) and adds the new
    # data's; replay and scratch learn from the original data, whose hands they are.
    shown = np.array([s.sensory for s in [*original, *new]])
    for method in ("rehearsal", "finetune", "replay", "scratch"):
        grown = consolidate(
            model, new, ConsolidationConfig(method, train=short), replay_data=original
        )
        assert grown.taught_sensory is not None
        np.testing.assert_allclose(grown.taught_sensory, shown, atol=1e-12)
    without = replace(model, taught_sensory=None)  # a model of format 2 kept none
    assert consolidate(without, new, ConsolidationConfig(train=short)).taught_sensory is None
    # The scratch method without a config: the first training's whole length.
    assert ConsolidationConfig("scratch").learning_for(model).iterations == 1200
    assert ConsolidationConfig().learning_for(model).iterations == 500


def test_a_warm_consolidation_learns_with_some_input_noise(two_patterns):
    """Without a learning of its own a warm-started consolidation adds at least the policy's
    input noise to the teacher-forced inputs (a model of the paper's algorithm has none), a
    rehearsal of the old function at least the policy's noise for it; a model with more keeps
    its own, and learning from scratch is the first's."""
    from rnnpb.model.consolidation import consolidation_policy

    model, _ = two_patterns
    paper = TrainConfig.paper(iterations=900)
    as_paper = replace(
        model,
        meta={**model.meta, "train_config": paper.to_dict(), "preset": {"name": "paper"}},
    )
    policy = consolidation_policy(as_paper, "add")
    least = {
        ConsolidationConfig(): policy.function_rehearsal_input_noise,
        ConsolidationConfig().with_tuning(rehearsal_target="trajectory"): policy.input_noise,
        ConsolidationConfig("finetune"): policy.input_noise,
        ConsolidationConfig("replay"): policy.input_noise,
    }
    for config, noise in least.items():
        learning = config.learning_for(as_paper)
        assert learning.input_noise == noise > 0
        assert (learning.optimizer, learning.learning_rate) == ("momentum", paper.learning_rate)
        assert learning.iterations == policy.iterations
    assert policy.function_rehearsal_input_noise > policy.input_noise
    assert ConsolidationConfig("scratch").learning_for(as_paper).input_noise == 0.0
    own = 0.05
    noisy = replace(
        model,
        meta={**model.meta, "train_config": {**model.meta["train_config"], "input_noise": own}},
    )
    assert ConsolidationConfig().learning_for(noisy).input_noise == own


@pytest.mark.parametrize(
    ("purpose", "preset", "expected"),
    [
        ("add", "paper", (20_000, 0.02, "first-half", "farthest")),
        ("add", "fast", (500, 0.02, "first-half", "farthest")),
        ("teach", "paper", (30_000, 0.03, "off", "centre")),
        ("teach", "fast", (1_000, 0.03, "off", "centre")),
    ],
)
def test_one_policy_sets_every_consolidation(two_patterns, purpose, preset, expected):
    """`rnnpb consolidate` (adding patterns) and teaching take their iterations, least input
    noise, PB hold and new PB start from one policy, by purpose and the model's preset; a
    rehearsal learns the old network's function either way, and a config's own choice wins."""
    from rnnpb.model.consolidation import consolidation_config

    model, _ = two_patterns
    learned = getattr(TrainConfig, preset)(iterations=900)
    recorded = {"train_config": learned.to_dict(), "preset": {"name": preset}}
    model = replace(model, meta={**model.meta, **recorded})
    config = consolidation_config(model, purpose)
    assert config.train is not None
    iterations, noise, hold, start = expected
    assert (config.train.iterations, config.train.input_noise) == (
        iterations,
        max(noise, learned.input_noise),
    )
    assert (config.hold_old_pb, config.new_pb_start, config.rehearsal_target) == (
        hold,
        start,
        "function",
    )
    assert config.purpose == purpose and config.method == "rehearsal"
    assert config.train.optimizer == learned.optimizer and config.train.seed == learned.seed
    given = consolidation_config(model, purpose, iterations=7, seed=3)
    assert given.train is not None and (given.train.iterations, given.train.seed) == (7, 3)
    own = ConsolidationConfig(purpose=purpose).with_tuning(hold_old_pb="all").resolved(model)
    assert own.hold_old_pb == "all" and own.new_pb_start == start
    with pytest.raises(ConfigError, match="purpose must be one of add, teach"):
        ConsolidationConfig(purpose="forget")  # type: ignore[arg-type]


def test_the_methods_are_named_once():
    """The command, the config and the model file's history know the same methods."""
    from rnnpb.model.consolidation import CONSOLIDATION_METHODS
    from rnnpb.model.io import HISTORY_METHODS

    assert CONSOLIDATION_METHODS == ("rehearsal", "finetune", "replay", "scratch")
    assert HISTORY_METHODS == ("train", *CONSOLIDATION_METHODS)


def test_a_config_file_overrides_the_policy(two_patterns):
    """Research changes any of the policy's values (a --config file's tables); an unknown
    key is refused with the file's name."""
    from rnnpb.model.consolidation import consolidation_config
    from rnnpb.presets import Overrides

    model, _ = two_patterns
    tables = {"consolidation": {"hold_old_pb": "off", "iterations": 7, "rehearsal_steps": 20}}
    added = consolidation_config(model, "add", overrides=Overrides(tables, "ablation.toml"))
    assert added.train is not None and added.train.iterations == 7
    assert (added.hold_old_pb, added.rehearsal_steps, added.new_pb_start) == ("off", 20, "farthest")
    taught = consolidation_config(
        model, "teach", overrides=Overrides({"teaching": {"input_noise": 0.05}}, "ablation.toml")
    )
    assert taught.train is not None and taught.train.input_noise == 0.05
    with pytest.raises(ConfigError, match="ablation.toml: unknown setting 'hold' in"):
        consolidation_config(
            model, overrides=Overrides({"consolidation": {"hold": "off"}}, "ablation.toml")
        )


def test_bad_input_is_refused_clearly(two_patterns):
    from rnnpb.demonstrator import pattern_dataset

    model, new = two_patterns
    with pytest.raises(ConfigError, match="'1' already learned"):
        consolidate(model, pattern_dataset(0, ("1",)), ConsolidationConfig())
    with pytest.raises(ConfigError, match="needs the original training data"):
        consolidate(model, new, ConsolidationConfig("replay"))
    with pytest.raises(ConfigError, match="missing 2"):
        consolidate(
            model, new, ConsolidationConfig("replay"), replay_data=pattern_dataset(0, ("1",))
        )
    with pytest.raises(ConfigError, match="method must be one of"):
        ConsolidationConfig("forget")  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="rehearsal_source must be one of"):
        ConsolidationConfig().with_tuning(rehearsal_source="data")
    # A model of another network size: its sensory-motor vector is not the data's.
    import jax

    from rnnpb.model import NetworkConfig, init_params

    small = NetworkConfig(sensory_size=2, motor_size=8)
    other = replace(
        model,
        network=small,
        params=init_params(small, jax.random.PRNGKey(0)),
        lower=model.lower[2:],
        upper=model.upper[2:],
    )
    with pytest.raises(ConfigError, match="another network size"):
        consolidate(other, new, ConsolidationConfig())


def test_a_model_file_of_format_1_still_loads(tmp_path):
    from pathlib import Path

    # Written by rnnpb before models recorded their history (format 1).
    old = TrainedModel.load(Path(__file__).parent / "data" / "model_format1.npz")
    assert old.patterns == ("0", "1")
    (entry,) = old.history
    assert entry.method == "train" and entry.added == ("0", "1") and entry.created is None
    assert entry.data_fingerprint == old.meta["training"]["data_fingerprint"]
    old.save(tmp_path / "m.npz")  # saved again, it is of the current format
    again = TrainedModel.load(tmp_path / "m.npz")
    assert again.history == old.history and again.fingerprint == old.fingerprint
    grown = consolidate(
        old,
        make_sequences(n_steps=20, kinds=(2,)),
        ConsolidationConfig(train=TrainConfig.fast(iterations=20)),
    )
    assert grown.patterns == ("0", "1", "2") and grown.network == old.network
    # Its normalization is kept: the limits of the synthetic set.
    assert np.allclose(model_joint_limits(grown), LIMITS)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda h: h[0].update(method="forget"), "history method 'forget'"),
        (lambda h: h[0].update(added=["../x"]), "history pattern name"),
        (lambda h: h[0].update(iterations=-1), "'iterations'"),
        (lambda h: h[0].update(surprise=1), "unknown field"),
        (lambda h: h.clear(), "history is not a list of 1"),
        (lambda h: h[0].update(patterns=["9"]), "last entry names other patterns"),
    ],
)
def test_a_bad_history_is_refused(tmp_path, change, message):
    import json

    from rnnpb.model.archive import load_archive, save_archive
    from rnnpb.model.io import MODEL_FORMAT_VERSION

    model = TrainedModel.load(__file__.rsplit("/", 1)[0] + "/data/model_format1.npz")
    model.save(tmp_path / "m.npz")
    meta, arrays = load_archive(tmp_path / "m.npz", "rnnpb-model", MODEL_FORMAT_VERSION)
    history = json.loads(json.dumps(meta["history"]))
    change(history)
    save_archive(tmp_path / "bad.npz", {**meta, "history": history}, arrays)
    with pytest.raises(ModelFileError, match=message):
        TrainedModel.load(tmp_path / "bad.npz")


def test_a_new_pattern_starts_at_the_pb_farthest_from_the_learned_ones(two_patterns):
    from rnnpb.model.consolidation import farthest_pb

    corners = np.array([[0.0, 0.0], [1.0, 1.0], [0.0, 1.0], [1.0, 0.0]])
    np.testing.assert_allclose(farthest_pb(corners), [0.5, 0.5])
    learned = np.array([[0.2, 0.2, 0.2, 0.2], [0.8, 0.8, 0.2, 0.2]])
    start = farthest_pb(learned)
    grid = np.linspace(0.1, 0.9, 5)
    assert all(v in grid for v in start)
    best = min(np.linalg.norm(start - p) for p in learned)
    mesh = np.stack(np.meshgrid(*[grid] * 4, indexing="ij"), -1).reshape(-1, 4)
    assert best >= max(min(np.linalg.norm(g - p) for p in learned) for g in mesh) - 1e-12
    # A large PB space is searched over a fixed, seeded set of points in the same box.
    wide = np.random.default_rng(1).uniform(0, 1, (5, 12))
    far = farthest_pb(wide)
    assert far.shape == (12,) and np.all((far >= 0.1) & (far <= 0.9))
    np.testing.assert_array_equal(far, farthest_pb(wide))
    # Consolidating: the start is recorded, the centre is still there, a bad name is refused.
    model, new = two_patterns
    short = TrainConfig.fast(iterations=20)
    grown = consolidate(model, new, ConsolidationConfig(train=short))
    assert grown.history[-1].details["new_pb_start"] == "farthest"
    centre = consolidate(
        model, new, ConsolidationConfig(train=short).with_tuning(new_pb_start="centre")
    )
    assert centre.history[-1].details["new_pb_start"] == "centre"
    assert not np.allclose(grown.sequence_pb[-1], centre.sequence_pb[-1])
    with pytest.raises(ConfigError, match="new_pb_start must be one of"):
        ConsolidationConfig().with_tuning(new_pb_start="middle")


def _response_change(before: TrainedModel, after: TrainedModel, noise: float) -> float:
    """RMS difference of ``after``'s and ``before``'s one-step predictions from the same noisy
    teacher-forced inputs around each of ``before``'s rehearsed cycles, each network from its
    own PB and initial context of the sequence (``after``'s old sequences come first)."""
    import jax.numpy as jnp

    from rnnpb.model.network import open_loop

    rehearsed = rehearse(before)
    data = prepare_data(rehearsed, model_joint_limits(before))
    rng = np.random.default_rng(7)
    forced = data.inputs[:, :-1] + noise * rng.standard_normal(data.inputs[:, :-1].shape)

    def predict(model: TrainedModel, pb: np.ndarray, context: np.ndarray) -> np.ndarray:
        pbs = np.broadcast_to(pb[:, None], (*forced.shape[:2], pb.shape[1]))
        out, _ = open_loop(
            model.params,
            jnp.asarray(context, jnp.float32),
            jnp.asarray(np.swapaxes(forced, 0, 1), jnp.float32),
            jnp.asarray(np.swapaxes(pbs, 0, 1), jnp.float32),
        )
        return np.asarray(out)

    n = len(rehearsed)
    was = predict(
        before,
        np.stack([s.meta["pb"] for s in rehearsed]),
        np.stack([s.meta["initial_context"] for s in rehearsed]),
    )
    now = predict(after, after.sequence_pb[:n], after.initial_context[:n])
    return float(np.sqrt(np.mean((now - was) ** 2)))


def test_function_rehearsal_keeps_the_old_networks_response_near_its_cycles(two_patterns):
    """A rehearsed sequence learning the old network's function keeps what the network
    predicts from inputs near the cycle (a person's version of the pattern); learning the
    cycle's next steps teaches it to pull them back onto the cycle instead."""
    model, new = two_patterns
    learning = TrainConfig.fast(iterations=1000)  # on this small model: 0.0036 against 0.0052
    function = consolidate(model, new, ConsolidationConfig(train=learning))
    trajectory = consolidate(
        model, new, ConsolidationConfig(train=learning).with_tuning(rehearsal_target="trajectory")
    )
    assert function.history[-1].details["rehearsal_target"] == "function"  # the default
    assert trajectory.history[-1].details["rehearsal_target"] == "trajectory"
    kept = _response_change(model, function, learning.input_noise)
    moved = _response_change(model, trajectory, learning.input_noise)
    assert kept < 0.8 * moved, (kept, moved)


def test_teacher_targets_are_the_start_networks_predictions():
    """Without noise a rehearsal's teacher predicts its rehearsed next steps (it generated
    them); a sequence it does not teach keeps its own next steps; noise moves the teacher's."""
    import jax.numpy as jnp

    from rnnpb.demonstrator import pattern_dataset
    from rnnpb.model.learning import Teacher, WarmStart, teacher_targets
    from rnnpb.robot import JOINT_LIMITS

    model = train(pattern_dataset(0, ("1",)), JOINT_LIMITS, config=TrainConfig.fast(iterations=50))
    rehearsed = rehearse(model, n_steps=12, transient=20)
    data = prepare_data(rehearsed, model_joint_limits(model))
    inputs = jnp.asarray(data.inputs, jnp.float32)
    context = np.stack([s.meta["initial_context"] for s in rehearsed])
    pb = np.stack([s.meta["pb"] for s in rehearsed])
    taught = np.arange(len(rehearsed)) == 0
    warm = WarmStart(model.params, context, pb, "start", taught=taught)
    teacher = warm.teacher()
    assert isinstance(teacher, Teacher)
    assert warm.identity == "start:taught=" + "".join("1" if t else "0" for t in taught)
    zero = jnp.zeros_like(inputs[:, :-1])
    targets = np.asarray(teacher_targets(teacher, inputs, zero))
    np.testing.assert_allclose(targets, data.inputs[:, 1:], atol=1e-5)
    noisy = np.asarray(teacher_targets(teacher, inputs, zero + 0.05))
    assert not np.allclose(noisy[0], data.inputs[0, 1:], atol=1e-3)
    np.testing.assert_array_equal(noisy[1:], np.asarray(inputs)[1:, 1:])  # exactly its own
    assert WarmStart(model.params, context, pb, "start").teacher() is None
    with pytest.raises(ConfigError, match="one flag per sequence"):
        WarmStart(model.params, context, pb, "start", taught=np.ones(5, bool))


def test_a_checkpoint_of_one_rehearsal_target_never_resumes_the_other(two_patterns, tmp_path):
    model, new = two_patterns
    learning = TrainConfig.fast(iterations=200, checkpoint_every=100)
    checkpoint = tmp_path / "c.npz"

    def stop(progress):
        if progress.iteration >= 100:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        consolidate(
            model,
            new,
            ConsolidationConfig(train=learning),
            progress=stop,
            checkpoint_path=checkpoint,
        )
    trajectory = ConsolidationConfig(train=learning).with_tuning(rehearsal_target="trajectory")
    with pytest.raises(ModelFileError, match="another starting model or method"):
        consolidate(model, new, trajectory, checkpoint_path=checkpoint, resume=True)
