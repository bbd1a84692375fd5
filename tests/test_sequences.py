"""Sequence CSV files: round trip, and clear messages for malformed files."""

import numpy as np
import pytest

from rnnpb.demonstrator import pattern_dataset
from rnnpb.errors import DataFileError
from rnnpb.sequences import read_sequence_files, read_sequences, write_sequence

HEADER = "step,lhy,lhz,rhy,rhz,lshp,lshr,lshy,lelp,rshp,rshr,rshy,relp"


def row(step, value=0.5):
    return f"{step}," + ",".join([str(value)] * 12)


def write(path, lines):
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def test_round_trip_keeps_values_to_six_decimals(tmp_path):
    seq = pattern_dataset(seed=0, patterns=("3",), samples_per_pattern=1, n_steps=20)[0]
    write_sequence(tmp_path / "3_1.csv", seq)
    (back,) = read_sequences(tmp_path / "3_1.csv")
    assert back.pattern == "3"
    np.testing.assert_allclose(back.sensory, seq.sensory, atol=5e-7)
    np.testing.assert_allclose(back.motor, seq.motor, atol=5e-7)


def test_missing_column(tmp_path):
    path = write(tmp_path / "a.csv", [HEADER.replace(",relp", ""), "0" + ",0.5" * 11])
    with pytest.raises(DataFileError, match=r"a\.csv: missing column\(s\) relp"):
        read_sequences(path)


def test_non_number(tmp_path):
    path = write(tmp_path / "b.csv", [HEADER, row(0), row(1).replace("0.5", "abc", 1)])
    with pytest.raises(DataFileError, match=r"b\.csv: line 3, column 'lhy': 'abc' is not a num"):
        read_sequences(path)


def test_nan(tmp_path):
    path = write(tmp_path / "c.csv", [HEADER, row(0), row(1, "nan")])
    with pytest.raises(DataFileError, match=r"c\.csv: line 3, column 'lhy'.*not a finite"):
        read_sequences(path)


def test_wrong_step_order(tmp_path):
    path = write(tmp_path / "d.csv", [HEADER, row(0), row(2), row(1)])
    with pytest.raises(DataFileError, match=r"d\.csv: line 4: column 'step' must increase"):
        read_sequences(path)


def test_empty_file(tmp_path):
    path = tmp_path / "e.csv"
    path.write_text("", encoding="utf-8")
    with pytest.raises(DataFileError, match=r"e\.csv: empty file"):
        read_sequences(path)


def test_directory_without_csvs(tmp_path):
    (tmp_path / "notes.txt").write_text("x", encoding="utf-8")
    with pytest.raises(DataFileError, match="directory holds no .csv files"):
        read_sequence_files([tmp_path])
