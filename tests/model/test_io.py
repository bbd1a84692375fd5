"""Model files: save → load gives identical outputs; bad files fail clearly; writes are atomic."""

import json
import zipfile

import numpy as np
import pytest

from rnnpb.errors import ModelFileError
from rnnpb.model import MirrorSystem, TrainedModel, generate
from rnnpb.model.archive import save_archive


def test_save_load_gives_identical_outputs(trained, tmp_path):
    path = tmp_path / "model.npz"
    trained.save(path)
    loaded = TrainedModel.load(path)
    assert loaded.patterns == trained.patterns
    assert loaded.network == trained.network
    np.testing.assert_array_equal(loaded.sequence_pb, trained.sequence_pb)
    assert loaded.meta["training"]["iterations"] == trained.meta["training"]["iterations"]
    pb = trained.pattern_pb["1"]
    np.testing.assert_array_equal(generate(loaded, pb, 30).motor, generate(trained, pb, 30).motor)
    a, b = MirrorSystem(trained), MirrorSystem(loaded)
    for u in np.random.default_rng(0).uniform(0.2, 0.8, (5, 4)):
        np.testing.assert_array_equal(a.step(u).motor, b.step(u).motor)


def test_history_and_renaming_go_through_the_model(trained, tmp_path):
    """A model's history is replaced, and a pattern renamed, by methods that leave the model
    they are called on as it was; both survive a file."""
    from dataclasses import replace

    first = trained.history[0]
    step = replace(first, method="rehearsal", parent="a.npz", details={"hold_old_pb": "off"})
    grown = trained.with_history((first, step))
    assert [e.method for e in grown.history] == ["train", "rehearsal"]
    assert [e.method for e in trained.history] == ["train"]
    old = trained.patterns[0]
    renamed = grown.renamed(old, "wave").renamed("wave", "swing")
    assert trained.patterns[0] == old and renamed.patterns[0] == "swing"
    renamed.save(tmp_path / "m.npz")
    loaded = TrainedModel.load(tmp_path / "m.npz")
    last = loaded.history[-1]
    assert loaded.patterns == renamed.patterns and last.patterns == renamed.patterns
    assert last.details["hold_old_pb"] == "off" and last.parent == "a.npz"
    assert [(r["from"], r["to"]) for r in last.details["renamed"]] == [
        (old, "wave"),
        ("wave", "swing"),
    ]
    assert loaded.history[0] == first


def _corrupt(trained, tmp_path, edit):
    path = tmp_path / "model.npz"
    trained.save(path)
    with np.load(path) as archive:
        arrays = {k: archive[k] for k in archive.files}
    meta = json.loads(arrays.pop("meta.json").tobytes())
    edit(meta, arrays)
    save_archive(path, meta, arrays)
    return path


def test_truncated_file(trained, tmp_path):
    path = tmp_path / "model.npz"
    trained.save(path)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(ModelFileError, match=f"{path}.*truncated"):
        TrainedModel.load(path)


def test_foreign_files(tmp_path):
    text = tmp_path / "notes.npz"
    text.write_text("hello")
    with pytest.raises(ModelFileError, match="not a readable"):
        TrainedModel.load(text)
    foreign = tmp_path / "foreign.npz"
    np.savez(foreign, weights=np.zeros(3))
    with pytest.raises(ModelFileError, match="no meta.json"):
        TrainedModel.load(foreign)
    with pytest.raises(ModelFileError, match="no such file"):
        TrainedModel.load(tmp_path / "missing.npz")
    with pytest.raises(ModelFileError, match="is a directory"):
        TrainedModel.load(tmp_path)


def test_pickled_content_is_never_loaded(tmp_path):
    path = tmp_path / "evil.npz"
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr(
            "meta.json.npy",
            b"\x93NUMPY\x01\x00v\x00{'descr': '|O', "
            b"'fortran_order': False, 'shape': (1,), }" + b" " * 60 + b"\n",
        )
    with pytest.raises(ModelFileError):
        TrainedModel.load(path)


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda m, a: m.update(format="something-else"), "format is 'something-else'"),
        (lambda m, a: m.update(format_version=99), "format version 99 is not supported"),
        (lambda m, a: a.pop("params/w_in"), "missing array 'params/w_in'"),
        (lambda m, a: a.update({"params/w_out": np.zeros((3, 3))}), "has shape"),
        (lambda m, a: m["network"].update(hidden_size=41), "expected"),
        (lambda m, a: a.update(lower=np.full(12, np.nan)), "NaN"),
        (lambda m, a: m.update(sequence_patterns=["a"]), "expected"),
    ],
)
def test_mismatched_content(trained, tmp_path, edit, message):
    path = _corrupt(trained, tmp_path, edit)
    with pytest.raises(ModelFileError, match=message) as error:
        TrainedModel.load(path)
    assert str(path) in str(error.value)


def test_failed_save_leaves_the_old_file_and_no_debris(trained, tmp_path, monkeypatch):
    path = tmp_path / "model.npz"
    trained.save(path)
    before = path.read_bytes()

    def broken_savez(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(np, "savez", broken_savez)
    with pytest.raises(OSError):
        trained.save(path)
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["model.npz"]


def test_trained_model_passes_the_robot_check_and_narrower_bounds_do_too(trained, tmp_path):
    from rnnpb.robot import JOINT_LIMITS as ROBOT_LIMITS

    from .synthetic import LIMITS as JOINT_LIMITS

    path = tmp_path / "model.npz"
    trained.save(path)
    # This model learned joints of [-2, 2] rad: the humanoid's own limits are narrower.
    with pytest.raises(ModelFileError, match="joint lshp is \\[-2, 2\\] rad, outside"):
        TrainedModel.load(path, joint_limits=ROBOT_LIMITS)
    loaded = TrainedModel.load(path, joint_limits=JOINT_LIMITS)
    np.testing.assert_array_equal(loaded.upper, trained.upper)
    narrow = _corrupt(
        trained,
        tmp_path,
        lambda meta, arrays: arrays.update(
            upper=arrays["upper"] - 0.1 * (arrays["upper"] - arrays["lower"])
        ),
    )
    assert TrainedModel.load(narrow, joint_limits=JOINT_LIMITS) is not None
    wide = _corrupt(
        trained, tmp_path, lambda meta, arrays: arrays.update(upper=arrays["upper"] + 1.0)
    )
    with pytest.raises(ModelFileError, match="outside the robot's joint limits"):
        TrainedModel.load(wide, joint_limits=JOINT_LIMITS)


def test_the_hands_as_taught_are_kept_and_read_back(trained, sequences, tmp_path):
    # Training keeps each sequence's hands (normalized: sensory values are in [0, 1] as they
    # are), recognition's templates.
    assert trained.taught_sensory is not None
    for taught, sequence in zip(trained.taught_sensory, sequences, strict=True):
        np.testing.assert_allclose(taught[: sequence.n_steps], sequence.sensory, atol=1e-12)
        assert np.isnan(taught[sequence.n_steps :]).all()
    hands = trained.taught_hands
    assert hands is not None and set(hands) == set(trained.patterns)
    assert sum(len(h) for h in hands.values()) == len(sequences)
    path = tmp_path / "model.npz"
    trained.save(path)
    loaded = TrainedModel.load(path)
    np.testing.assert_array_equal(loaded.taught_sensory, trained.taught_sensory)
    assert loaded.fingerprint == trained.fingerprint
    assert "taught_steps" not in loaded.meta


def test_a_model_of_format_2_loads_without_taught_hands(trained, tmp_path):
    def as_format_2(meta, arrays):
        meta.update(format_version=2)
        meta.pop("taught_steps")
        arrays.pop("taught_sensory")

    loaded = TrainedModel.load(_corrupt(trained, tmp_path, as_format_2))
    assert loaded.taught_sensory is None and loaded.taught_hands is None
    mirror = MirrorSystem(loaded)  # recognition goes by the network's evidence alone
    assert mirror.step([0.5, 0.5, 0.5, 0.5]).novelty == ""


def _taught_edit(change):
    def edit(meta, arrays):
        taught = arrays["taught_sensory"].copy()
        change(taught)
        arrays["taught_sensory"] = taught

    return edit


@pytest.mark.parametrize(
    "edit, message",
    [
        (_taught_edit(lambda t: t.__setitem__((0, 3, 1), np.nan)), "padded with NaN"),
        (_taught_edit(lambda t: t.__setitem__((0, 3, 1), 1.5)), r"in \[0, 1\]"),
        (_taught_edit(lambda t: t.__setitem__((0, 3, 1), np.inf)), "infinite"),
        (lambda m, a: m.update(taught_steps=0), "taught_steps"),
        (lambda m, a: m.update(taught_steps=7), "has shape"),
        (lambda m, a: a.pop("taught_sensory"), "missing array 'taught_sensory'"),
    ],
)
def test_bad_taught_hands_are_refused(trained, tmp_path, edit, message):
    path = _corrupt(trained, tmp_path, edit)
    with pytest.raises(ModelFileError, match=message) as error:
        TrainedModel.load(path)
    assert str(path) in str(error.value)
