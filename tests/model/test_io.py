"""Model files: save → load gives identical outputs; bad files fail clearly; writes are atomic."""

import json
import zipfile

import numpy as np
import pytest

from rnnpb.errors import ModelFileError
from rnnpb.model import MirrorSystem, TrainedModel, generate
from rnnpb.model.io import save_archive


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
