"""The volume-calibration sound of the headphone check (Woods, Siegel, Traer & McDermott 2017).

Before the screening trials the participant plays a noise as often as they like and sets the computer's
volume until it is comfortable; the trials that follow are then heard at that volume. The noise has the
RMS level of the trials' plain tone (:data:`study_app.headphones.LEVEL` peak, so RMS = LEVEL / sqrt(2)),
so that a comfortable noise means comfortable tones. It is the same in both ears (diotic), tells nothing
about any trial, and may be replayed: it is not a media slot of the page and is not in ``media_served``.
"""
from __future__ import annotations

import functools

import numpy as np
from flask import Blueprint, Response, request

from study_app.headphones import LEVEL, RATE, stereo_wav
from study_app.participant import _own

bp = Blueprint("calibration", __name__)

SECONDS = 3.0
RAMP_SECONDS = 0.1
SEED = 2017


def calibration_samples() -> np.ndarray:
    """Stereo samples ``(n, 2)`` in [-1, 1]: Gaussian white noise, n = RATE * SECONDS, both channels equal,
    raised-cosine ramps of RAMP_SECONDS, scaled so that RMS over the whole sound = LEVEL / sqrt(2) (the RMS
    of the trials' plain tone, a sine of peak LEVEL)."""
    rng = np.random.default_rng(SEED)
    x = rng.standard_normal(int(RATE * SECONDS))
    n = int(RATE * RAMP_SECONDS)
    ramp = 0.5 - 0.5 * np.cos(np.pi * np.arange(n) / n)
    x[:n] *= ramp
    x[-n:] *= ramp[::-1]
    x *= (LEVEL / np.sqrt(2)) / np.sqrt(np.mean(x ** 2))
    x = np.clip(x, -1.0, 1.0)
    return np.stack([x, x], axis=1)


@functools.lru_cache(maxsize=1)
def calibration_wav() -> bytes:
    """The calibration noise as a 16-bit stereo WAV file (made once per process)."""
    return stereo_wav(calibration_samples())


@bp.route("/s/<sid>/calibration.wav")
def calibration(sid):
    """The calibration noise, for a browser that holds the session (replays allowed)."""
    _own(sid)
    body = calibration_wav()
    resp = Response(body, mimetype="audio/wav")
    resp.headers["Cache-Control"] = "private, max-age=3600"
    return resp.make_conditional(request, accept_ranges=True, complete_length=len(body))
