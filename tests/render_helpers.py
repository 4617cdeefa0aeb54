"""Shared helpers of the render tests: a small analytic skeleton, decoding videos with ffmpeg."""
from __future__ import annotations

import subprocess

import imageio_ffmpeg
import numpy as np

from evalsuite.motion import Motion

RATE = 16000
NAMES = ["Hips", "Spine", "Neck", "Head",
         "LeftShoulder", "LeftElbow", "LeftWrist", "RightShoulder", "RightElbow", "RightWrist",
         "LeftHip", "LeftKnee", "LeftAnkle", "RightHip", "RightKnee", "RightAnkle"]
PARENTS = [-1, 0, 1, 2, 2, 4, 5, 2, 7, 8, 0, 10, 11, 0, 13, 14]
# A T-pose facing +Z (its left side at +X), Y up, in centimetres.
TPOSE = np.array([[0, 100, 0], [0, 130, 0], [0, 150, 0], [0, 165, 0],
                  [15, 148, 0], [40, 148, 0], [65, 148, 0], [-15, 148, 0], [-40, 148, 0], [-65, 148, 0],
                  [10, 95, 0], [10, 50, 0], [10, 5, 0], [-10, 95, 0], [-10, 50, 0], [-10, 5, 0]], dtype=float)


def waving_motion(seconds=1.0, fps=30.0, amplitude=20.0, shift=(0.0, 0.0, 0.0)) -> Motion:
    """The T-pose with both forearms waving up and down."""
    t = np.arange(int(round(seconds * fps))) / fps
    pos = np.repeat(TPOSE[None], len(t), axis=0) + np.asarray(shift)
    wave = amplitude * np.sin(2 * np.pi * 1.5 * t)
    pos[:, [5, 8], 1] += wave[:, None] * 0.5
    pos[:, [6, 9], 1] += wave[:, None]
    return Motion.from_positions(pos, NAMES, fps, PARENTS)


def decode(path):
    gen = imageio_ffmpeg.read_frames(str(path))
    meta = next(gen)
    w, h = meta["size"]
    frames = np.stack([np.frombuffer(f, np.uint8).reshape(h, w, 3) for f in gen])
    return meta, frames


def decoded_audio_seconds(path, rate=RATE) -> float:
    """Decode the audio stream fully with ffmpeg and count the samples."""
    out = subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-i", str(path), "-vn", "-f", "s16le",
                          "-ac", "1", "-ar", str(rate), "-"], capture_output=True, check=True).stdout
    return len(out) / 2 / rate


def ffmpeg_stream_info(path) -> str:
    return subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-hide_banner", "-i", str(path)],
                          capture_output=True, text=True).stderr
