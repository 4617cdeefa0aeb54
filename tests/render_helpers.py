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


def _genea2023_joints() -> dict:
    """name -> (parent, OFFSET) of a stand-in with the GENEA 2023 (Talking With Hands) joint names and
    hierarchy, in centimetres, Y up, facing +Z with its left at +X: ``body_world`` is a root at the floor
    (the origin) whose child ``b_root`` is the pelvis, placed by its own position channels."""
    j: dict = {"body_world": (None, (0, 0, 0)), "b_root": ("body_world", (0, 0, 0))}
    for s, x in (("l", 1), ("r", -1)):
        j[f"b_{s}_upleg"] = ("b_root", (9 * x, -5, 0))
        j[f"b_{s}_leg"] = (f"b_{s}_upleg", (0, -42, 0))
    j["b_spine0"] = ("b_root", (0, 8, 0))
    for k in (1, 2, 3):
        j[f"b_spine{k}"] = (f"b_spine{k - 1}", (0, 10, 0))
    fingers = {"pinky": (3, -3), "ring": (4, -1), "middle": (4, 1), "index": (4, 3), "thumb": (1, 3)}
    for s, x in (("l", 1), ("r", -1)):
        chain = [("shoulder", "b_spine3", (4, 8, 0)), ("arm", "shoulder", (14, 0, 0)), ("arm_twist", "arm", (14, 0, 0)),
                 ("forearm", "arm_twist", (14, 0, 0)), ("wrist_twist", "forearm", (12, 0, 0)),
                 ("wrist", "wrist_twist", (12, 0, 0))]
        for name, parent, off in chain:
            j[f"b_{s}_{name}"] = (parent if parent.startswith("b_") else f"b_{s}_{parent}", (off[0] * x, off[1], off[2]))
        order = ["pinky", "ring", "middle", "index", "thumb"] if s == "l" else ["thumb", "pinky", "middle", "ring", "index"]
        for finger in order:
            first = 0 if finger == "thumb" else 1
            for k in range(first, 4):
                parent = f"b_{s}_wrist" if k == first else f"b_{s}_{finger}{k - 1}"
                dx, dz = fingers[finger] if k == first else ((2, 1) if finger == "thumb" else (3, 0))
                j[f"b_{s}_{finger}{k}"] = (parent, (dx * x, 0, dz))
    j["b_neck0"] = ("b_spine3", (0, 10, 0))
    j["b_head"] = ("b_neck0", (0, 10, 0))
    return j


def genea2023_standin(seconds=1.0, fps=30.0) -> Motion:
    """A hierarchical motion on the GENEA 2023 stand-in skeleton: world root fixed at the floor, the
    pelvis swaying 95 cm above it, arms hanging at 70 degrees and the forearms waving."""
    from evalsuite.motion.presets import GENEA2023
    from evalsuite.motion.skeleton import Skeleton

    joints = _genea2023_joints()
    assert list(joints) == GENEA2023   # the stand-in keeps the real file's joint order
    names = list(joints)
    parents = [names.index(p) if p else -1 for p, _ in joints.values()]
    six = ("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation")
    channels = [six if n in ("body_world", "b_root") else six[3:] for n in names]
    skeleton = Skeleton(names, parents, [off for _, off in joints.values()], channels)
    t = np.arange(int(round(seconds * fps))) / fps
    values = np.zeros((len(t), skeleton.n_channels))
    start = {n: int(s) for n, s in zip(names, skeleton.channel_starts)}
    values[:, start["b_root"]] = 3.0 * np.sin(2 * np.pi * 0.5 * t)           # sway along X
    values[:, start["b_root"] + 1] = 95.0                                       # pelvis height
    for s, sign in (("l", -1.0), ("r", 1.0)):
        values[:, start[f"b_{s}_arm"]] = sign * 70.0                              # Zrotation: arms down
        values[:, start[f"b_{s}_forearm"] + 1] = 30.0 * np.sin(2 * np.pi * 1.5 * t)   # Xrotation: wave
    return Motion(skeleton, values, fps, name="genea2023_standin")


def upper_body(seconds=0.5, fps=30.0) -> Motion:
    """The first ten joints of :data:`NAMES` (hips to wrists, no legs) with the arms hanging: an upper-body
    skeleton like GENEA 2020's (torso 50 cm, shoulders 30 cm apart; its extent, 65 cm, is far below its stature)."""
    rest = TPOSE[:10].copy()
    rest[1, 1] = 110.0     # the spine joint near the pelvis (else the root reads as a world root: renderers.skeleton)
    rest[4:10] = [[15, 148, 0], [18, 120, 3], [20, 95, 6], [-15, 148, 0], [-18, 120, 3], [-20, 95, 6]]
    n = int(round(seconds * fps))
    pos = np.repeat(rest[None], n, axis=0)
    pos[:, 6, 1] += 10 * np.sin(np.linspace(0, np.pi, n))     # the left wrist lifts a little
    return Motion.from_positions(pos, NAMES[:10], fps, PARENTS[:10])
