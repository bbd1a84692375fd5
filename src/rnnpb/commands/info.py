"""rnnpb info: what a model file holds."""

from __future__ import annotations

import argparse
from typing import Any

NAME = "info"
HELP = "show what a model holds: patterns and PBs, sizes, learning, error, history"
DESCRIPTION = """\
Show what a model file holds: its learned patterns and their PBs, the network's sizes, the
learning preset it was learned with (paper or fast) and that preset's version, the step time
it was learned at, the training config, the on-line regression that suits it, the training
error, and the model's history (which patterns were learned when, by which method, from which
model).

Example:
  rnnpb info results/demo/models/set1.npz
"""

# Settings that do not change what is learned, left out when a config is matched to a preset.
_RUN_SETTINGS = ("iterations", "seed", "chunk_iterations", "checkpoint_every")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("model", metavar="MODEL", help="a model file (.npz)")


def preset_of(train_config: dict[str, Any] | None) -> str:
    """``paper``, ``fast`` or ``custom``: the preset the recorded training config is (its
    iterations and seed aside), ``unknown`` when none is recorded."""
    from rnnpb.model import TrainConfig

    if not isinstance(train_config, dict):
        return "unknown"
    from rnnpb.errors import ConfigError

    try:
        recorded = TrainConfig.from_dict(train_config).to_dict()
    except (ConfigError, TypeError, ValueError, KeyError):
        return "unknown"
    for name, preset in (("paper", TrainConfig.paper()), ("fast", TrainConfig.fast())):
        wanted = preset.to_dict()
        if all(recorded[k] == wanted[k] for k in wanted if k not in _RUN_SETTINGS):
            return name
    return "custom"


def recorded_preset(meta: dict[str, Any]) -> str:
    """The learning preset and version a model records (``meta["preset"]``), with the
    values its learning changed from the preset's; for a file from before presets were
    recorded, the preset its recorded optimizer implies."""
    from rnnpb.model.io import learning_preset

    learned = learning_preset(meta)
    if learned is None:
        return "not recorded"
    name, version = learned
    if version is None and isinstance(meta.get("preset"), dict):
        return f"{name} (its version not recorded)"
    if version is None:
        return f"{name} (by its optimizer; the file records no preset version)"
    changed = meta["preset"].get("changed")
    text = f"{name}, version {version}"
    if isinstance(changed, list) and changed:
        text += f", with other {', '.join(str(key) for key in changed)}"
    return text + _preset_version_note(name, version, meta["preset"].get("fingerprint"))


def _preset_version_note(name: str, version: int, fingerprint: object) -> str:
    """What a reader of an older model needs to know of the version it records: that the
    preset has moved on, or that the version's values changed while it was current."""
    from rnnpb.presets import load_preset, recorded_versions

    current = load_preset(name)
    recorded = recorded_versions().get((name, version))
    notes = []
    if version != current.version:
        notes.append(f"the {name} preset is at version {current.version} now")
    if recorded is not None and recorded.earlier:
        if fingerprint is None:
            notes.append(f"version {version}'s values changed while it was current")
        elif fingerprint != recorded.fingerprint and fingerprint in recorded.earlier:
            notes.append(f"learned with earlier values of version {version}")
    if isinstance(fingerprint, str) and recorded is not None:
        if fingerprint != recorded.fingerprint and fingerprint not in recorded.earlier:
            notes.append(f"values that version {version} never held (fingerprint {fingerprint})")
    return f" ({'; '.join(notes)})" if notes else ""


def suited_regression(model: Any) -> str:
    """The on-line regression ``rnnpb interact`` and ``serve`` run ``model`` with, and why
    (:func:`rnnpb.model.online_config.suggested_online_config`)."""
    from rnnpb.model.online_config import suggested_online_config

    choice = suggested_online_config(model)
    return f"{choice.name} ({choice.reason}; --online chooses another)"


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from rnnpb.model import TrainedModel
    from rnnpb.model.io import model_framing

    model = TrainedModel.load(args.model)
    net = model.network
    print(
        f"{args.model}: {len(model.patterns)} pattern(s), {len(model.sequence_patterns)} "
        f"training sequence(s); model fingerprint {model.fingerprint[:16]}"
    )
    print(
        f"network: {net.sensory_size} sensory + {net.motor_size} motor values, "
        f"{net.pb_size} PB, {net.hidden_size} hidden, {net.context_size} context units"
    )
    print("patterns (PB: the mean of its sequences' learned PBs):")
    counts = {p: model.sequence_patterns.count(p) for p in model.patterns}
    for name, pb in model.pattern_pb.items():
        print(f"  {name}: PB {np.array2string(pb, precision=3)} ({counts[name]} sequence(s))")
    config = model.meta.get("train_config")
    history = model.history
    # A grown model records its last step's learning; its preset is its first training's.
    preset = (
        f"{preset_of(history[0].train_config)} preset in its first training; last step"
        if len(history) > 1
        else f"{preset_of(config)} preset"
    )
    print(f"learning preset: {recorded_preset(model.meta)}")
    if isinstance(config, dict):
        print(
            f"learning: {preset}, {config.get('optimizer')}, "
            f"{config.get('iterations')} iterations, learning rate "
            f"{config.get('learning_rate')}, input noise {config.get('input_noise')}, "
            f"seed {config.get('seed')}"
        )
    else:
        print("learning: not recorded")
    recorded_dt = "dt" in model.meta
    print(
        f"step time: dt {model.dt:g} s, learned and played at"
        + ("" if recorded_dt else " (not recorded: the paper's, as every older model file)")
    )
    framing = model_framing(model.meta)
    print(
        f"framing: a person's body placed {framing:g} m from the robot's camera"
        + (
            ""
            if "framing_m" in model.meta
            else " (not recorded: the standard user's place, where the demonstrator stands)"
        )
    )
    print(f"on-line regression: {suited_regression(model)}")
    if model.taught_sensory is None:
        print(
            "recognition: by the network's evidence alone (the file keeps no hands as taught: "
            "saved before model format 3)"
        )
    else:
        print(
            "recognition: with the hands as taught "
            f"({model.taught_sensory.shape[0]} sequence(s), up to "
            f"{model.taught_sensory.shape[1]} steps each)"
        )
    training = model.meta.get("training")
    if isinstance(training, dict) and "mse_max" in training:
        print(
            f"training error (MSE over outputs): max {training['mse_max']:.2e}, mean "
            f"{training.get('mse_mean', float('nan')):.2e}; {training.get('seconds', 0):.1f} s"
        )
    print("history:")
    for k, entry in enumerate(model.history):
        when = entry.created or "time not recorded"
        source = (
            f" from {entry.parent} ({(entry.parent_fingerprint or '')[:16]})"
            if entry.parent or entry.parent_fingerprint
            else ""
        )
        print(
            f"  {k}. {entry.method}: learned {', '.join(entry.added)}{source}; "
            f"{entry.iterations} iterations, {entry.seconds:.1f} s; {when}"
        )
        if entry.details:
            shown = ", ".join(f"{key} {value}" for key, value in entry.details.items())
            print(f"     {shown}")
    return 0
