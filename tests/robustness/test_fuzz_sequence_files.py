"""Sequence CSVs and sensory streams: hostile files give a DataFileError naming the file, or a
documented result — never another exception from inside the reader."""

import math
import string

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from rnnpb.errors import DataFileError
from rnnpb.sequences import (
    Sequence,
    read_sensory_stream,
    read_sequence_files,
    read_sequences,
    write_sensory_stream,
    write_sequence,
)
from rnnpb.vectors import MOTOR_NAMES, SENSORY_NAMES

SEQUENCE_COLUMNS = ["step", *SENSORY_NAMES, *MOTOR_NAMES]
STREAM_COLUMNS = ["step", *SENSORY_NAMES]
FUZZ = settings(
    max_examples=60,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)

cells = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(min_value=-(10**400), max_value=10**400).map(str),
    st.sampled_from(
        [
            "",
            " ",
            "nan",
            "inf",
            "-inf",
            "1e999",
            "-1e999",
            "0x10",
            "1_0",
            "١٢",
            "½",
            "\u00a0",
            "0.5\u200b",
            "true",
            '"',
            "\x00",
            "NaN",
            "Infinity",
        ]
    ),
    st.text(max_size=8),
)


def _expect_clear_error(path, call):
    """Either the call succeeds or it raises DataFileError whose one-line message names path."""
    try:
        return call(path)
    except DataFileError as error:
        message = str(error)
        assert message.startswith(str(path)), message
        assert "\n" not in message.strip() or "line" in message
        return None


def _grid_text(draw, columns_from):
    header = draw(
        st.one_of(
            st.just(list(columns_from)),
            st.permutations(list(columns_from)),
            st.lists(st.sampled_from([*columns_from, "pattern", "extra", ""]), max_size=16),
            st.lists(st.text(max_size=6), max_size=6),
        )
    )
    rows = draw(
        st.lists(
            st.lists(cells, min_size=max(0, len(header) - 1), max_size=len(header) + 1), max_size=6
        )
    )
    newline = draw(st.sampled_from(["\n", "\r\n", "\r"]))
    bom = draw(st.sampled_from(["", "\ufeff"]))
    blank = draw(st.sampled_from(["", newline]))
    lines = [",".join(header)] + [",".join(row) for row in rows]
    return bom + (newline + blank).join(lines) + newline


@st.composite
def sequence_grids(draw):
    return _grid_text(draw, SEQUENCE_COLUMNS)


@st.composite
def stream_grids(draw):
    return _grid_text(draw, STREAM_COLUMNS)


@FUZZ
@given(data=st.binary(max_size=400))
def test_random_bytes(tmp_path, data):
    path = tmp_path / "seq.csv"
    path.write_bytes(data)
    for reader in (read_sequences, read_sensory_stream):
        _expect_clear_error(path, reader)


@FUZZ
@given(text=st.text(max_size=300))
def test_random_text(tmp_path, text):
    path = tmp_path / "seq.csv"
    path.write_text(text, encoding="utf-8")
    for reader in (read_sequences, read_sensory_stream):
        _expect_clear_error(path, reader)


@FUZZ
@given(text=sequence_grids())
def test_random_sequence_grids(tmp_path, text):
    path = tmp_path / "wave_1.csv"
    path.write_text(text, encoding="utf-8", newline="")
    sequences = _expect_clear_error(path, read_sequences)
    for sequence in sequences or []:
        # What is accepted is usable: finite numbers of the documented shape.
        assert isinstance(sequence, Sequence)
        assert sequence.sensory.shape[1] == 4 and sequence.motor.shape[1] == 8
        assert np.all(np.isfinite(sequence.sensory)) and np.all(np.isfinite(sequence.motor))


@FUZZ
@given(text=stream_grids())
@example(text='"0\n0.0\n')  # a quoted header cell holding a line break: message on one line
def test_random_stream_grids(tmp_path, text):
    path = tmp_path / "stream.csv"
    path.write_text(text, encoding="utf-8", newline="")
    values = _expect_clear_error(path, read_sensory_stream)
    if values is not None:
        # Not seen is NaN and nothing else: no infinities reach the interaction loop.
        assert values.ndim == 2 and values.shape[1] == 4 and len(values) >= 1
        assert not np.any(np.isinf(values))


@pytest.fixture()
def good_sequence_text(tmp_path):
    rng = np.random.default_rng(0)
    sequence = Sequence(rng.uniform(0, 1, (6, 4)), rng.uniform(-1, 1, (6, 8)), "wave")
    path = tmp_path / "good.csv"
    write_sequence(path, sequence)
    return path.read_bytes()


@FUZZ
@given(cut=st.integers(min_value=0, max_value=2000))
def test_truncated_sequence_file(tmp_path, good_sequence_text, cut):
    path = tmp_path / "wave_1.csv"
    path.write_bytes(good_sequence_text[:cut])
    sequences = _expect_clear_error(path, read_sequences)
    if sequences is not None:
        # A cut at a row boundary, or inside the last row's final field, still reads.
        assert sequences[0].n_steps >= 2


def test_bom_crlf_and_blank_lines_are_accepted(tmp_path):
    rows = ["step,lhy,lhz,rhy,rhz", "0,0.1,0.2,0.3,0.4", "", "1,0.5,,0.7,nan", ""]
    path = tmp_path / "stream.csv"
    path.write_bytes(("\ufeff" + "\r\n".join(rows) + "\r\n").encode("utf-8"))
    values = read_sensory_stream(path)
    assert values.shape == (2, 4)
    np.testing.assert_allclose(values[0], [0.1, 0.2, 0.3, 0.4])
    assert values[1, 0] == 0.5 and math.isnan(values[1, 1]) and math.isnan(values[1, 3])


def test_infinite_sensory_value_means_not_seen(tmp_path):
    path = tmp_path / "stream.csv"
    path.write_text("step,lhy,lhz,rhy,rhz\n0,inf,0.2,-inf,1e999\n1,0.1,0.2,0.3,0.4\n")
    values = read_sensory_stream(path)
    assert np.isnan(values[0, [0, 2, 3]]).all() and values[0, 1] == 0.2
    np.testing.assert_allclose(values[1], [0.1, 0.2, 0.3, 0.4])
    # The writer then writes them as empty cells, like any hand not seen.
    write_sensory_stream(tmp_path / "again.csv", values)
    assert (tmp_path / "again.csv").read_text().splitlines()[1] == "0,,0.200000,,"


def test_values_outside_the_view_plane_are_kept(tmp_path):
    path = tmp_path / "stream.csv"
    path.write_text("step,lhy,lhz,rhy,rhz\n0,-3,1e30,2,0.5\n")
    np.testing.assert_array_equal(read_sensory_stream(path), [[-3, 1e30, 2, 0.5]])


@pytest.mark.parametrize(
    "text, message",
    [
        ("step,lhy,lhz,rhy,rhz\n0,0.1,0.2,0.3\n", "line 2: expected 5 fields"),
        ("step,lhy,lhz,rhy,rhz\n0,0.1,0.2,0.3,0.4,9\n", "line 2: expected 5 fields"),
        ("step,lhy,lhz,rhy,rhz\n0,0.1,abc,0.3,0.4\n", "column 'lhz': 'abc' is not a number"),
        ("step,lhy,lhz\n0,0.1,0.2\n", "missing column(s) rhy, rhz"),
        ("step,lhy,lhz,rhy,rhz\n", "has a header but no rows"),
        ("", "empty file"),
        ("step,lhy,lhz,rhy,rhz\n1e308,0,0,0,0\n-1e308,0,0,0,0\n", "'step' must increase"),
        ('step,lhy,lhz,rhy,rhz\n0,"0.1\n', "expected 5 fields"),
    ],
)
def test_stream_errors_name_file_and_problem(tmp_path, text, message):
    path = tmp_path / "stream.csv"
    path.write_text(text)
    with pytest.raises(DataFileError) as caught:
        read_sensory_stream(path)
    assert str(caught.value).startswith(str(path)) and message in str(caught.value)


def test_short_row_with_pattern_column(tmp_path):
    header = ",".join([*SEQUENCE_COLUMNS, "pattern"])
    row = ",".join(["0", *["0.5"] * 12])  # the pattern field is missing
    path = tmp_path / "seq.csv"
    path.write_text(f"{header}\n{row},a\n{row}\n")
    with pytest.raises(DataFileError, match=r"line 3: expected 14 fields"):
        read_sequences(path)


def test_huge_field_and_binary_file(tmp_path):
    path = tmp_path / "seq.csv"
    path.write_text(",".join(SEQUENCE_COLUMNS) + "\n" + "9" * 200_000 + "\n")
    with pytest.raises(DataFileError, match="line 2 is longer than 65,536 characters"):
        read_sequences(path)
    path.write_bytes(b"\x89PNG\r\n\x1a\n\xff\xfe\x00")
    with pytest.raises(DataFileError, match="cannot decode as UTF-8"):
        read_sequences(path)


def test_unreadable_and_directory_paths(tmp_path):
    with pytest.raises(DataFileError, match="is a directory"):
        read_sequences(tmp_path)
    with pytest.raises(DataFileError, match="holds no .csv files"):
        read_sequence_files([tmp_path])
    with pytest.raises(DataFileError, match="no such file"):
        read_sensory_stream(tmp_path / "missing.csv")
    path = tmp_path / "locked.csv"
    path.write_text("step,lhy,lhz,rhy,rhz\n0,0,0,0,0\n")
    path.chmod(0)
    try:
        if not _readable(path):
            with pytest.raises(DataFileError, match="cannot read"):
                read_sensory_stream(path)
    finally:
        path.chmod(0o600)


def _readable(path):
    try:
        path.open("rb").close()
    except PermissionError:
        return False
    return True


@settings(max_examples=30, deadline=None, database=None)
@given(name=st.text(alphabet=string.ascii_letters + "é中", min_size=1, max_size=6))
def test_unicode_pattern_names_round_trip(tmp_path_factory, name):
    path = tmp_path_factory.mktemp("u") / "seq.csv"
    rng = np.random.default_rng(1)
    write_sequence(path, Sequence(rng.uniform(0, 1, (3, 4)), rng.uniform(-1, 1, (3, 8)), name))
    (sequence,) = read_sequences(path)
    assert sequence.pattern == name.strip() and sequence.n_steps == 3
