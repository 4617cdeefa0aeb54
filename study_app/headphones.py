"""Headphone screening (Woods, Siegel, Traer & McDermott 2017, *Attention, Perception &
Psychophysics* 79:2064-2072), the check crowd audio studies use before speech matters.

Each trial plays three 200 Hz tones of 1 s (100 ms raised-cosine ramps, 500 ms apart). One is
6 dB quieter; one is in antiphase between the left and right channel; one is the plain tone.
The participant reports which tone was *quietest*. Over headphones the quiet tone is plainly
the quietest; over loudspeakers the two channels of the antiphase tone cancel in the air, so it
sounds quietest and people pick it. Woods et al. use 6 trials, each heard once, and pass a
participant with at least 5 correct (chance passes 1.8 % of the time).

The answer of a trial is in the sound only: the page and its URLs name the trial number, never
the order of the tones.
"""
from __future__ import annotations

import functools
import io
import itertools
import wave

import numpy as np

RATE = 22050            # Hz; ample for a 200 Hz tone, and the files stay small
FREQUENCY = 200.0       # Hz
TONE_SECONDS = 1.0
RAMP_SECONDS = 0.1
GAP_SECONDS = 0.5
LEVEL = 0.25            # peak of the plain tone, about -12 dBFS: room for the listener's volume
QUIET_DB = -6.0
TONES = ("plain", "quiet", "antiphase")
#: the six orders of the three tones; a plan's trial names one of them by index
ORDERS = tuple(itertools.permutations(TONES))


def correct_choice(order: int) -> int:
    """The tone (1, 2 or 3) an attentive listener on headphones reports as quietest."""
    return ORDERS[order].index("quiet") + 1


def trial_orders(n_trials: int, rng) -> list[int]:
    """``n_trials`` order indices: the six orders shuffled, then again, so the quiet tone is in
    each position equally often over every six trials."""
    out: list = []
    while len(out) < n_trials:
        block = list(range(len(ORDERS)))
        rng.shuffle(block)
        out += block
    return out[:n_trials]


def _tone() -> np.ndarray:
    t = np.arange(int(RATE * TONE_SECONDS)) / RATE
    x = np.sin(2 * np.pi * FREQUENCY * t)
    n = int(RATE * RAMP_SECONDS)
    ramp = 0.5 - 0.5 * np.cos(np.pi * np.arange(n) / n)
    x[:n] *= ramp
    x[-n:] *= ramp[::-1]
    return x


def trial_samples(order: int) -> np.ndarray:
    """Stereo samples ``(n, 2)`` in [-1, 1] of one trial, tones in the given order."""
    tone = LEVEL * _tone()
    gap = np.zeros((int(RATE * GAP_SECONDS), 2))
    parts = []
    for k, kind in enumerate(ORDERS[order]):
        if kind == "plain":
            parts.append(np.stack([tone, tone], axis=1))
        elif kind == "quiet":
            q = tone * 10 ** (QUIET_DB / 20)
            parts.append(np.stack([q, q], axis=1))
        else:
            parts.append(np.stack([tone, -tone], axis=1))
        if k < 2:
            parts.append(gap)
    return np.concatenate(parts)


@functools.lru_cache(maxsize=len(ORDERS))
def trial_wav(order: int) -> bytes:
    """One trial as a 16-bit stereo WAV file (made once per process, about 150 kB)."""
    if not 0 <= order < len(ORDERS):
        raise ValueError(f"trial order must be in 0..{len(ORDERS) - 1}, got {order}")
    pcm = np.round(trial_samples(order) * 32767).astype("<i2")
    buf = io.BytesIO()
    with wave.open(buf, "wb") as w:
        w.setnchannels(2)
        w.setsampwidth(2)
        w.setframerate(RATE)
        w.writeframes(pcm.tobytes())
    return buf.getvalue()
