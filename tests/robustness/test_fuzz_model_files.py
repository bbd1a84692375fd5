"""Model files and training checkpoints: damaged, truncated or forged archives give a
ModelFileError naming the file — never a zip, JSON, numpy or memory error from inside."""

import io
import json
import zipfile

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from rnnpb.errors import ModelFileError
from rnnpb.model import TrainConfig, TrainedModel
from rnnpb.model.archive import load_archive, save_archive
from rnnpb.model.io import MODEL_FORMAT, MODEL_FORMAT_VERSION
from rnnpb.model.learning import init_state, prepare_data
from rnnpb.model.training import load_checkpoint, save_checkpoint
from rnnpb.robot import JOINT_LIMITS
from rnnpb.sequences import read_sequence_files

FUZZ = settings(
    max_examples=60,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)


def _load_or_clear_error(path):
    try:
        return TrainedModel.load(path)
    except ModelFileError as error:
        assert str(error).startswith(str(path)), str(error)
        assert "\n" not in str(error)
        return None


@pytest.fixture(scope="module")
def model_bytes(model_file):
    return model_file.read_bytes()


@FUZZ
@given(data=st.binary(max_size=600))
def test_random_bytes(tmp_path, data):
    path = tmp_path / "model.npz"
    path.write_bytes(data)
    assert _load_or_clear_error(path) is None


@FUZZ
@given(fraction=st.floats(min_value=0, max_value=1, exclude_max=True))
def test_truncated_model(tmp_path, model_bytes, fraction):
    path = tmp_path / "model.npz"
    path.write_bytes(model_bytes[: int(len(model_bytes) * fraction)])
    assert _load_or_clear_error(path) is None


@FUZZ
@given(fraction=st.floats(min_value=0, max_value=1, exclude_max=True))
@example(fraction=0.435546875)  # a damaged .npy header: NumPy's parser raised TokenError
def test_damaged_compressed_model(tmp_path, model_file, fraction):
    # Users may re-save a model with np.savez_compressed; damage then also hits zlib.
    with np.load(model_file) as archive:
        arrays = {name: archive[name] for name in archive.files}
    buffer = io.BytesIO()
    np.savez_compressed(buffer, **arrays)
    data = bytearray(buffer.getvalue())
    data[int(fraction * len(data))] ^= 0x5A
    path = tmp_path / "model.npz"
    path.write_bytes(bytes(data))
    model = _load_or_clear_error(path)
    if model is not None:
        assert np.all(model.upper > model.lower)


@FUZZ
@given(
    flips=st.lists(
        st.tuples(st.floats(0, 1, exclude_max=True), st.integers(1, 255)), min_size=1, max_size=8
    )
)
def test_corrupted_bytes(tmp_path, model_bytes, flips):
    data = bytearray(model_bytes)
    for where, mask in flips:
        data[int(where * len(data))] ^= mask
    path = tmp_path / "model.npz"
    path.write_bytes(bytes(data))
    model = _load_or_clear_error(path)
    if model is not None:
        # Damage in the zip's slack (timestamps, comments) may leave every array intact.
        assert np.all(np.isfinite(model.sequence_pb)) and np.all(model.upper > model.lower)


def _forge(path, meta, arrays):
    buffer = io.BytesIO()
    payload = dict(arrays)
    if meta is not None:
        payload["meta.json"] = np.frombuffer(
            meta if isinstance(meta, bytes) else json.dumps(meta).encode(), np.uint8
        )
    np.savez(buffer, **payload)
    path.write_bytes(buffer.getvalue())


@pytest.fixture(scope="module")
def genuine(model_file):
    with np.load(model_file) as archive:
        arrays = {name: archive[name] for name in archive.files}
    meta = json.loads(arrays.pop("meta.json").tobytes())
    return meta, arrays


def _with(genuine, meta_changes=None, array_changes=None):
    meta, arrays = genuine
    meta = {**meta, **(meta_changes or {})}
    arrays = {**arrays, **(array_changes or {})}
    return meta, {k: v for k, v in arrays.items() if v is not None}


@pytest.mark.parametrize(
    "name, build, message",
    [
        ("no meta", lambda g: (None, g[1]), "no meta.json inside"),
        ("bad utf-8", lambda g: (b"\xff\xfe{", g[1]), "meta.json is not valid JSON"),
        (
            "deep JSON",
            lambda g: (b"[" * 100_000 + b"]" * 100_000, g[1]),
            "meta.json is not valid JSON",
        ),
        (
            "huge integer",
            lambda g: (b'{"format": ' + b"9" * 5000 + b"}", g[1]),
            "meta.json is not valid JSON",
        ),
        ("JSON list", lambda g: ([1, 2], g[1]), "format is None"),
        ("foreign format", lambda g: _with(g, {"format": "other"}), "format is 'other'"),
        ("future version", lambda g: _with(g, {"format_version": 99}), "format version 99"),
        ("network a string", lambda g: _with(g, {"network": "big"}), "bad network config"),
        (
            "network negative",
            lambda g: _with(g, {"network": {**g[0]["network"], "hidden_size": -4}}),
            "bad network config",
        ),
        (
            "network huge",
            lambda g: _with(g, {"network": {**g[0]["network"], "hidden_size": 10**30}}),
            "expected",
        ),
        ("patterns not a list", lambda g: _with(g, {"sequence_patterns": 7}), "pattern list"),
        (
            "array of text",
            lambda g: _with(g, array_changes={"lower": np.array(["a"] * 12)}),
            "dtype <U1, expected real numbers",
        ),
        (
            "complex array",
            lambda g: _with(g, array_changes={"upper": np.ones(12) * 1j}),
            "expected real numbers",
        ),
        (
            "NaN weights",
            lambda g: _with(
                g, array_changes={"params/w_in": np.full_like(g[1]["params/w_in"], np.nan)}
            ),
            "NaN or infinite",
        ),
        (
            "missing array",
            lambda g: _with(g, array_changes={"sequence_pb": None}),
            "missing array 'sequence_pb'",
        ),
        ("wrong shape", lambda g: _with(g, array_changes={"lower": np.zeros(3)}), "has shape (3,)"),
        (
            "upper below lower",
            lambda g: _with(g, array_changes={"upper": np.zeros(12)}),
            "upper <= lower",
        ),
    ],
)
def test_forged_model_files(tmp_path, genuine, name, build, message):
    meta, arrays = build(genuine)
    path = tmp_path / "model.npz"
    _forge(path, meta, arrays)
    with pytest.raises(ModelFileError) as caught:
        TrainedModel.load(path)
    assert str(caught.value).startswith(str(path)) and message in str(caught.value)


@pytest.mark.parametrize(
    "shape, message",
    [
        ((10**13,), r"array 'lower' has shape \(10000000000000,\), expected \(12,\)"),
        ((12,), r"array 'lower' claims 96 bytes but its member holds 32"),
    ],
)
def test_array_claiming_huge_size(tmp_path, genuine, shape, message):
    meta, arrays = genuine
    header = np.lib.format.header_data_from_array_1_0(np.zeros(4))
    header["shape"] = shape
    big = io.BytesIO()
    np.lib.format.write_array_header_1_0(big, header)
    path = tmp_path / "model.npz"
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr("meta.json.npy", _npy(np.frombuffer(json.dumps(meta).encode(), np.uint8)))
        for name, array in arrays.items():
            archive.writestr(
                f"{name}.npy", big.getvalue() + b"\0" * 32 if name == "lower" else _npy(array)
            )
    # Refused from the header, before anything of that size is allocated.
    with pytest.raises(ModelFileError, match=message):
        TrainedModel.load(path)


def _npy(array):
    buffer = io.BytesIO()
    np.save(buffer, array)
    return buffer.getvalue()


def test_archive_paths(tmp_path):
    with pytest.raises(ModelFileError, match="no such file"):
        TrainedModel.load(tmp_path / "none.npz")
    with pytest.raises(ModelFileError, match="is a directory"):
        TrainedModel.load(tmp_path)
    save_archive(tmp_path / "a.npz", {"format": "x", "format_version": 1}, {"v": np.ones(2)})
    meta, arrays = load_archive(tmp_path / "a.npz", "x", 1)
    assert meta["format"] == "x" and arrays["v"].tolist() == [1.0, 1.0]
    with pytest.raises(ModelFileError, match=r"not an rnnpb model file \(format is .x.\)"):
        load_archive(tmp_path / "a.npz", MODEL_FORMAT, MODEL_FORMAT_VERSION)


@pytest.fixture(scope="module")
def checkpoint_setup(data_dir, tmp_path_factory):
    data = prepare_data(read_sequence_files([data_dir]), JOINT_LIMITS)
    config = TrainConfig.fast(iterations=10)
    from rnnpb.model import NetworkConfig

    network = NetworkConfig()
    state = init_state(data, network, config)
    path = tmp_path_factory.mktemp("ckpt") / "c.npz"
    save_checkpoint(path, state, data, network, config)
    return path, state, data, network, config


def test_checkpoint_round_trip_and_forgeries(tmp_path, checkpoint_setup):
    path, state, data, network, config = checkpoint_setup
    restored = load_checkpoint(path, state, data, network, config)
    assert int(restored.iteration) == int(state.iteration)
    with np.load(path) as archive:
        arrays = {name: archive[name] for name in archive.files}
    meta = json.loads(arrays.pop("meta.json").tobytes())
    cases = [
        ({**meta, "train_config": "abc"}, arrays, "has no training config"),
        ({**meta, "train_config": [1, 2]}, arrays, "has no training config"),
        (
            meta,
            {
                **arrays,
                "state/0000": np.array(["x"] * arrays["state/0000"].size).reshape(
                    arrays["state/0000"].shape
                ),
            },
            "expected real numbers",
        ),
        ({**meta, "data_fingerprint": "other"}, arrays, "other training data"),
        ({**meta, "n_leaves": 1}, arrays, "unexpected member(s) 'state/0001'"),
        ({**meta, "n_leaves": 99}, arrays, "missing array 'state/00"),
    ]
    for forged_meta, forged_arrays, message in cases:
        forged = tmp_path / "forged.npz"
        _forge(forged, forged_meta, forged_arrays)
        with pytest.raises(ModelFileError) as caught:
            load_checkpoint(forged, state, data, network, config)
        assert str(caught.value).startswith(str(forged)) and message in str(caught.value)
    truncated = tmp_path / "truncated.npz"
    truncated.write_bytes(path.read_bytes()[:-100])
    with pytest.raises(ModelFileError, match="truncated or not an .npz"):
        load_checkpoint(truncated, state, data, network, config)
