"""The Gesticulator re-implementation's network and schedule, on random tensors (no corpus, no training)."""
from __future__ import annotations

import math

import pytest
import torch

from evalsuite.generators.gesticulator.net import GesticulatorConfig, GesticulatorNet
from evalsuite.generators.gesticulator.training import budgeted_schedule


def _net(**changes):
    torch.manual_seed(0)
    config = GesticulatorConfig(audio_dim=6, text_dim=4, pose_dim=9, frame_dim=8, hidden=(16, 12), film_dim=24,
                                **changes)
    return GesticulatorNet(config).eval()


@pytest.mark.parametrize("changes", [{}, {"film": False}, {"autoregressive": False}, {"past": 3, "future": 5},
                                     {"film_identity": True, "frame_layers": 2}])
def test_speech_codes_of_a_sequence_equal_one_window_at_a_time(changes):
    net = _net(**changes)
    c = net.config
    speech = torch.randn(2, c.window + 7, 10)
    prev = torch.randn(2, c.n_prev_poses, 9)
    codes = net.speech_codes(speech)
    assert codes.shape == (2, 8, 12)
    with torch.no_grad():
        for k in range(8):
            one = net(speech[:, k:k + c.window], prev if c.autoregressive else None)
            torch.testing.assert_close(net.decode(codes[:, k], prev if c.autoregressive else None), one)


def test_the_original_codes_film_is_the_identity_until_trained():
    """film_identity: x * (1 + alpha) + beta from a zero-initialised layer, so at the start the previous poses do
    not change the output; the paper's form (x * alpha + beta from a random encoder) scales the speech code."""
    net = _net(film_identity=True)
    codes = torch.randn(5, 12)
    out = net.decode(codes, torch.randn(5, net.config.n_prev_poses, 9))
    torch.testing.assert_close(out, net.decode(codes, torch.zeros(5, net.config.n_prev_poses, 9)))
    torch.testing.assert_close(out, net.output(codes))
    paper = _net()
    assert not torch.allclose(paper.decode(codes, torch.zeros(5, 3, 9)), paper.output(codes))


def test_the_frame_encoder_has_one_or_two_layers():
    linear = [m for m in _net(frame_layers=2).frame_encoder if isinstance(m, torch.nn.Linear)]
    assert [(m.in_features, m.out_features) for m in linear] == [(10, 16), (16, 8)]
    with pytest.raises(ValueError, match="frame_layers must be 1 or 2"):
        _net(frame_layers=3)


def test_text_dropout_drops_only_the_text_features_and_only_in_training():
    net = _net(text_dropout=0.5, dropout=0.0, prev_pose_dropout=0.0)
    speech = torch.randn(3, net.config.window + 4, 10)
    audio_only = speech.clone()
    audio_only[..., 6:] = 0.0
    net.train()
    # with no text there is nothing to drop: two passes agree; with text they differ
    torch.testing.assert_close(net.speech_codes(audio_only), net.speech_codes(audio_only))
    assert not torch.allclose(net.speech_codes(speech), net.speech_codes(speech))
    net.eval()
    torch.testing.assert_close(net.speech_codes(speech), net.speech_codes(speech))
    torch.testing.assert_close(net.speech_codes(speech), _net(dropout=0.0).speech_codes(speech))


def test_too_short_a_sequence_and_a_missing_previous_pose_are_refused():
    net = _net()
    with pytest.raises(ValueError, match="fewer than the model's window"):
        net.speech_codes(torch.zeros(1, net.config.window - 1, 10))
    with pytest.raises(ValueError, match="needs the previous poses"):
        net(torch.zeros(1, net.config.window, 10))


def test_the_audio_only_ablation_ignores_the_text_features():
    net = _net(use_text=False)
    speech = torch.randn(1, net.config.window, 10)
    other_text = speech.clone()
    other_text[..., 6:] = torch.randn(1, net.config.window, 4)
    prev = torch.zeros(1, 3, 9)
    torch.testing.assert_close(net(speech, prev), net(other_text, prev))


def test_the_compressed_schedule_keeps_the_papers_stage_order():
    schedule = budgeted_schedule(40)
    stages = [schedule.stage(e) for e in range(schedule.epochs)]
    assert schedule.epochs == 40
    assert stages[:3] == [(False, 0)] * 3                      # pretraining without autoregression
    assert stages[3:6] == [(True, 16), (True, 8), (True, 4)]     # teacher forcing withdrawn
    assert set(stages[6:]) == {(True, 1)}                         # then free
    with pytest.raises(ValueError):
        budgeted_schedule(4)


def test_the_cosine_learning_rate_decays_from_the_rate_to_one_percent():
    from dataclasses import replace

    schedule = replace(budgeted_schedule(60), learning_rate=1e-3, lr_schedule="cosine")
    rates = [schedule.learning_rate_at(e) for e in range(schedule.epochs)]
    assert rates[0] == pytest.approx(1e-3) and rates[-1] == pytest.approx(1e-5)
    assert rates[30] == pytest.approx(1e-5 + (1e-3 - 1e-5) * 0.5 * (1 + math.cos(math.pi * 30 / 59)))
    assert all(a > b for a, b in zip(rates, rates[1:]))          # strictly decreasing
    constant = replace(schedule, lr_schedule="constant")
    assert {constant.learning_rate_at(e) for e in range(60)} == {1e-3}
    with pytest.raises(ValueError, match="lr_schedule"):
        replace(schedule, lr_schedule="step").learning_rate_at(1)


def test_the_loss_is_pose_mse_plus_alpha_times_velocity_mse():
    from evalsuite.generators.gesticulator.training import _loss, velocity_weight

    pred = torch.zeros(1, 3, 1)
    target = torch.tensor([[[0.0], [1.0], [3.0]]])  # pose MSE 10/3; velocities 1, 2: velocity MSE 5/2
    assert velocity_weight == 0.6  # the paper's alpha, equation (2)
    assert float(_loss(pred, target)) == pytest.approx(10 / 3 + 0.6 * 5 / 2)
    assert float(_loss(pred, target, 0.0)) == pytest.approx(10 / 3)  # the "no velocity penalty" ablation
