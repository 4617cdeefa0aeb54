"""Speech-feature recipes against independent computations: MFCC against a direct python_speech_features call,
the log-mel against a direct numpy/scipy computation of the stated recipe written here, the Aud2Repr2Pose demo
recipe against the original's arrays; the frame-rate and length rules; precise errors."""
from __future__ import annotations

import pathlib

import numpy as np
import pytest
from scipy.io import wavfile
from scipy.signal import resample_poly

from evalsuite.errors import InputError
from evalsuite.features import extract, get_recipe, list_recipes
from evalsuite.features.base import fit_length, resample_frames

SHARED = pathlib.Path(__file__).resolve().parents[1].parent / "shared"
DEMO_WAV = SHARED / "weights" / "aud2repr2pose-demo" / "audio" / "audio3_20sec.wav"
GOLDEN = SHARED / "golden" / "aud2repr2pose-demo"


def speechlike(rate: int, seconds: float, seed: int = 0, channels: int = 2) -> np.ndarray:
    """int16 (N, C): a harmonic voice with a gliding pitch, pauses and a little noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(rate * seconds)) / rate
    f0 = 110 + 40 * np.sin(2 * np.pi * 0.7 * t)
    phase = 2 * np.pi * np.cumsum(f0) / rate
    voice = sum(np.sin(k * phase) / k for k in range(1, 8)) * (np.sin(2 * np.pi * 1.3 * t) > -0.3)
    x = 0.25 * voice + 0.01 * rng.standard_normal(len(t))
    chans = [x * (1.0 - 0.2 * c) for c in range(channels)]
    return np.clip(np.round(np.stack(chans, axis=1) * 32767), -32768, 32767).astype(np.int16)


@pytest.fixture(scope="module")
def wav44(tmp_path_factory) -> pathlib.Path:
    path = tmp_path_factory.mktemp("audio") / "stereo44.wav"
    wavfile.write(path, 44100, speechlike(44100, 3.0))
    return path


def test_every_recipe_declares_what_it_is():
    names = {r.name for r in list_recipes()}
    assert {"mfcc_kucherenko", "logmel_gesticulator", "aud2repr2pose_demo", "aud2repr2pose_demo_windows",
            "mfcc_f0_ferstl", "pitch", "energy", "pitch_praat", "text_timing", "words_hash", "words_minilm",
            "words_minilm_static", "words_model"} <= names
    for r in list_recipes():
        assert r.reproduces and r.quirks and r.version >= 1
        assert r.native_fps is None or r.native_fps > 0


def test_mfcc_kucherenko_equals_a_direct_python_speech_features_call(wav44):
    from python_speech_features import mfcc

    rate, data = wavfile.read(wav44)
    with np.errstate(over="ignore"):
        mono = (data[:, 0] + data[:, 1]) / 2          # the original's mix, in int16
    frames = mfcc(mono, winlen=0.02, winstep=0.01, samplerate=rate, numcep=26, nfft=1024)
    n = len(frames) // 5
    expected = np.array([frames[5 * i:5 * i + 5].mean(axis=0) for i in range(n)])
    got = extract("mfcc_kucherenko", wav44, cache=False, dtype=np.float64)
    assert got.shape == (n, 26) == (59, 26)     # 299 frames of 10 ms, blocks of 5, tail dropped
    np.testing.assert_allclose(got, expected, atol=1e-6, rtol=0)
    assert extract("mfcc_kucherenko", wav44, cache=False).dtype == np.float32


def test_mfcc_kucherenko_keeps_the_int16_wraparound_of_the_stereo_mix(tmp_path):
    loud = np.full((4410, 2), 30000, dtype=np.int16)           # L + R overflows int16
    path = tmp_path / "loud.wav"
    wavfile.write(path, 44100, loud)
    from python_speech_features import mfcc

    wrapped = np.full(4410, (30000 + 30000 - 65536) / 2)
    expected = mfcc(wrapped, winlen=0.02, winstep=0.01, samplerate=44100, numcep=26, nfft=1024)
    got = extract("mfcc_kucherenko", path, cache=False, dtype=np.float64)
    np.testing.assert_allclose(got[0], expected[:5].mean(axis=0), atol=1e-6, rtol=0)


def _direct_logmel(path: pathlib.Path) -> np.ndarray:
    """The stated recipe, written independently: float mono, resample_poly to 22,050 Hz, symmetric Hann
    (np.hanning) of 2048, reflect padding 1024, hop 1102, |rfft|^2, Slaney mel triangles built band by band
    in Hz with area normalisation, natural log of (S + 1e-10)."""
    rate, data = wavfile.read(path)
    x = (data.astype(np.float64) / 32768.0).mean(axis=1)
    y = resample_poly(x, 22050 // np.gcd(rate, 22050), rate // np.gcd(rate, 22050))

    def mel(f):
        f = np.asarray(f, dtype=float)
        return np.where(f < 1000, 3 * f / 200, 15 + 27 * np.log(np.maximum(f, 1e-9) / 1000) / np.log(6.4))

    def hz(m):
        m = np.asarray(m, dtype=float)
        return np.where(m < 15, 200 * m / 3, 1000 * 6.4 ** ((m - 15) / 27))

    edges = hz(np.linspace(mel(100.0), mel(7500.0), 66))
    bins = np.arange(1025) * 22050 / 2048
    fb = np.zeros((64, 1025))
    for b in range(64):
        lo, mid, hi = edges[b], edges[b + 1], edges[b + 2]
        up = (bins - lo) / (mid - lo)
        down = (hi - bins) / (hi - mid)
        fb[b] = np.clip(np.minimum(up, down), 0, None) * 2 / (hi - lo)
    padded = np.pad(y, 1024, mode="reflect")
    win = np.hanning(2048)
    rows = []
    for start in range(0, len(padded) - 2048 + 1, 1102):
        spec = np.fft.rfft(padded[start:start + 2048] * win)
        rows.append(fb @ (spec.real ** 2 + spec.imag ** 2))
    return np.log(np.array(rows) + 1e-10)


def test_logmel_gesticulator_equals_a_direct_numpy_scipy_computation(wav44):
    expected = _direct_logmel(wav44)
    got = extract("logmel_gesticulator", wav44, cache=False, dtype=np.float64)
    assert got.shape == expected.shape == (1 + 66150 // 1102, 64)
    np.testing.assert_allclose(got, expected, atol=1e-5, rtol=0)
    assert get_recipe("logmel_gesticulator").native_fps == pytest.approx(22050 / 1102)


def test_logmel_at_22050_hz_needs_no_resampling(tmp_path):
    path = tmp_path / "a.wav"
    wavfile.write(path, 22050, speechlike(22050, 1.0, seed=3))
    np.testing.assert_allclose(extract("logmel_gesticulator", path, cache=False, dtype=np.float64),
                               _direct_logmel(path), atol=1e-5, rtol=0)


def test_ferstl_recipe_is_26_mfcc_and_f0_at_100_fps_and_20_fps_picks_every_fifth_frame(wav44):
    native = extract("mfcc_f0_ferstl", wav44, cache=False, dtype=np.float64)
    assert native.shape[1] == 27 and abs(len(native) - 300) <= 1
    voiced = native[:, 26][native[:, 26] > 0]
    assert voiced.size > 0.4 * len(native) and np.all((voiced > 60) & (voiced < 170))
    np.testing.assert_array_equal(extract("mfcc_f0_ferstl", wav44, fps=20, cache=False, dtype=np.float64),
                                  native[0::5][: len(native) // 5])


def test_audio_as_samples_and_rate_equals_the_file(wav44):
    rate, data = wavfile.read(wav44)
    for name in ("mfcc_kucherenko", "logmel_gesticulator", "energy"):
        np.testing.assert_array_equal(extract(name, (data, rate), cache=False), extract(name, wav44, cache=False))


def test_resampling_rule_is_linear_interpolation_in_time():
    x = np.arange(10, dtype=float)[:, None] * np.array([[1.0, -2.0]])
    y = resample_frames(x, 20.0, 30.0)
    assert y.shape == (15, 2)
    np.testing.assert_allclose(y[:, 0], np.minimum(np.arange(15) * 20 / 30, 9))
    np.testing.assert_array_equal(resample_frames(x, 20.0, 10.0)[:, 0], [0, 2, 4, 6, 8])
    assert resample_frames(x, 20.0, 20.0) is x


def test_n_frames_crops_or_repeats_the_last_frame(wav44):
    full = extract("mfcc_kucherenko", wav44, cache=False)
    np.testing.assert_array_equal(extract("mfcc_kucherenko", wav44, n_frames=10, cache=False), full[:10])
    longer = extract("mfcc_kucherenko", wav44, n_frames=len(full) + 3, cache=False)
    np.testing.assert_array_equal(longer[-3:], np.repeat(full[-1:], 3, axis=0))
    resampled = extract("mfcc_kucherenko", wav44, fps=30, n_frames=95, cache=False)
    assert resampled.shape == (95, 26)
    assert fit_length(np.zeros((0, 4)), 2).shape == (2, 4)


@pytest.mark.skipif(not (DEMO_WAV.is_file() and (GOLDEN / "model_input_windows.npy").is_file()),
                    reason=f"the demo's recording ({DEMO_WAV}) or golden arrays ({GOLDEN}) are not present")
def test_demo_recipes_equal_the_originals_arrays():
    feats = extract("aud2repr2pose_demo", DEMO_WAV, cache=False, dtype=np.float64)
    np.testing.assert_allclose(feats, np.load(GOLDEN / "features_30.npy"), atol=1e-6, rtol=0)
    windows = extract("aud2repr2pose_demo_windows", DEMO_WAV, cache=False, dtype=np.float64)
    golden = np.load(GOLDEN / "model_input_windows.npy")
    assert windows.shape == golden.shape == (399, 61, 30)
    np.testing.assert_allclose(windows, golden, atol=1e-6, rtol=0)
    np.testing.assert_allclose(extract("aud2repr2pose_demo_windows", DEMO_WAV, cache=False), golden,
                               atol=1e-12, rtol=1e-6)                 # float32: rounding only
    np.testing.assert_allclose(extract("mfcc_kucherenko", DEMO_WAV, cache=False, dtype=np.float64).shape, (399, 26))


def _words():
    from evalsuite.corpus.types import Transcript, Word

    return Transcript((Word("hi", 0.0, 0.5),))


def test_errors_name_the_file_the_recipe_and_the_option(tmp_path, wav44):
    with pytest.raises(InputError, match=r"missing\.wav: no such audio file"):
        extract("mfcc_kucherenko", tmp_path / "missing.wav", cache=False)
    for k, content in enumerate((b"not a wav file", b"RIFF\x00\x00\x00\x00WAVEjunk", b"RIFF\x24\x00\x00\x00WAVEfmt ")):
        bad = tmp_path / f"bad{k}.wav"
        bad.write_bytes(content)
        with pytest.raises(InputError, match=rf"bad{k}\.wav: not a readable WAV file"):
            extract("mfcc_kucherenko", bad, cache=False)
    with pytest.raises(InputError, match=r"recipe: unknown feature recipe 'mfcc'; known: .*mfcc_kucherenko"):
        extract("mfcc", wav44, cache=False)
    with pytest.raises(InputError, match=r"recipe 'pitch' has no option winlen \(its options: fmax, fmin"):
        extract("pitch", wav44, cache=False, winlen=0.1)
    with pytest.raises(InputError, match=r"fps: the frame rate must be a positive number, got -5"):
        extract("pitch", wav44, fps=-5, cache=False)
    with pytest.raises(InputError, match=r"n_frames: n_frames must be a non-negative integer, got -1"):
        extract("text_timing", None, transcript=_words(), n_frames=-1, cache=False)
    with pytest.raises(InputError, match=r"fps: the frame rate must be a positive number, got '20'"):
        extract("pitch", wav44, fps="20", cache=False)
    with pytest.raises(InputError, match=r"gives 20 fps only, not 30"):
        extract("aud2repr2pose_demo_windows", wav44, fps=30, cache=False)
    with pytest.raises(InputError, match=r"shape \(N,\) or \(N, C\)"):
        extract("energy", (np.zeros((2, 2, 2)), 16000), cache=False)
    with pytest.raises(InputError, match=r"sample rate must be a positive integer, got 0"):
        extract("energy", (np.zeros(100), 0), cache=False)
    with pytest.raises(InputError, match=r"transcript: recipe 'text_timing' computes text features"):
        extract("text_timing", wav44, cache=False)


@pytest.mark.parametrize("n, rate, options", [
    (44100 * 3 + 7, 44100, {"winlen": 0.06666666666, "winstep": 0.0166666666, "numcep": 26}),   # the demo's
    (16000 * 2 + 13, 16000, {"winlen": 0.02, "winstep": 0.01, "numcep": 26, "nfft": 1024}),     # Kucherenko's
    (96000, 96000, {"winlen": 0.02, "winstep": 0.01, "numcep": 26, "nfft": 1024}),   # frames truncated to nfft
    (100, 16000, {"winlen": 0.02, "winstep": 0.01, "numcep": 13}),                   # shorter than one frame
])
def test_psf_mfcc_with_strided_frames_is_bit_identical_to_the_library(n, rate, options):
    import logging
    import warnings

    from python_speech_features import mfcc

    from evalsuite.features.mfcc import psf_mfcc

    x = np.random.default_rng(n).integers(-3000, 3000, n).astype(np.int16) / 2
    logging.disable(logging.WARNING)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            expected = mfcc(x, samplerate=rate, **options)
    finally:
        logging.disable(logging.NOTSET)
    np.testing.assert_array_equal(psf_mfcc(x, rate, **options), expected)
