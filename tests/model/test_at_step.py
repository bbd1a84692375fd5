"""Settings kept in seconds at a model's own step: a person's durations and the regression's
effort; the parts of a movement's cycle stay in steps."""

from __future__ import annotations

from dataclasses import replace

import pytest

from rnnpb.errors import ConfigError
from rnnpb.model import OnlineConfig
from rnnpb.model.online_config import suggested_online_config
from rnnpb.model.recognition import DURATIONS, RecognitionConfig


def test_a_persons_durations_are_kept_in_seconds_and_cycle_parts_in_steps():
    paper = RecognitionConfig.for_preset("paper")
    fine = paper.at_step(0.1)
    for name in DURATIONS:
        assert getattr(fine, name) == 4 * getattr(paper, name)
    # everything else is unchanged, and the paper's step changes nothing
    changed = {k for k, v in fine.tuning.items() if paper.tuning[k] != v}
    assert changed == set(DURATIONS)
    assert paper.at_step(0.4) is paper
    assert paper.at_step(1.6).still_steps == max(2, round(paper.still_steps / 4))
    with pytest.raises(ConfigError, match="dt"):
        paper.at_step(0.0)


def test_the_regressions_effort_is_kept_per_second():
    for config in (OnlineConfig(), OnlineConfig.ungated()):
        fine = config.at_step(0.1)
        assert fine.iterations == config.iterations // 4
        # the tuned values (the preset's gate, restarts, PB update) and the window stay
        assert fine.tuning == config.tuning and fine.window == config.window
        assert config.at_step(0.4) is config
    assert OnlineConfig().at_step(0.0001).iterations == 1
    with pytest.raises(ConfigError, match="dt"):
        OnlineConfig().at_step(-0.1)


def test_a_model_at_another_step_is_suggested_its_settings_at_that_step(set1_model):
    at_paper = suggested_online_config(set1_model)
    fine = suggested_online_config(replace(set1_model, meta={**set1_model.meta, "dt": 0.1}))
    assert at_paper.name == fine.name
    assert fine.config.iterations * 4 == at_paper.config.iterations
    assert fine.recognition.still_steps == 4 * at_paper.recognition.still_steps
