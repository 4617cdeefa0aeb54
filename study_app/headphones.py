"""Headphone screening (Woods, Siegel, Traer & McDermott 2017, *Attention, Perception &
Psychophysics* 79:2064-2072), the check crowd audio studies use before speech matters.

Each trial plays three 200 Hz tones of 1 s (100 ms raised-cosine ramps, 500 ms apart). One is
6 dB quieter; one is in antiphase between the left and right channel; one is the plain tone.
The participant reports which tone was *quietest*. Over headphones the quiet tone is plainly
the quietest; over loudspeakers the two channels of the antiphase tone cancel in the air, so it
sounds quietest and people pick it. Woods et al. use 6 trials, each heard once, and pass a
participant with at least 5 correct (chance passes 1.8 % of the time).

The answer of a trial is in the sound only: the page and its URLs name the trial number, never
the order of the tones. Nor do the files' bytes give it away to a lookup table: each trial's sound is
made when it is requested from a seed stored in the session's plan (:func:`trial_seeds`), with its own
random starting phase for each tone and a level jitter of the whole trial (the same for its three
tones, so the quiet tone stays 6 dB below the others). Every trial file therefore has the same length
and byte size whatever its answer, and no two sessions receive the same file. A program that decodes the
audio and measures each tone's level can still find the quiet tone: that is the listening task itself.
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
LEVEL_JITTER_DB = 1.0   # a trial's level is LEVEL times 10**(u/20), u uniform in +-this (seeded)
QUIET_DB = -6.0
TONES = ("plain", "quiet", "antiphase")
TRIAL_SECONDS = 3 * TONE_SECONDS + 2 * GAP_SECONDS      # length of one trial's sound
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


def trial_seeds(n_trials: int, rng) -> list[int]:
    """One seed per trial (stored in the plan): it draws the trial's phases and level jitter."""
    return [rng.getrandbits(48) for _ in range(n_trials)]


def _tone(phase: float = 0.0) -> np.ndarray:
    t = np.arange(int(RATE * TONE_SECONDS)) / RATE
    x = np.sin(2 * np.pi * FREQUENCY * t + phase)
    n = int(RATE * RAMP_SECONDS)
    ramp = 0.5 - 0.5 * np.cos(np.pi * np.arange(n) / n)
    x[:n] *= ramp
    x[-n:] *= ramp[::-1]
    return x


def trial_samples(order: int, seed: int | None = None) -> np.ndarray:
    """Stereo samples ``(n, 2)`` in [-1, 1] of one trial, tones in the given order.

    Without a seed every tone starts at phase 0 at level :data:`LEVEL`. With one, tone ``k`` is
    ``g * LEVEL * ramp(t) * sin(2 pi f t + phi_k)`` with ``phi_k`` uniform in [0, 2 pi) per tone and
    ``g = 10**(u / 20)``, ``u`` uniform in +-:data:`LEVEL_JITTER_DB` dB once per trial.
    """
    if seed is None:
        phases, gain = np.zeros(3), 1.0
    else:
        rng = np.random.default_rng(seed)
        phases = rng.uniform(0.0, 2 * np.pi, 3)
        gain = 10 ** (rng.uniform(-LEVEL_JITTER_DB, LEVEL_JITTER_DB) / 20)
    gap = np.zeros((int(RATE * GAP_SECONDS), 2))
    parts = []
    for k, kind in enumerate(ORDERS[order]):
        tone = gain * LEVEL * _tone(float(phases[k]))
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


@functools.lru_cache(maxsize=64)
def trial_wav(order: int, seed: int | None = None) -> bytes:
    """One trial as a 16-bit stereo WAV file (about 150 kB; the same length and size for every order
    and seed). The study app passes the trial's stored seed, so a range request gets the same bytes."""
    if not 0 <= order < len(ORDERS):
        raise ValueError(f"trial order must be in 0..{len(ORDERS) - 1}, got {order}")
    return stereo_wav(trial_samples(order, seed))


def stereo_wav(samples: np.ndarray) -> bytes:
    """Samples ``(n, 2)`` in [-1, 1] at :data:`RATE` as a 16-bit stereo WAV file."""
    pcm = np.round(samples * 32767).astype("<i2")
    buf = io.BytesIO()
    with wave.open(buf, "wb") as w:
        w.setnchannels(2)
        w.setsampwidth(2)
        w.setframerate(RATE)
        w.writeframes(pcm.tobytes())
    return buf.getvalue()
