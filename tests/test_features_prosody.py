"""Pitch and energy tracks on signals whose answer is known: tones and a harmonic signal within 1 % of the
true F0, noise and silence unvoiced, RMS levels of sines and silence in dB; Praat's pitch through the praat extra."""
from __future__ import annotations

import numpy as np
import pytest

from evalsuite.features import extract
from evalsuite.features.prosody import frame_centres, rms_db, yin_pitch


def tone(f0: float, rate: int = 16000, seconds: float = 1.0, amp: float = 0.5) -> np.ndarray:
    t = np.arange(int(rate * seconds)) / rate
    return amp * np.sin(2 * np.pi * f0 * t + 0.3)


@pytest.mark.parametrize("rate", [16000, 44100])
@pytest.mark.parametrize("f0", [65.0, 100.0, 147.0, 220.0, 333.0, 480.0])
def test_pitch_of_pure_tones_is_within_one_percent(f0, rate):
    p = extract("pitch", (tone(f0, rate), rate), cache=False)[:, 0]
    inner = p[4:-4]                                   # frames whose window lies inside the signal
    assert np.all(inner > 0)
    assert np.max(np.abs(inner / f0 - 1)) < 0.01


def test_pitch_of_a_harmonic_signal_with_a_weak_fundamental_is_the_fundamental():
    rate, f0 = 22050, 118.0
    t = np.arange(rate) / rate
    x = 0.1 * np.sin(2 * np.pi * f0 * t) + sum(0.3 / k * np.sin(2 * np.pi * k * f0 * t + k) for k in range(2, 7))
    p = extract("pitch", (x, rate), cache=False)[4:-4, 0]
    assert np.all(p > 0)
    assert np.max(np.abs(p / f0 - 1)) < 0.01


def test_noise_and_silence_are_unvoiced():
    rate = 16000
    noise = np.random.default_rng(1).standard_normal(rate) * 0.3
    assert np.all(extract("pitch", (noise, rate), cache=False) == 0)
    assert np.all(extract("pitch", (np.zeros(rate), rate), cache=False) == 0)


def test_a_tone_after_silence_is_voiced_only_where_it_sounds():
    rate = 16000
    x = np.concatenate([np.zeros(rate // 2), tone(200.0, rate, 0.5)])
    p = yin_pitch(x, rate, frame_centres(1.0))
    assert np.all(p[:23] == 0) and np.all(np.abs(p[52:96] / 200 - 1) < 0.01)


def test_pitch_frames_are_centred_on_t_over_100():
    p = extract("pitch", (tone(150.0, 16000, 1.234), 16000), cache=False)
    assert p.shape == (124, 1)


def test_energy_of_known_signals_in_db_full_scale():      # whole periods in each 0.04 s window
    rate = 16000
    e = extract("energy", (tone(400.0, rate, amp=1.0), rate), cache=False, dtype=np.float64)[:, 0]
    np.testing.assert_allclose(e[3:-3], 10 * np.log10(0.5), atol=0.01)             # -3.01 dB
    e = extract("energy", (tone(400.0, rate, amp=0.25), rate), cache=False, dtype=np.float64)[:, 0]
    np.testing.assert_allclose(e[3:-3], 20 * np.log10(0.25 / np.sqrt(2)), atol=0.01)
    e = extract("energy", (np.full(rate, 0.5), rate), cache=False, dtype=np.float64)[:, 0]
    np.testing.assert_allclose(e[3:-3], 20 * np.log10(0.5), atol=1e-9)
    assert np.all(extract("energy", (np.zeros(rate), rate), cache=False) == -100)
    # half of the first window lies before the signal: zeros there count
    np.testing.assert_allclose(rms_db(np.full(rate, 0.5), rate, np.array([0.0]))[0], 20 * np.log10(0.5) - 3.0103,
                               atol=1e-3)


def test_int16_audio_is_scaled_to_full_scale():
    rate = 16000
    x = np.round(tone(300.0, rate, amp=0.5) * 32767).astype(np.int16)
    e = extract("energy", (x, rate), cache=False, dtype=np.float64)[3:-3, 0]
    np.testing.assert_allclose(e, 20 * np.log10(0.5 * 32767 / 32768 / np.sqrt(2)), atol=0.01)


def test_praat_pitch_of_a_tone():
    pytest.importorskip("parselmouth", reason="pitch_praat needs the praat extra: pip install 'evalsuite[praat]'")
    p = extract("pitch_praat", (tone(180.0, 16000), 16000), cache=False)[:, 0]
    voiced = p[p > 0]
    assert len(p) == 100 and len(voiced) > 80
    assert np.max(np.abs(voiced / 180 - 1)) < 0.01
