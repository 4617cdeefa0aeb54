"""MFCC recipes: Kucherenko et al.'s 26 MFCC at 20 fps, and Ferstl et al.'s 26 MFCC + F0 at 100 fps.

``mfcc_kucherenko`` is what ``calculate_mfcc`` computes in both Kucherenko code bases
(Speech_driven_gesture_generation_with_autoencoder ``data_processing/tools.py`` and Gesticulator's
``data_processing/tools.py``): the WAV as ``scipy.io.wavfile.read`` gives it (native rate, integer scale),
a stereo file mixed as ``(L + R) / 2`` **in the file's integer type** (int16 wraps around where ``L + R``
overflows, as in the original), ``python_speech_features.mfcc(winlen=0.02, winstep=0.01, numcep=26,
nfft=1024)`` with its other defaults (nfilt 26, preemphasis 0.97, ceplifter 22, column 0 replaced by the log
frame energy; above 51.2 kHz a 20 ms window is longer than 1024 samples and is truncated, as in the
original), then the 100-fps frames averaged in blocks of 5 (tail dropped) -> 20 fps. Frame ``t`` starts at
``t / 20`` s and spans 0.06 s.

``mfcc_f0_ferstl``: Ferstl, Neff & McDonnell (MIG 2019) extracted 26 MFCC and F0 with openSMILE, 20 ms
windows every 10 ms (100 fps), and trained on 20-fps data taken from 5 starting offsets. openSMILE's MFCC
configuration is not given in the paper and is not reproduced: we use python_speech_features with the same
window and step (26 filters, 26 coefficients, nfft the next power of two of the window, so nothing is
truncated) and F0 (Hz, 0 unvoiced) from the permissive pitch tracker (:mod:`evalsuite.features.prosody`),
its analysis window centred on each MFCC window's centre. 100 fps native; ``fps=20`` gives frames
``[0::5]`` exactly (the paper's first offset; ``features[k::5]`` for the others, at native rate).
"""
from __future__ import annotations

import logging
import math
import warnings

import numpy as np

from evalsuite.errors import InputError
from evalsuite.features.base import Audio, Recipe, register_recipe

__all__ = ["kucherenko_mfcc", "ferstl_mfcc_f0", "psf_mfcc", "original_mix"]


class _TruncationNotice(logging.Filter):
    def filter(self, record: logging.LogRecord) -> bool:
        return "greater than FFT size" not in record.getMessage()


def _frames(signal: np.ndarray, frame_len: int, frame_step: int) -> np.ndarray:
    """``python_speech_features.sigproc.framesig`` (no window) as a strided view: the same frames, zero-padded
    at the end the same way, without building an index array of every sample of every frame."""
    n = 1 if len(signal) <= frame_len else 1 + int(math.ceil((1.0 * len(signal) - frame_len) / frame_step))
    padded = np.concatenate((signal, np.zeros((n - 1) * frame_step + frame_len - len(signal))))
    return np.lib.stride_tricks.sliding_window_view(padded, frame_len)[::frame_step][:n]


def psf_mfcc(signal: np.ndarray, rate: int, *, winlen: float = 0.025, winstep: float = 0.01, numcep: int = 13,
             nfilt: int = 26, nfft: int = 512, preemph: float = 0.97, ceplifter: int = 22) -> np.ndarray:
    """``python_speech_features.mfcc`` (its defaults, rectangular window, log energy in column 0), computed from
    the library's own steps (pre-emphasis, power spectrum, mel filterbank, DCT, lifter) with strided framing,
    which is several times faster on long files and gives the same numbers (tests/test_features_recipes.py);
    its notice that a frame longer than ``nfft`` is truncated is silenced (the truncation is part of the
    recipes)."""
    try:
        from python_speech_features import sigproc
        from python_speech_features.base import get_filterbanks, lifter
    except ImportError:  # pragma: no cover - a dependency of evalsuite
        raise InputError("MFCC recipes need python_speech_features: pip install python-speech-features") from None
    from scipy.fftpack import dct

    notice = _TruncationNotice()
    logging.getLogger().addFilter(notice)
    try:
        with warnings.catch_warnings():   # python_speech_features calls the deprecated logging.warn
            warnings.filterwarnings("ignore", "The 'warn' function is deprecated", DeprecationWarning)
            emphasised = sigproc.preemphasis(np.asarray(signal), preemph)
            frames = _frames(emphasised, sigproc.round_half_up(winlen * rate), sigproc.round_half_up(winstep * rate))
            pspec = sigproc.powspec(frames, nfft)
    finally:
        logging.getLogger().removeFilter(notice)
    eps = np.finfo(float).eps
    energy = np.sum(pspec, 1)
    energy = np.where(energy == 0, eps, energy)
    feat = np.dot(pspec, get_filterbanks(nfilt, nfft, rate, 0, rate / 2).T)
    feat = dct(np.log(np.where(feat == 0, eps, feat)), type=2, axis=1, norm="ortho")[:, :numcep]
    feat = lifter(feat, ceplifter)
    feat[:, 0] = np.log(energy)
    return np.asarray(feat, dtype=np.float64)


def original_mix(audio: Audio) -> np.ndarray:
    """The originals' mono signal: the samples as read (integer scale kept); two channels mixed as
    ``(L + R) / 2`` with ``L + R`` in the samples' own type (integers wrap around), more than two averaged."""
    x = audio.samples
    if x.shape[1] == 1:
        return x[:, 0]
    if x.shape[1] == 2:
        with np.errstate(over="ignore"):
            return (x[:, 0] + x[:, 1]) / 2
    return x.astype(np.float64).mean(axis=1)


def kucherenko_mfcc(audio: Audio) -> np.ndarray:
    """``(T, 26)`` at 20 fps (see the module docstring)."""
    frames = psf_mfcc(original_mix(audio), audio.rate, winlen=0.02, winstep=0.01, numcep=26, nfft=1024)
    n = len(frames) // 5
    return frames[: n * 5].reshape(n, 5, 26).mean(axis=1)


def ferstl_mfcc_f0(audio: Audio, *, fmin: float = 60.0, fmax: float = 500.0) -> np.ndarray:
    """``(T, 27)`` at 100 fps: 26 MFCC then F0 in Hz (0 when unvoiced)."""
    from evalsuite.features.prosody import yin_pitch

    winlen = 0.02
    nfft = 1 << int(np.ceil(np.log2(max(winlen * audio.rate, 2))))
    frames = psf_mfcc(original_mix(audio), audio.rate, winlen=winlen, winstep=0.01, numcep=26, nfilt=26, nfft=nfft)
    centres = np.arange(len(frames)) * 0.01 + winlen / 2
    f0 = yin_pitch(audio.mono(), audio.rate, centres, fmin=fmin, fmax=fmax)
    return np.concatenate([frames, f0[:, None]], axis=1)


register_recipe(Recipe(
    name="mfcc_kucherenko", native_fps=20.0, dim=26,
    reproduces="calculate_mfcc of Kucherenko et al.'s code (Speech_driven_gesture_generation_with_autoencoder, "
               "Gesticulator): 26 MFCC, 20 ms / 10 ms, averaged over 5 frames to 20 fps",
    quirks="native rate and integer scale of the WAV; stereo (L + R) / 2 in int16 wraps around; column 0 is the "
           "log frame energy; nfft 1024 truncates windows above 51.2 kHz; tail frames (< 5) dropped",
    compute=lambda audio, transcript, fps, n, opts: kucherenko_mfcc(audio)))

register_recipe(Recipe(
    name="mfcc_f0_ferstl", native_fps=100.0, dim=27,
    reproduces="Ferstl, Neff & McDonnell (MIG 2019): 26 MFCC + F0, 20 ms windows every 10 ms (100 fps)",
    quirks="the paper used openSMILE (configuration not published): python_speech_features MFCC with the same "
           "window and step and the evalsuite YIN-style F0 instead; fps=20 gives frames [0::5]",
    compute=lambda audio, transcript, fps, n, opts: ferstl_mfcc_f0(audio, fmin=opts["fmin"], fmax=opts["fmax"]),
    params={"fmin": 60.0, "fmax": 500.0}))
