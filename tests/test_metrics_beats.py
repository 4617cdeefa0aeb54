"""Beat alignment: score oracles, spectral-flux onsets of a click track, motion beats of a known motion."""
import numpy as np
import pytest
from scipy.io import wavfile

from evalsuite.errors import InputError
from evalsuite.metrics import audio_onsets, beat_alignment, beat_alignment_score, motion_beats, read_wav


def test_score_is_one_for_coincident_beats_and_follows_the_gaussian_kernel():
    beats = np.array([0.5, 1.0, 2.25])
    assert beat_alignment_score(beats, beats, 0.1) == 1.0
    assert beat_alignment_score([1.0], [1.1], 0.1) == pytest.approx(np.exp(-0.5))
    both = beat_alignment([1.0, 2.0], [1.0], sigma=0.2)
    assert both["a2m"] == pytest.approx((1 + np.exp(-1 / 0.08)) / 2)
    assert both["m2a"] == 1.0
    assert beat_alignment_score([], [1.0]) != beat_alignment_score([], [1.0])   # NaN: no source beat
    assert beat_alignment_score([1.0], []) == 0.0
    with pytest.raises(InputError):
        beat_alignment_score([1.0], [1.0], sigma=0)


def _click_track(times, sr=16000, seconds=4.0, seed=0):
    rng = np.random.default_rng(seed)
    x = 0.001 * rng.normal(size=int(sr * seconds))
    for t in times:
        i = int(t * sr)
        x[i:i + 200] += np.hanning(200) * rng.normal(size=200) * 0.8
    return x


def test_spectral_flux_finds_clicks(tmp_path):
    clicks = [0.5, 1.25, 2.0, 2.6, 3.3]
    sig = _click_track(clicks)
    path = tmp_path / "clicks.wav"
    wavfile.write(path, 16000, (sig * 32767).astype(np.int16))
    data, sr = read_wav(path)
    assert sr == 16000
    onsets = audio_onsets(data, sr)
    assert len(onsets) == len(clicks)
    np.testing.assert_allclose(onsets, clicks, atol=0.03)


def test_read_wav_rejects_garbage(tmp_path):
    bad = tmp_path / "bad.wav"
    bad.write_bytes(b"not a wav")
    with pytest.raises(InputError):
        read_wav(bad)


def test_motion_beats_are_the_speed_minima_and_align_with_matching_audio():
    fps = 30.0
    t = np.arange(int(4 * fps)) / fps
    # x = sin(2 pi f t): speed |cos| is zero at t = (k + 1/2) / (2 f)
    f = 0.75
    pos = np.zeros((len(t), 1, 3))
    pos[:, 0, 0] = 20 * np.sin(2 * np.pi * f * t)
    beats = motion_beats(pos, fps)
    expected = (np.arange(6) + 0.5) / (2 * f)
    expected = expected[(expected > 0.1) & (expected < t[-1] - 0.1)]
    np.testing.assert_allclose(beats, expected, atol=1.0 / fps)
    scores = beat_alignment(expected, beats, sigma=0.1)
    assert scores["a2m"] > 0.95
    assert scores["m2a"] > 0.95
    assert len(motion_beats(np.zeros((30, 2, 3)), fps)) == 0   # no motion, no beats
