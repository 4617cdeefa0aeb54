"""What the aud2* trainers validate on: the kept weights are the best by the validation loss they log, and with
``validate_on="poses"`` that loss is the pose error over whole held-out segments (the representation decoded)."""
from __future__ import annotations

import numpy as np
import pytest
import torch

from evalsuite.generators.aud2repr2pose.training import generate, train_system


def _segments(rng: np.random.Generator, lengths: list[int]) -> tuple[list[np.ndarray], list[np.ndarray]]:
    speech = [rng.normal(size=(n, 26)).astype(np.float32) for n in lengths]
    mix = rng.normal(size=(26, 12))
    poses = [np.cumsum(s @ mix, axis=0) * 0.01 + rng.normal(size=(len(s), 12)) * 0.1 for s in speech]
    return speech, poses


@pytest.mark.parametrize("system", ["aud2repr2pose", "aud2motion"])
def test_validation_on_poses_scores_whole_segments_and_keeps_the_best(system):
    rng = np.random.default_rng(0)
    speech, poses = _segments(rng, [230, 260, 240])
    val_speech, val_poses = _segments(rng, [170, 135])   # 135: not a whole number of 100-frame chunks
    torch.set_num_threads(1)
    model = train_system(system, speech, poses, epochs=4, dae_epochs=2, code_dim=8, batch_size=4, seed=0,
                         val_speech=val_speech, val_poses=val_poses, validate_on="poses",
                         config={"width": 16})
    losses = [r["val_loss"] for r in model.history if "val_loss" in r]
    assert len(losses) == 4
    err = [model.pose_norm(generate(model, s)) - model.pose_norm(p) for s, p in zip(val_speech, val_poses)]
    kept = sum(float((e ** 2).sum()) for e in err) / sum(e.size for e in err)
    assert kept == pytest.approx(min(losses), rel=1e-4)


def test_validate_on_must_be_targets_or_poses():
    from evalsuite.generators import GeneratorError, find_generator
    from evalsuite.generators.registry import generator_class

    g = generator_class(find_generator("aud2motion").target)()
    g.configure({"validate_on": "codes"})
    with pytest.raises(GeneratorError, match="validate_on") as err:
        g._settings()
    assert err.value.field == "validate_on"
    with pytest.raises(ValueError, match="validate_on must be 'targets' or 'poses'"):
        train_system("aud2pose", [np.zeros((120, 26), np.float32)], [np.zeros((120, 3))], validate_on="codes")


@pytest.mark.parametrize("validate_on", ["poses", "targets"])
def test_autoencoder_of_poses_and_velocities_codes_both_and_decodes_poses(validate_on):
    """``dae_inputs=poses+velocities`` (the paper's Japanese-data setup): the autoencoder reconstructs each pose
    with its frame difference; the speech network's targets are those codes; generation keeps only the poses."""
    rng = np.random.default_rng(1)
    speech, poses = _segments(rng, [230, 260, 240])
    val_speech, val_poses = _segments(rng, [170])
    torch.set_num_threads(1)
    model = train_system("aud2repr2pose", speech, poses, epochs=3, dae_epochs=2, code_dim=8, batch_size=4,
                         seed=0, val_speech=val_speech, val_poses=val_poses, validate_on=validate_on,
                         dae_velocities=True, config={"width": 16})
    assert model.dae is not None and model.dae.encoder.in_features == 24 and model.dae.pose_dim == 12
    assert generate(model, val_speech[0]).shape == (170, 12)
    # the code carries the motion: a pose held still and the same pose moving apart encode differently
    still = torch.zeros(2, 24)
    moving = still.clone()
    moving[:, 12:] = 1.0
    assert not torch.allclose(model.dae.encode(still), model.dae.encode(moving))


def test_past_frames_give_each_frame_the_speech_before_it_and_nothing_after():
    """``past_frames=k`` (sequence form): frame t's input holds, for each feature, its values at frames t-k+1 .. t
    (zeros before the first frame); an output never depends on speech after its frame (the model stays causal)."""
    from evalsuite.generators.aud2repr2pose.net import SpeechNet, SpeechNetConfig, with_past_frames

    x = torch.arange(2 * 5 * 2, dtype=torch.float32).reshape(2, 5, 2)
    stacked = with_past_frames(x, 3)
    assert stacked.shape == (2, 5, 6)
    assert stacked[1, 4].tolist() == [x[1, 2, 0], x[1, 3, 0], x[1, 4, 0], x[1, 2, 1], x[1, 3, 1], x[1, 4, 1]]
    assert stacked[0, 0].tolist() == [0, 0, x[0, 0, 0], 0, 0, x[0, 0, 1]]
    assert torch.equal(with_past_frames(x, 1), x)
    torch.manual_seed(0)
    net = SpeechNet(SpeechNetConfig(26, 12, width=16, bidirectional=False, form="sequence", velocity_target=False,
                                    past_frames=10)).eval()
    assert net.dense[0].linear.in_features == 260
    speech = torch.randn(2, 60, 26)
    later = speech.clone()
    later[:, 40:] += 1.0
    assert torch.equal(net(speech)[:, :40], net(later)[:, :40])
    assert not torch.equal(net(speech)[:, 40:], net(later)[:, 40:])
    with pytest.raises(ValueError, match="1 in the windowed form"):
        SpeechNet(SpeechNetConfig(26, 12, form="windowed", past_frames=5))
