"""Stand-ins of the four kinds of input a body style draws, all self-made: a BEAT-style BVH (Mixamo-like names,
fingers), an SMPL-X recording with a plausible fake model (55 vertices at SMPL-X-like joint places, an
identity J_regressor; nothing licensed), a positions ``.npz`` and the GENEA 2023 stand-in of render_helpers."""
from __future__ import annotations

import pathlib

import numpy as np
from render_helpers import genea2023_standin

from evalsuite.motion import Motion
from evalsuite.motion.io import save_motion
from evalsuite.motion.smplx_layout import SMPLX_JOINT_NAMES, SMPLX_PARENTS
from evalsuite.motion.synthetic import humanoid_skeleton


def beat_standin(seconds: float = 1.0, fps: float = 30.0) -> Motion:
    """Mixamo-style names (Hips, Spine..Spine3, LeftArm, LeftHandIndex1...), 20 finger joints, arms hanging at
    70 degrees with the forearms raised forward and waving, fingers slightly curled."""
    sk = humanoid_skeleton(54)
    t = np.arange(int(round(seconds * fps))) / fps
    values = np.zeros((len(t), sk.n_channels))
    start = {n: int(s) for n, s in zip(sk.names, sk.channel_starts)}
    values[:, 1] = 95.0
    for side, sign in (("Left", -1.0), ("Right", 1.0)):
        values[:, start[f"{side}Arm"]] = sign * 70.0                                        # Z: arm down
        values[:, start[f"{side}ForeArm"] + 2] = -sign * (50.0 + 20.0 * np.sin(2 * np.pi * t))   # Y: forward
        for n in sk.names:
            if n.startswith(f"{side}Hand") and n != f"{side}Hand":
                values[:, start[n] + 2] = -sign * 15.0                                       # Y: curl
    return Motion(sk, values, fps, name="beat_standin")


def beat_bvh(path) -> pathlib.Path:
    path = pathlib.Path(path)
    save_motion(beat_standin(), path)
    return path


_REST = {   # SMPL-X-like rest joints in metres: Y up, facing +Z, the body's left at +X (a T-pose)
    "pelvis": (0, 0, 0), "left_hip": (0.06, -0.09, 0), "spine1": (0, 0.11, -0.01), "left_knee": (0.10, -0.47, 0),
    "spine2": (0, 0.24, 0), "left_ankle": (0.09, -0.87, -0.04), "spine3": (0, 0.30, 0.01),
    "left_foot": (0.11, -0.93, 0.08), "neck": (0, 0.51, -0.02), "left_collar": (0.07, 0.41, 0),
    "head": (0, 0.60, 0.01), "left_shoulder": (0.17, 0.44, -0.02), "left_elbow": (0.43, 0.42, -0.04),
    "left_wrist": (0.68, 0.42, -0.03), "jaw": (0, 0.56, 0.05), "left_eye_smplhf": (0.03, 0.66, 0.08),
}
_FINGER_BASE = {"index": (0.77, 0.41, 0.025), "middle": (0.775, 0.41, 0.0), "pinky": (0.75, 0.41, -0.045),
                "ring": (0.765, 0.41, -0.022), "thumb": (0.71, 0.40, 0.045)}


def smplx_rest_joints() -> np.ndarray:
    out = np.zeros((55, 3))
    for j, name in enumerate(SMPLX_JOINT_NAMES):
        side = -1.0 if name.startswith("right") else 1.0
        key = name.replace("right", "left")
        if key in _REST:
            out[j] = np.multiply(_REST[key], (side, 1, 1))
            continue
        finger, k = key[len("left_"):-1], int(key[-1])
        step = (0.025, 0, 0.02) if finger == "thumb" else (0.035, 0, 0)
        out[j] = (np.add(_FINGER_BASE[finger], np.multiply(step, k - 1))) * (side, 1, 1)
    return out


def fake_smplx_body_model(path) -> pathlib.Path:
    """An SMPL-X-format model file whose joints sit where a body's do (55 vertices, identity J_regressor)."""
    path = pathlib.Path(path)
    v = smplx_rest_joints()
    parents = np.array(SMPLX_PARENTS, dtype=np.int64)
    parents[0] = 2**32 - 1
    np.savez(path, v_template=v, shapedirs=np.zeros((55, 3, 20)), J_regressor=np.eye(55),
             kintree_table=np.stack([parents, np.arange(55)]).astype(np.int64),
             posedirs=np.zeros((55, 3, 486)), weights=np.eye(55), f=np.zeros((1, 3), np.uint32))
    return path


def smplx_recording(path, seconds: float = 1.0, fps: int = 30) -> pathlib.Path:
    """A BEAT2-style recording: arms lowered from the T-pose, elbows bent forward and waving."""
    path = pathlib.Path(path)
    t = np.arange(int(round(seconds * fps))) / fps
    poses = np.zeros((len(t), 165))
    names = list(SMPLX_JOINT_NAMES)
    for side, sign in (("left", -1.0), ("right", 1.0)):
        poses[:, 3 * names.index(f"{side}_shoulder") + 2] = sign * 1.2
        poses[:, 3 * names.index(f"{side}_elbow") + 1] = sign * (0.9 + 0.3 * np.sin(2 * np.pi * t))
    trans = np.tile([0.0, 0.95, 0.0], (len(t), 1))
    np.savez(path, poses=poses, trans=trans, betas=np.zeros(10), expressions=np.zeros((len(t), 10)),
             model=np.array("smplx2020"), gender=np.array("neutral"), mocap_frame_rate=np.array(fps))
    return path


def positions_npz(path) -> pathlib.Path:
    """The BEAT stand-in as a positions file (evalsuite's .npz: positions, joint_names, parents, fps)."""
    path = pathlib.Path(path)
    m = beat_standin()
    save_motion(Motion.from_positions(m.positions(), m.joint_names, m.fps, m.parents), path)
    return path


def four_inputs(tmp_path, monkeypatch) -> dict[str, pathlib.Path]:
    """name -> file of each input kind; the SMPL-X model is set through EVALSUITE_SMPLX_MODEL."""
    monkeypatch.setenv("EVALSUITE_SMPLX_MODEL", str(fake_smplx_body_model(tmp_path / "model.npz")))
    genea = tmp_path / "genea2023.bvh"
    save_motion(genea2023_standin(), genea)
    return {"genea2023": genea, "beat": beat_bvh(tmp_path / "beat.bvh"),
            "smplx": smplx_recording(tmp_path / "smplx.npz"), "positions": positions_npz(tmp_path / "pos.npz")}
