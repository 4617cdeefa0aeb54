"""The headphone check's volume-calibration noise (study_app.calibration): its level equals the trials'
plain tone, it is the same in both ears, and only the browser that holds the session gets it."""
from __future__ import annotations

import io
import wave

import numpy as np
import study_helpers as h
from study_fixtures import make_app

from study_app.calibration import SECONDS, calibration_samples, calibration_wav
from study_app.headphones import LEVEL, RATE, trial_samples


def test_noise_has_the_rms_of_the_plain_tone_in_both_ears():
    x = calibration_samples()
    assert x.shape == (int(RATE * SECONDS), 2)
    assert np.array_equal(x[:, 0], x[:, 1])
    assert abs(np.sqrt(np.mean(x ** 2)) - LEVEL / np.sqrt(2)) < 1e-9
    # the plain tone's steady part (order 0 plays it first; its 0.1 s ramps left out) has that RMS too
    n = int(RATE * 0.1)
    steady = trial_samples(0)[n: int(RATE * 1.0) - n, 0]
    assert abs(np.sqrt(np.mean(steady ** 2)) - LEVEL / np.sqrt(2)) < 1e-3
    assert np.abs(x).max() < 1.0
    assert abs(x[0, 0]) < 0.01 and abs(x[-1, 0]) < 0.01     # ramps: no click at either end


def test_wav_is_16_bit_stereo_at_the_trials_rate():
    with wave.open(io.BytesIO(calibration_wav())) as w:
        assert (w.getnchannels(), w.getsampwidth(), w.getframerate()) == (2, 2, RATE)
        pcm = np.frombuffer(w.readframes(w.getnframes()), "<i2").reshape(-1, 2) / 32767
    assert np.allclose(pcm, calibration_samples(), atol=1 / 32767)


def test_only_the_sessions_browser_gets_the_noise_and_may_replay_it(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    alice, bob = h.Participant(app.test_client(), "pcalib001"), h.Participant(app.test_client(), "pcalib002")
    alice.enter()
    bob.enter()
    url = f"/s/{alice.sid}/calibration.wav"
    assert bob.client.get(url).status_code == 403
    for _ in range(2):                                     # not a trial: played as often as wanted
        r = alice.client.get(url)
        assert r.status_code == 200 and r.mimetype == "audio/wav" and r.data == calibration_wav()
    part = alice.client.get(url, headers={"Range": "bytes=0-99"})
    assert part.status_code == 206 and len(part.data) == 100
