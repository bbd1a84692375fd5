"""The public configs: a user's few settings, the rest read from the learning preset."""

from __future__ import annotations

import dataclasses
import json
import pickle
import re

import numpy as np
import pytest

from rnnpb.cli import main
from rnnpb.errors import ConfigError
from rnnpb.interaction.episodes import TeachingConfig
from rnnpb.model import NetworkConfig, OnlineConfig, TrainConfig, TrainedModel
from rnnpb.model.consolidation import ConsolidationConfig
from rnnpb.model.io import learning_preset
from rnnpb.model.learning import preset_record
from rnnpb.model.parametric_bias import PBUpdateConfig
from rnnpb.model.recognition import RecognitionConfig
from rnnpb.models import SHIPPED_MODEL
from rnnpb.presets import load_preset
from rnnpb.sequences import write_sequence

from .synthetic import make_sequences

# What a user sets (docs/model.md, "Settings a user changes"). PBUpdateConfig is the record of
# a preset's coefficients of eqs. 1-2, which no public config takes from a user.
USER_SETTINGS = {
    NetworkConfig: ("sensory_size", "motor_size", "pb_size", "hidden_size", "context_size"),
    TrainConfig: ("iterations", "input_noise", "seed", "checkpoint_every"),
    OnlineConfig: ("window", "iterations", "safety_guard"),
    RecognitionConfig: (),
    ConsolidationConfig: ("method", "purpose", "train"),
    TeachingConfig: ("confirm_cycles", "tolerance_steps", "max_run_steps", "plane_x"),
}
MOST_USER_SETTINGS = 20
"""What the model-facing configs may take from a user, all together."""


def _settings(cls) -> tuple[str, ...]:
    return tuple(f.name for f in dataclasses.fields(cls) if f.init and not f.name.startswith("_"))


def test_the_configs_take_only_the_settings_a_user_changes():
    assert {cls: _settings(cls) for cls in USER_SETTINGS} == USER_SETTINGS
    taken = [f"{cls.__name__}.{name}" for cls in USER_SETTINGS for name in _settings(cls)]
    assert len(taken) <= MOST_USER_SETTINGS, (
        f"{len(taken)} user settings, more than {MOST_USER_SETTINGS}: {', '.join(taken)}"
    )
    # The constructor takes no tuned value: research changes it one way, with_tuning.
    with pytest.raises(TypeError):
        OnlineConfig(surprise_gate=0.0)  # type: ignore[call-arg]
    with pytest.raises(ValueError, match="init=False"):
        dataclasses.replace(OnlineConfig(), surprise_gate=0.0)


@pytest.mark.parametrize(
    ("config", "preset", "section"),
    [
        (TrainConfig.paper(), "paper", "learning"),
        (TrainConfig.fast(), "fast", "learning"),
        (OnlineConfig(), "paper", "online"),
        (OnlineConfig.ungated(), "fast", "online"),
        (OnlineConfig.paper(), "paper", "paper_online"),
        (RecognitionConfig(), "paper", "recognition"),
        (RecognitionConfig.fast(), "fast", "recognition"),
        (RecognitionConfig.untaught(), "paper", "recognition_untaught"),
        (RecognitionConfig.untaught(fast=True), "fast", "recognition_untaught"),
    ],
)
def test_the_named_configs_are_their_preset_sections(config, preset, section):
    values = load_preset(preset)
    record = config.to_dict()
    for key, value in values.section(section).items():
        assert record[key] == value, key
        # The kinds the compiled code was written for: a float stays a float.
        assert type(getattr(config, key)) is type(value), key
    if f"{section}.pb" in values.sections:
        assert record["pb"] == dict(values.section(f"{section}.pb"))
    assert config.tuning.preset == preset


def test_ungated_is_the_default_without_the_gate():
    assert OnlineConfig.ungated() == OnlineConfig().with_tuning(surprise_gate=0.0)
    assert OnlineConfig().surprise_gate > 0


def test_with_tuning_changes_only_what_it_names_and_keeps_the_settings():
    config = OnlineConfig.ungated(window=20)
    changed = config.with_tuning(phase_restarts=0, pb={"k_nb": 0.1})
    assert (changed.window, changed.phase_restarts, changed.pb.k_nb) == (20, 0, 0.1)
    assert changed.pb.integration_length == config.pb.integration_length
    assert changed.surprise_gate == 0.0
    # A setting changed by replace keeps the tuned values it had.
    assert dataclasses.replace(config, window=12).surprise_gate == 0.0
    with pytest.raises(ConfigError, match="no tuned setting 'surprise_gat'") as error:
        config.with_tuning(surprise_gat=0.0)
    assert "\n" not in str(error.value)
    with pytest.raises(ConfigError, match="gate_floor"):
        config.with_tuning(gate_floor=0.0)


@pytest.mark.parametrize(
    "config",
    [
        TrainConfig.fast(iterations=7).with_tuning(learning_rate=0.02),
        OnlineConfig.paper(window=12),
        RecognitionConfig.fast().with_tuning(switch_steps=2),
    ],
)
def test_a_config_round_trips_through_its_record_and_pickle(config):
    assert type(config).from_dict(json.loads(json.dumps(config.to_dict()))) == config
    copy = pickle.loads(pickle.dumps(config))
    assert copy == config and copy.tuning == config.tuning and hash(copy) == hash(config)


def test_a_consolidation_s_research_choices_change_only_by_with_tuning():
    with pytest.raises(TypeError):
        ConsolidationConfig(hold_old_pb="all")  # type: ignore[call-arg]
    config = ConsolidationConfig("replay", train=TrainConfig.fast(iterations=7))
    assert config.hold_old_pb is None  # the model's policy's, once resolved
    held = config.with_tuning(hold_old_pb="all", rehearsal_steps=40)
    assert (held.method, held.train, held.hold_old_pb, held.rehearsal_steps) == (
        "replay",
        config.train,
        "all",
        40,
    )
    assert held != config and held.with_tuning(hold_old_pb=None, rehearsal_steps=None) == config
    # A setting changed by replace keeps the choices; a worker process gets the same config.
    assert dataclasses.replace(held, method="rehearsal").hold_old_pb == "all"
    copy = pickle.loads(pickle.dumps(held))
    assert copy == held and hash(copy) == hash(held)
    assert dataclasses.asdict(copy)["hold_old_pb"] == "all"
    with pytest.raises(ConfigError, match="no tuned setting 'hold_old_pbs'"):
        config.with_tuning(hold_old_pbs="all")
    with pytest.raises(ConfigError, match="rehearsal_steps must be >= 2"):
        config.with_tuning(rehearsal_steps=1)


def test_a_recorded_learning_reads_back_as_the_preset_its_optimizer_implies():
    assert TrainConfig.from_dict(TrainConfig.fast().to_dict()).preset == "fast"
    assert TrainConfig.from_dict(TrainConfig.paper().to_dict()).preset == "paper"


def test_a_model_records_its_preset_and_what_its_learning_changed():
    fast = load_preset("fast")
    assert preset_record(TrainConfig.fast(iterations=5, seed=3)) == {
        "name": "fast",
        "version": fast.version,
        "fingerprint": fast.fingerprint,
    }
    changed = TrainConfig.paper().with_tuning(learning_rate=0.5, pb={"k_nb": 0.0})
    assert preset_record(changed)["changed"] == ["learning_rate", "pb"]


def test_the_on_line_choice_follows_the_recorded_preset(trained):
    assert learning_preset(trained.meta) == ("fast", load_preset("fast").version)
    # The preset recorded decides, not the optimizer...
    recorded = dataclasses.replace(trained, meta={**trained.meta, "preset": {"name": "paper"}})
    choice = OnlineConfig.for_model(recorded)
    assert (choice.name, choice.config, choice.recognition) == (
        "default",
        OnlineConfig(),
        RecognitionConfig(),
    )
    # ...and a file from before presets were recorded is read by its optimizer, as before.
    old = dataclasses.replace(trained, meta={"train_config": trained.meta["train_config"]})
    assert learning_preset(old.meta) == ("fast", None)
    assert OnlineConfig.for_model(old).config == OnlineConfig.ungated()
    untaught = dataclasses.replace(old, taught_sensory=None)
    assert OnlineConfig.for_model(untaught).recognition == RecognitionConfig.untaught(fast=True)
    assert learning_preset({"preset": {"name": "slow"}, "train_config": {}}) == ("paper", None)
    assert learning_preset({"preset": "fast"}) is None


def test_the_shipped_model_chooses_as_it_always_has():
    model = TrainedModel.load(SHIPPED_MODEL)
    choice = OnlineConfig.for_model(model)
    assert (choice.name, choice.config, choice.recognition) == (
        "ungated",
        OnlineConfig.ungated(),
        RecognitionConfig.fast(),
    )


def test_pb_coefficients_have_no_defaults_of_their_own():
    with pytest.raises(TypeError):
        PBUpdateConfig()  # type: ignore[call-arg]


@pytest.fixture()
def data_dir(tmp_path):
    directory = tmp_path / "data"
    for i, seq in enumerate(make_sequences(n_steps=20)):
        write_sequence(directory / f"p{seq.pattern}_{i % 2 + 1}.csv", seq)
    return directory


def test_train_takes_a_config_file_and_info_shows_the_preset(
    data_dir, tmp_path, capsys, monkeypatch
):
    monkeypatch.setattr("rnnpb.robot.JOINT_LIMITS", np.array([[-2.0, 2.0]] * 8))
    research = tmp_path / "research.toml"
    research.write_text("[learning]\nlearning_rate = 0.02\n[learning.pb]\nk_nb = 0\n")
    model_path = tmp_path / "model.npz"
    # Made-up joint angles, not robot postures: the safety check would refuse them.
    args = ["train", "--data", str(data_dir), "--out", str(model_path), "--preset", "fast"]
    args.append("--allow-unsafe")
    assert main([*args, "--iterations", "20", "--no-progress", "--config", str(research)]) == 0
    model = TrainedModel.load(model_path)
    assert model.meta["train_config"]["learning_rate"] == 0.02
    assert model.meta["train_config"]["pb"]["k_nb"] == 0.0
    fast = load_preset("fast")
    assert model.meta["preset"] == {
        "name": "fast",
        "version": fast.version,
        "fingerprint": fast.fingerprint,
        "changed": ["learning_rate", "pb"],
    }
    capsys.readouterr()
    assert main(["info", str(model_path)]) == 0
    shown = f"learning preset: fast, version {fast.version}, with other learning_rate, pb\n"
    assert shown in capsys.readouterr().out


_NOW = {name: load_preset(name).version for name in ("paper", "fast")}


@pytest.mark.parametrize(
    ("recorded", "shown"),
    [
        # Learned before the fingerprints were recorded: version 1, whose values changed.
        (
            {"name": "fast", "version": 1},
            f"fast, version 1 (the fast preset is at version {_NOW['fast']} now; version 1's "
            "values changed while it was current)",
        ),
        # Learned with version 1's first values, the fingerprint recorded.
        (
            {"name": "paper", "version": 1, "fingerprint": "27140656dee47093"},
            f"paper, version 1 (the paper preset is at version {_NOW['paper']} now; learned with "
            "earlier values of version 1)",
        ),
        (
            {"name": "paper", "version": 2, "fingerprint": "c9fc8abe565ee980"},
            f"paper, version 2 (the paper preset is at version {_NOW['paper']} now)",
        ),
        (
            {"name": "paper", "version": 2, "fingerprint": "0000000000000000"},
            f"paper, version 2 (the paper preset is at version {_NOW['paper']} now; values that "
            "version 2 never held (fingerprint 0000000000000000))",
        ),
    ],
)
def test_a_model_of_an_older_preset_version_loads_and_says_so(
    trained, tmp_path, capsys, recorded, shown
):
    path = tmp_path / "older.npz"
    dataclasses.replace(trained, meta={**trained.meta, "preset": recorded}).save(path)
    model = TrainedModel.load(path)
    assert model.learning_preset == (recorded["name"], recorded["version"])
    capsys.readouterr()
    assert main(["info", str(path)]) == 0
    assert f"learning preset: {shown}\n" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("[learning]\nlearning_rat = 0.02\n", "unknown setting 'learning_rat' in \\[learning\\]"),
        ("[online]\nwindow = 20\n", "\\[online\\] does not apply to rnnpb train"),
        ('[learning]\niterations = "many"\n', "\\[learning\\] iterations must be a int"),
    ],
)
def test_a_bad_config_file_is_one_line_naming_file_and_key(tmp_path, capsys, text, message):
    research = tmp_path / "research.toml"
    research.write_text(text)
    args = ["train", "--data", str(tmp_path / "none"), "--out", str(tmp_path / "m.npz")]
    assert main([*args, "--config", str(research)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(research) in err
    assert re.search(message, err), err


def test_interact_takes_a_config_file(tmp_path):
    research = tmp_path / "research.toml"
    research.write_text("[online]\nsurprise_gate = 0.02\n[recognition]\nswitch_steps = 3\n")
    out = tmp_path / "run"
    args = ["interact", "--model", str(SHIPPED_MODEL), "--source", "scenario:held:1"]
    assert main([*args, "--out", str(out), "--steps", "6", "--config", str(research)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["online"] == "ungated"
    assert summary["online_config"]["surprise_gate"] == 0.02
    assert summary["online_config"]["window"] == 30
    assert summary["recognition_config"]["switch_steps"] == 3
    assert summary["recognition_config"]["match_scale"] == RecognitionConfig.fast().match_scale


def test_a_config_file_gives_a_job_its_preset_with_the_file_s_values(tmp_path):
    from rnnpb.commands._config import read_config

    research = tmp_path / "research.toml"
    research.write_text("[consolidation]\ninput_noise = 0.02\n[teaching]\niterations = 10\n")
    checked = read_config(str(research), ("consolidation", "teaching"), "consolidate")
    assert checked is not None
    preset = checked.preset("fast")
    assert preset.section("consolidation")["input_noise"] == 0.02
    assert preset.section("teaching")["iterations"] == 10
    assert preset.section("consolidation")["iterations"] == 500  # the fast preset's own
    assert preset.evidence("teaching", "iterations").note == f"set by {research}"
    assert read_config(None, ("teaching",), "consolidate") is None
