"""The Aud2Repr2Pose demo's speech features against the original pipeline's intermediates (to 1e-6), and the
whole published model from the recording against the original's gestures.

Golden arrays: ../shared/golden/aud2repr2pose-demo; the recording: ../shared/weights/aud2repr2pose-demo/audio
(tests only, never in this repository)."""
from __future__ import annotations

import pathlib

import numpy as np
import pytest

from evalsuite.audio import write_wav
from evalsuite.errors import InputError
from evalsuite.features.aud2repr2pose_demo import demo_features, demo_mfcc, demo_prosody, demo_windows, silence_row

SHARED = pathlib.Path(__file__).resolve().parents[1].parent / "shared"
WAV = SHARED / "weights" / "aud2repr2pose-demo" / "audio" / "audio3_20sec.wav"
GOLDEN = SHARED / "golden" / "aud2repr2pose-demo"
pytestmark = pytest.mark.skipif(not (WAV.is_file() and (GOLDEN / "mfcc_20fps.npy").is_file()),
                                reason=f"the demo's recording ({WAV}) or golden arrays ({GOLDEN}) are not present")


def golden(name: str) -> np.ndarray:
    return np.load(GOLDEN / name)


def test_mfcc_reproduces_the_original_with_the_int16_wraparound():
    np.testing.assert_allclose(demo_mfcc(WAV), golden("mfcc_20fps.npy"), atol=1e-6, rtol=0)


def test_prosody_reproduces_the_praat_tracks_and_their_averages():
    np.testing.assert_allclose(demo_prosody(WAV, per_query=True), golden("prosody_180hz.npy"), atol=1e-6, rtol=0)
    np.testing.assert_allclose(demo_prosody(WAV), golden("prosody_20fps.npy"), atol=1e-6, rtol=0)


def test_padding_features_and_windows_reproduce_the_model_input():
    np.testing.assert_allclose(silence_row(), golden("silence_pad_vector.npy"), atol=1e-6, rtol=0)
    features = demo_features(WAV)
    np.testing.assert_allclose(features, golden("features_30.npy"), atol=1e-6, rtol=0)
    windows = demo_windows(features)
    assert windows.shape == (399, 61, 30)
    np.testing.assert_allclose(windows, golden("model_input_windows.npy"), atol=1e-6, rtol=0)
    np.testing.assert_allclose(windows[:, 30], features)            # the centre of window i is frame i


def test_the_published_model_from_the_recording_gives_the_originals_gestures():
    from evalsuite.generators.aud2repr2pose_demo.model import Aud2Repr2PoseDemo

    folder = WAV.parent.parent
    if not (folder / "Model_MFCC_Pros_Best.hdf5").is_file():
        pytest.skip(f"the demo model's files are not present in {folder}")
    points = Aud2Repr2PoseDemo.from_folder(folder)(demo_windows(demo_features(WAV)))
    # float32 summation order in the speech encoder (codes within 2.3e-6) amplified by max_val (<= 121 cm)
    np.testing.assert_allclose(points.reshape(len(points), -1), golden("gestures.npy"), atol=2.5e-4, rtol=0)


def test_float_wav_is_refused_with_the_reason(tmp_path):
    from scipy.io import wavfile

    path = tmp_path / "float.wav"
    wavfile.write(path, 16000, np.zeros(16000, dtype=np.float32))
    with pytest.raises(InputError, match="integer PCM"):
        demo_mfcc(path)
    mono = tmp_path / "mono.wav"
    write_wav(mono, np.zeros(16000), 16000)
    assert demo_mfcc(mono).shape[1] == 26
