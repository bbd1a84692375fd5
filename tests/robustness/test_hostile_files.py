"""Files built to hurt: zip bombs, endless or blocking paths, values that freeze the robot,
names that carry markup, and writers that must name the file they failed to write. Each is
refused (or handled) with one line naming the file — before the harm, not after it."""

import io
import json
import os
import stat
import string
import threading
import tracemalloc
import zipfile

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rnnpb._atomic import atomic_write
from rnnpb._reading import MAX_LINE_CHARS, MAX_TEXT_FILE_BYTES
from rnnpb.cli import main
from rnnpb.errors import ConfigError, DataFileError, ModelFileError
from rnnpb.interaction import SessionRecorder, read_session
from rnnpb.interaction.loop import StepRecord
from rnnpb.model import TrainedModel
from rnnpb.model.archive import MAX_ARCHIVE_BYTES
from rnnpb.model.io import check_joint_limits
from rnnpb.perception import ImageFolderSource, load_ball_colors
from rnnpb.robot import JOINT_LIMITS
from rnnpb.sequences import (
    Sequence,
    pattern_name_problem,
    read_sensory_stream,
    read_sequences,
    write_sensory_stream,
    write_sequence,
)
from rnnpb.vectors import MOTOR_NAMES, SENSORY_NAMES

FUZZ = settings(
    max_examples=40,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
XSS = "<img src=x onerror=alert(1)>"
CSV_READERS = {
    "read_sequences": read_sequences,
    "read_sensory_stream": read_sensory_stream,
    "read_session": read_session,
}


def _one_line_error(error, path):
    message = str(error)
    assert message.startswith(str(path)), message
    assert "\n" not in message, message
    return message


@pytest.fixture(scope="module")
def genuine(model_file):
    with np.load(model_file) as archive:
        arrays = {name: archive[name] for name in archive.files}
    meta = json.loads(arrays.pop("meta.json").tobytes())
    return meta, arrays


def _npy(array):
    buffer = io.BytesIO()
    np.save(buffer, array)
    return buffer.getvalue()


def _write_model(path, meta, arrays, extra=(), compression=zipfile.ZIP_STORED):
    """A model archive written member by member, as a forger would."""
    with zipfile.ZipFile(path, "w", compression) as archive:
        archive.writestr("meta.json.npy", _npy(np.frombuffer(json.dumps(meta).encode(), np.uint8)))
        for name, array in arrays.items():
            archive.writestr(f"{name}.npy", array if isinstance(array, bytes) else _npy(array))
        for name, data in extra:
            archive.writestr(name, data)
    return path


def _load_peak(path, **kwargs):
    """Load, expecting ModelFileError; return it and the peak traced memory in bytes."""
    tracemalloc.start()
    try:
        with pytest.raises(ModelFileError) as caught:
            TrainedModel.load(path, **kwargs)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    return caught.value, peak


def _zeros_member(archive, name, shape, n_bytes):
    """A deflated .npy member of ``n_bytes`` zeros: a few hundred kB on disk."""
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        header, {"descr": "<f8", "fortran_order": False, "shape": shape}
    )
    with archive.open(f"{name}.npy", "w", force_zip64=True) as member:
        member.write(header.getvalue())
        chunk = bytes(2**20)
        for _ in range(n_bytes // len(chunk)):
            member.write(chunk)


# --- 1. zip bombs and members that do not belong ---------------------------------------------


def test_zip_bomb_is_refused_before_it_is_decompressed(tmp_path, genuine):
    meta, arrays = genuine
    path = tmp_path / "bomb.npz"
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("meta.json.npy", _npy(np.frombuffer(json.dumps(meta).encode(), np.uint8)))
        for name, array in arrays.items():
            if name == "lower":
                _zeros_member(archive, name, (8 * 2**20,), 64 * 2**20)
            else:
                archive.writestr(f"{name}.npy", _npy(array))
    assert path.stat().st_size < 2 * 2**20
    error, peak = _load_peak(path)
    message = _one_line_error(error, path)
    assert "member 'lower' is 67,108,992 bytes uncompressed" in message
    assert "refused before reading it" in message
    # Nothing near the 64 MiB the member claims was ever held.
    assert peak < 8 * 2**20


def test_checkpoint_total_size_is_capped(tmp_path):
    from rnnpb.model.training import CHECKPOINT_FORMAT, CHECKPOINT_FORMAT_VERSION

    path = tmp_path / "c.checkpoint.npz"
    meta = {"format": CHECKPOINT_FORMAT, "format_version": CHECKPOINT_FORMAT_VERSION, "n_leaves": 1}
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("meta.json.npy", _npy(np.frombuffer(json.dumps(meta).encode(), np.uint8)))
        _zeros_member(
            archive, "state/0000", (MAX_ARCHIVE_BYTES // 8 + 2**17,), MAX_ARCHIVE_BYTES + 2**20
        )
    from rnnpb.model.archive import load_archive

    tracemalloc.start()
    try:
        with pytest.raises(ModelFileError) as caught:
            load_archive(path, CHECKPOINT_FORMAT, CHECKPOINT_FORMAT_VERSION)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert "MiB uncompressed, more than the 512 MiB" in _one_line_error(caught.value, path)
    assert peak < 8 * 2**20


@FUZZ
@given(
    name=st.text(alphabet=string.ascii_letters + "/._-", min_size=1, max_size=12),
    suffix=st.sampled_from([".npy", ".txt", ""]),
)
def test_unknown_members_are_refused(tmp_path, genuine, name, suffix):
    meta, arrays = genuine
    if f"{name}{suffix}".removesuffix(".npy") in {*arrays, "meta.json"}:
        return  # a genuine member's name, written twice: tested below
    path = _write_model(
        tmp_path / "extra.npz", meta, arrays, extra=[(f"{name}{suffix}", _npy(np.zeros(2)))]
    )
    with pytest.raises(ModelFileError) as caught:
        TrainedModel.load(path)
    message = _one_line_error(caught.value, path)
    assert "unexpected member" in message or "not a .npy array" in message


def test_a_member_twice_is_refused(tmp_path, genuine):
    meta, arrays = genuine
    path = tmp_path / "twice.npz"
    with pytest.warns(UserWarning, match="Duplicate name"):
        _write_model(path, meta, arrays, extra=[("lower.npy", _npy(arrays["lower"] - 1))])
    with pytest.raises(ModelFileError, match="holds the member 'lower.npy' twice"):
        TrainedModel.load(path)


# --- 3. model contents --------------------------------------------------------------------


def test_npy_renamed_npz(tmp_path):
    path = tmp_path / "model.npz"
    np.save(path.with_suffix(".npy"), np.zeros(3))
    path.with_suffix(".npy").rename(path)
    with pytest.raises(ModelFileError) as caught:
        TrainedModel.load(path)
    assert "is a single .npy array, not an .npz archive" in _one_line_error(caught.value, path)


@pytest.mark.parametrize("payload", [b"plain text, not an array", b"", b"\x93NUMPY"])
def test_plain_member_where_an_array_belongs(tmp_path, genuine, payload):
    meta, arrays = genuine
    path = _write_model(tmp_path / "model.npz", meta, {**arrays, "lower": payload})
    with pytest.raises(ModelFileError) as caught:
        TrainedModel.load(path)
    message = _one_line_error(caught.value, path)
    assert "'lower'" in message or "not a readable" in message


def test_model_with_zero_sequences_is_refused(tmp_path, genuine):
    meta, arrays = genuine
    network = meta["network"]
    path = _write_model(
        tmp_path / "empty.npz",
        {**meta, "sequence_patterns": []},
        {
            **arrays,
            "sequence_pb": np.zeros((0, network["pb_size"])),
            "initial_context": np.zeros((0, network["context_size"])),
        },
    )
    with pytest.raises(ModelFileError) as caught:
        TrainedModel.load(path)
    assert "holds no training sequences" in _one_line_error(caught.value, path)


@FUZZ
@given(
    value=st.floats(min_value=3.5e38, max_value=1e308)
    | st.floats(max_value=-3.5e38, min_value=-1e308),
    name=st.sampled_from(["params/w_in", "params/b_out", "lower"]),
)
def test_float64_beyond_float32_is_refused(tmp_path, genuine, value, name):
    meta, arrays = genuine
    changed = arrays[name].astype(np.float64)
    changed.flat[0] = value
    path = _write_model(tmp_path / "wide.npz", meta, {**arrays, name: changed})
    with pytest.raises(ModelFileError) as caught:
        TrainedModel.load(path)
    assert "beyond the range of float32" in _one_line_error(caught.value, path)


@pytest.mark.parametrize("name, value", [("sequence_pb", 1e30), ("initial_context", -2.0)])
def test_pb_and_context_outside_the_unit_interval(tmp_path, genuine, name, value):
    meta, arrays = genuine
    changed = arrays[name].copy()
    changed.flat[0] = value
    path = _write_model(tmp_path / "m.npz", meta, {**arrays, name: changed})
    with pytest.raises(ModelFileError, match=f"array '{name}' has values outside"):
        TrainedModel.load(path)


def _with_motor_bounds(genuine, scale):
    meta, arrays = genuine
    lower, upper = arrays["lower"].copy(), arrays["upper"].copy()
    centre = (lower[4:] + upper[4:]) / 2
    lower[4:] = centre + (lower[4:] - centre) * scale
    upper[4:] = centre + (upper[4:] - centre) * scale
    return meta, {**arrays, "lower": lower, "upper": upper}


@FUZZ
@given(scale=st.floats(min_value=0.05, max_value=20))
def test_normalization_must_lie_within_the_joint_limits(tmp_path, genuine, scale):
    path = _write_model(tmp_path / "m.npz", *_with_motor_bounds(genuine, scale))
    assert TrainedModel.load(path) is not None  # the model package knows no robot
    if scale <= 1:
        model = TrainedModel.load(path, joint_limits=JOINT_LIMITS)
        assert np.all(model.upper[4:] <= JOINT_LIMITS[:, 1] + 1e-9)
    else:
        with pytest.raises(ModelFileError) as caught:
            TrainedModel.load(path, joint_limits=JOINT_LIMITS)
        message = _one_line_error(caught.value, path)
        assert "outside the robot's joint limits" in message
        assert any(f"joint {name} " in message for name in MOTOR_NAMES)


def test_joint_limits_of_another_robot_are_refused(model):
    with pytest.raises(ModelFileError, match="has 8 motor values but the robot"):
        check_joint_limits(model, JOINT_LIMITS[:6], "m.npz")


@pytest.mark.slow
def test_interact_refuses_a_model_wider_than_the_robot(tmp_path, genuine, capsys):
    path = _write_model(tmp_path / "wide.npz", *_with_motor_bounds(genuine, 10))
    code = main(
        [
            "interact",
            "--model",
            str(path),
            "--source",
            "scenario:held:1",
            "--out",
            str(tmp_path / "out"),
            "--steps",
            "2",
        ]
    )
    err = capsys.readouterr().err
    assert code == 2 and err.startswith(f"rnnpb: error: {path}: normalization of joint ")
    assert len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out" / "session.csv").exists()


# --- 4. pattern names --------------------------------------------------------------------


@settings(max_examples=200, deadline=None, database=None)
@given(name=st.text(max_size=40))
def test_pattern_name_rule(name):
    problem = pattern_name_problem(name)
    allowed = (
        1 <= len(name) <= 32
        and name == name.strip(" ")
        and all(c.isalnum() or c in "-_. " for c in name)
    )
    assert (problem is None) == allowed, (name, problem)
    if any(c in name for c in "<>&\"'`=/\\\n\r\t\x00"):
        assert problem is not None


@pytest.mark.parametrize("name", [XSS, "a" * 33, "wave\nnext", " wave", "a&b", "x\u202ey"])
def test_model_with_a_bad_pattern_name_is_refused(tmp_path, genuine, name):
    meta, arrays = genuine
    patterns = list(meta["sequence_patterns"])
    patterns[0] = name
    path = _write_model(tmp_path / "m.npz", {**meta, "sequence_patterns": patterns}, arrays)
    with pytest.raises(ModelFileError) as caught:
        TrainedModel.load(path)
    assert "pattern name" in _one_line_error(caught.value, path)


def _sequence_text(pattern=None, rows=3):
    header = ["step", *SENSORY_NAMES, *MOTOR_NAMES] + (["pattern"] if pattern else [])
    lines = [",".join(header)]
    for t in range(rows):
        cells = [str(t), *["0.5"] * 12] + ([f'"{pattern}"'] if pattern else [])
        lines.append(",".join(cells))
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("name", [XSS, "x" * 40, "tab\there"])
def test_sequence_file_with_a_bad_pattern_column(tmp_path, name):
    path = tmp_path / "seq.csv"
    path.write_text(_sequence_text(name))
    with pytest.raises(DataFileError) as caught:
        read_sequences(path)
    assert "pattern name" in _one_line_error(caught.value, path)


def test_file_name_pattern_is_checked_and_train_refuses_it(tmp_path, capsys):
    folder = tmp_path / "data"
    folder.mkdir()
    path = folder / f"{XSS}_1.csv"
    path.write_text(_sequence_text())
    with pytest.raises(DataFileError, match="pattern name '<img src=x onerror=alert"):
        read_sequences(path)
    code = main(
        [
            "train",
            "--data",
            str(folder),
            "--out",
            str(tmp_path / "m.npz"),
            "--iterations",
            "2",
            "--no-progress",
        ]
    )
    err = capsys.readouterr().err
    assert code == 2 and err.startswith(f"rnnpb: error: {path}") and "pattern name" in err
    assert not (tmp_path / "m.npz").exists()


# --- 2. unbounded lines, huge files, FIFOs and devices ---------------------------------------


@pytest.mark.parametrize("reader", list(CSV_READERS))
def test_fifo_is_refused_without_blocking(tmp_path, reader):
    path = tmp_path / "stream.csv"
    os.mkfifo(path)
    outcome = {}

    def read():
        try:
            CSV_READERS[reader](path)
        except DataFileError as error:
            outcome["error"] = str(error)

    worker = threading.Thread(target=read, daemon=True)
    worker.start()
    worker.join(timeout=10)
    if worker.is_alive():  # unblock the reader so the test run can end
        with open(path, "w") as writer:
            writer.write("")
        pytest.fail(f"{reader} blocked on a FIFO")
    expected = "a session recording (.csv)" if reader == "read_session" else "a CSV file"
    assert outcome["error"] == (
        f"{path}: is not a regular file (a FIFO, device or socket), expected {expected}"
    )


def test_colour_fifo_and_device_are_refused(tmp_path):
    path = tmp_path / "colours.json"
    os.mkfifo(path)
    with pytest.raises(ConfigError, match="is not a regular file"):
        load_ball_colors(path)
    with pytest.raises(ConfigError, match="is not a regular file"):
        load_ball_colors("/dev/zero")
    big = tmp_path / "big.json"
    with open(big, "wb") as handle:
        handle.truncate(2**20 + 1)
    with pytest.raises(ConfigError, match="larger than the 1 MiB"):
        load_ball_colors(big)


@pytest.mark.parametrize("reader", list(CSV_READERS))
def test_devices_are_refused(reader):
    for device in ("/dev/zero", "/dev/urandom"):
        with pytest.raises(DataFileError, match=f"^{device}: is not a regular file"):
            CSV_READERS[reader](device)


@pytest.mark.parametrize("reader", list(CSV_READERS))
def test_file_over_the_size_cap_is_refused_unread(tmp_path, reader):
    path = tmp_path / "huge.csv"
    with open(path, "wb") as handle:  # sparse: takes no disk space
        handle.truncate(MAX_TEXT_FILE_BYTES + 1)
    with pytest.raises(DataFileError, match="is 256 MiB, larger than the 256 MiB"):
        CSV_READERS[reader](path)


@FUZZ
@given(
    extra=st.integers(min_value=1, max_value=3 * MAX_LINE_CHARS),
    filler=st.sampled_from(["9", ",", "a", "é", '"']),
    reader=st.sampled_from(list(CSV_READERS)),
)
def test_line_without_break_is_refused_at_the_limit(tmp_path, extra, filler, reader):
    path = tmp_path / "long.csv"
    header = ",".join(["step", "time_s", *SENSORY_NAMES, *MOTOR_NAMES])
    path.write_text(header + "\n" + filler * (MAX_LINE_CHARS + extra), encoding="utf-8")
    tracemalloc.start()
    try:
        with pytest.raises(DataFileError) as caught:
            CSV_READERS[reader](path)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    message = _one_line_error(caught.value, path)
    # A quote opens a field that runs on; csv's own field limit may stop it first.
    assert "line 2 is longer than 65,536 characters" in message or (
        filler == '"' and "malformed CSV" in message
    )
    assert peak < 2 * 2**20


def test_lines_up_to_the_limit_are_read(tmp_path):
    path = tmp_path / "stream.csv"
    cell = "0." + "5" * (MAX_LINE_CHARS - 20)
    path.write_text(f"step,lhy,lhz,rhy,rhz\n0,{cell},0,0,0\n1,0,0,0,0\n")
    assert read_sensory_stream(path).shape == (2, 4)


@pytest.mark.parametrize("reader", ["read_sequences", "read_sensory_stream", "read_session"])
def test_readers_hold_about_the_file_size_in_memory(tmp_path, reader):
    rng = np.random.default_rng(0)
    n = 20_000
    path = tmp_path / "big_1.csv"
    if reader == "read_sequences":
        write_sequence(
            path, Sequence(rng.uniform(0, 1, (n, 4)), rng.uniform(-1, 1, (n, 8)), "wave")
        )
    elif reader == "read_sensory_stream":
        write_sensory_stream(path, rng.uniform(0, 1, (n, 4)))
    else:
        with SessionRecorder(path) as recorder:
            for t in range(n // 4):
                recorder.write(
                    StepRecord(
                        step=t,
                        time_s=0.4 * t,
                        observed=rng.uniform(0, 1, 4),
                        predicted=rng.uniform(0, 1, 4),
                        predicted_next=rng.uniform(0, 1, 4),
                        motor=rng.uniform(-1, 1, 8),
                        pb=rng.uniform(0, 1, 4),
                        prediction_error=0.01,
                        window_error=0.02,
                        held=False,
                        truth={"pattern": "wave"},
                    )
                )
    size = path.stat().st_size
    tracemalloc.start()
    try:
        CSV_READERS[reader](path)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    # Lists of dicts of strings took 11-15 times the file; parsed straight to float64, ~1-2.
    assert peak < 3 * size, (peak, size)


# --- 5. other readers and writers --------------------------------------------------------


@pytest.mark.parametrize("reader", ["read_sequences", "read_session"])
def test_duplicate_column_is_refused(tmp_path, reader):
    path = tmp_path / "dup.csv"
    header = ["step", "time_s", *SENSORY_NAMES, *MOTOR_NAMES, "lhy"]
    path.write_text(
        ",".join(header)
        + "\n"
        + ",".join(["0"] * len(header))
        + "\n"
        + ",".join(["1"] * len(header))
        + "\n"
    )
    with pytest.raises(DataFileError) as caught:
        CSV_READERS[reader](path)
    assert "'lhy'" in str(caught.value) or "lhy appears" in str(caught.value)
    assert "more than once" in _one_line_error(caught.value, path)


def test_unnamed_columns_may_repeat(tmp_path):
    path = tmp_path / "stream.csv"
    path.write_text("step,lhy,lhz,rhy,rhz,,\n0,0.1,0.2,0.3,0.4,,\n")
    assert read_sensory_stream(path).shape == (1, 4)


def _png_header(width, height):
    import struct
    import zlib

    def chunk(kind, data):
        return (
            struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
        )

    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
        + chunk(b"IDAT", zlib.compress(b"\0" * 64))
        + chunk(b"IEND", b"")
    )


def test_image_claiming_too_many_pixels(tmp_path):
    (tmp_path / "f1.png").write_bytes(_png_header(40_000, 40_000))
    with ImageFolderSource(tmp_path) as source, pytest.raises(DataFileError) as caught:
        source.read()
    message = _one_line_error(caught.value, tmp_path / "f1.png")
    assert "its header claims more than 2^30 pixels" in message


def test_train_out_is_checked_before_training(tmp_path, data_dir, capsys, monkeypatch):
    import rnnpb.model

    def no_training(*args, **kwargs):
        raise AssertionError("training started")

    monkeypatch.setattr(rnnpb.model, "train", no_training)
    folder = tmp_path / "a-folder"
    folder.mkdir()
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    for out, words in [(folder, "is a directory"), (blocker / "m.npz", "is not a directory")]:
        code = main(["train", "--data", str(data_dir), "--out", str(out), "--no-progress"])
        err = capsys.readouterr().err
        assert code == 2 and err.startswith(f"rnnpb: error: {out}: ") and words in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a-file", "a-folder"]


def test_train_out_in_a_read_only_folder(tmp_path, data_dir, capsys):
    folder = tmp_path / "read-only"
    folder.mkdir()
    folder.chmod(0o500)
    try:
        if os.access(folder, os.W_OK):
            pytest.skip("running as a user who may write anywhere")
        code = main(["train", "--data", str(data_dir), "--out", str(folder / "m.npz")])
        err = capsys.readouterr().err
        assert code == 2 and "cannot write the model here: Permission denied" in err
    finally:
        folder.chmod(0o700)


def test_atomic_write_names_the_destination(tmp_path, monkeypatch, capsys, model):
    target = tmp_path / "model.npz"
    monkeypatch.setattr(
        os, "fsync", lambda fd: (_ for _ in ()).throw(OSError(28, "No space left on device"))
    )
    with pytest.raises(OSError) as caught:
        model.save(target)
    assert caught.value.filename == str(target) and caught.value.errno == 28
    monkeypatch.undo()
    folder = tmp_path / "folder"
    folder.mkdir()
    with pytest.raises(IsADirectoryError) as caught, atomic_write(folder) as handle:
        handle.write("x")
    assert caught.value.filename == str(folder)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["folder"]


@pytest.mark.parametrize("umask", [0o022, 0o002, 0o077])
def test_written_files_get_the_mode_the_umask_gives(tmp_path, umask):
    old = os.umask(umask)
    try:
        with atomic_write(tmp_path / "new.csv") as handle:
            handle.write("x")
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "new.csv").stat().st_mode) == 0o666 & ~umask


def test_replacing_a_file_keeps_its_mode(tmp_path):
    path = tmp_path / "kept.csv"
    path.write_text("old")
    path.chmod(0o640)
    with atomic_write(path) as handle:
        handle.write("new")
    assert path.read_text() == "new" and stat.S_IMODE(path.stat().st_mode) == 0o640
