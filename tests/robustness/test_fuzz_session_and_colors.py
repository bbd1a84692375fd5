"""Session recordings and colour files: hostile and cut-short files give a clear error naming the
file, or the documented result (a recording's unfinished last row is left out)."""

import json
import re

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rnnpb.errors import ConfigError, DataFileError
from rnnpb.interaction import SessionRecorder, read_session
from rnnpb.interaction.loop import StepRecord
from rnnpb.perception import ball_colors_from_json, load_ball_colors

FUZZ = settings(
    max_examples=60,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
N_ROWS = 12


def _record(step):
    rng = np.random.default_rng(step)
    observed = rng.uniform(0, 1, 4)
    if step % 5 == 3:
        observed[:2] = np.nan
    return StepRecord(
        step=step,
        time_s=0.4 * step,
        observed=observed,
        predicted=rng.uniform(0, 1, 4),
        predicted_next=rng.uniform(0, 1, 4),
        motor=rng.uniform(-1, 1, 8),
        pb=rng.uniform(0, 1, 4),
        prediction_error=0.01,
        window_error=0.02,
        held=False,
        truth={"pattern": "horizontal swing é"},
    )


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    path = tmp_path_factory.mktemp("session") / "session.csv"
    with SessionRecorder(path) as recorder:
        for step in range(N_ROWS):
            recorder.write(_record(step))
    return path.read_bytes()


def test_recording_round_trip(tmp_path, recording):
    path = tmp_path / "session.csv"
    path.write_bytes(recording)
    session = read_session(path)
    assert session["step"].tolist() == list(range(N_ROWS))
    assert np.isnan(session["lhy"][3]) and session["lost_left"][3] == 1
    assert session["truth_pattern"][0] == "horizontal swing é"


@FUZZ
@given(cut=st.integers(min_value=0, max_value=10_000))
def test_cut_anywhere_keeps_every_complete_row(tmp_path, recording, cut):
    cut = min(cut, len(recording))
    path = tmp_path / "session.csv"
    path.write_bytes(recording[:cut])
    complete_rows = max(recording[:cut].count(b"\n") - 1, 0)
    try:
        session = read_session(path)
    except DataFileError as error:
        # Only a file cut inside its header has nothing to read.
        assert cut <= recording.index(b"\n") + 1, error
        assert str(error).startswith(str(path))
        return
    # Every complete row is read, exactly as written; the unfinished one is left out.
    assert session["step"].tolist() == list(range(complete_rows))
    full = read_session_bytes(tmp_path, recording)
    for name in ("lshp", "pb0", "time_s", "lost_left", "truth_pattern"):
        if name in session:
            np.testing.assert_array_equal(session[name], full[name][:complete_rows])


def read_session_bytes(tmp_path, data):
    path = tmp_path / "full.csv"
    path.write_bytes(data)
    return read_session(path)


@FUZZ
@given(data=st.binary(max_size=500))
def test_random_bytes(tmp_path, data):
    path = tmp_path / "session.csv"
    path.write_bytes(data)
    with pytest.raises(DataFileError) as caught:
        read_session(path)
    assert str(caught.value).startswith(str(path))


@FUZZ
@given(position=st.floats(0.05, 0.9), junk=st.sampled_from(["abc", "1,2", "\x00", '"', "é"]))
def test_damage_inside_the_file_is_reported_with_its_line(tmp_path, recording, position, junk):
    text = recording.decode("utf-8")
    lines = text.split("\r\n")
    line = 1 + int(position * (len(lines) - 2))
    fields = lines[line].split(",")
    fields[4] = junk
    lines[line] = ",".join(fields)
    path = tmp_path / "session.csv"
    path.write_text("\r\n".join(lines), encoding="utf-8", newline="")
    try:
        session = read_session(path)
    except DataFileError as error:
        # A stray quote runs on to the end of the file: csv reports the line where it ends.
        found = re.match(rf"{re.escape(str(path))}: line (\d+)", str(error))
        assert found and int(found.group(1)) >= line + 1, str(error)
    else:
        pytest.fail(f"damage {junk!r} on line {line + 1} went unnoticed: {session['lhz']}")


def test_bom_header_and_paths(tmp_path, recording):
    path = tmp_path / "session.csv"
    path.write_bytes(b"\xef\xbb\xbf" + recording)
    assert len(read_session(path)["step"]) == N_ROWS
    with pytest.raises(DataFileError, match="is a directory"):
        read_session(tmp_path)
    with pytest.raises(DataFileError, match="no such file"):
        read_session(tmp_path / "none.csv")
    path.write_text("step,lhy\n0,1\n")
    with pytest.raises(DataFileError, match="not a session recording: missing column"):
        read_session(path)


json_values = st.recursive(
    st.none() | st.booleans() | st.integers(-(10**30), 10**30) | st.floats() | st.text(max_size=6),
    lambda children: (
        st.lists(children, max_size=4)
        | st.dictionaries(
            st.sampled_from(
                ["format", "version", "left", "right", "hue", "saturation", "value", "name", "x"]
            ),
            children,
            max_size=5,
        )
    ),
    max_leaves=20,
)


@FUZZ
@given(data=json_values)
def test_random_colour_documents(data):
    try:
        colors = ball_colors_from_json(data, "colours.json")
    except ConfigError as error:
        assert str(error).startswith("colours.json")
    else:
        for ball in colors.balls:
            assert all(0 <= v <= 255 for v in (*ball.saturation, *ball.value))


@FUZZ
@given(data=st.binary(max_size=300))
def test_random_colour_files(tmp_path, data):
    path = tmp_path / "colours.json"
    path.write_bytes(data)
    with pytest.raises(ConfigError) as caught:
        load_ball_colors(path)
    assert str(caught.value).startswith(str(path))


@pytest.mark.parametrize(
    "content, message",
    [
        (b"[" * 50_000, "not valid JSON"),
        (b'{"left": {"hue": [' + b"9" * 5000 + b", 1]}}", "not valid JSON"),
        (b'{"left": {"hue": [0, 300]}, "right": {"hue": [1, 2]}}', "field 'left.hue'"),
    ],
)
def test_colour_file_errors(tmp_path, content, message):
    path = tmp_path / "colours.json"
    path.write_bytes(content)
    with pytest.raises(ConfigError) as caught:
        load_ball_colors(path)
    assert str(caught.value).startswith(str(path)) and message in str(caught.value)


def test_colour_file_with_bom_and_directory(tmp_path):
    path = tmp_path / "colours.json"
    document = {"left": {"hue": [100, 130]}, "right": {"hue": [170, 10]}}
    path.write_bytes(b"\xef\xbb\xbf" + json.dumps(document).encode())
    assert load_ball_colors(path).left.hue == (100, 130)
    with pytest.raises(ConfigError, match="no such colour file"):
        load_ball_colors(tmp_path)
