"""SMPL-X joint positions from a body-model file the user supplies, in numpy (no ``smplx`` import, no download).

The positions of the 55 joints need the rest joints of the speaker's body shape, which only the licensed SMPL-X
model file gives (users register at https://smpl-x.is.tue.mpg.de and download e.g. ``SMPLX_NEUTRAL_2020.npz``):

    J(β) = J_regressor · (v_template + shapedirs[..., :nβ] · β)                        (55, 3), metres

with ``J_regressor`` (55, V), ``v_template`` (V, 3), ``shapedirs`` (V, 3, S). Pose blend shapes do not move
the joints, so forward kinematics of J(β) gives the model's joints exactly: for joint j with parent p,

    G_j = G_p · [R_j | J_j − J_p],   G_root = [R_0 | J_0],   position_j = translation of G_j + trans

where R_j is the rotation matrix of joint j's axis-angle (Rodrigues). Expressions ψ (T, E) move the rest joints
by J_regressor · (expression dirs · ψ) in ``full`` mode (the expression dirs are ``shapedirs[..., 300:300+E]``
in models with 300 shape components, ``[..., 10:20]`` in the older 10 + 10 models).

Modes (:data:`MODES`): ``full`` applies everything; ``leaderboard`` is the GENEA Leaderboard's convention:
global orientation, translation, jaw, eyes and expressions zeroed, betas those of the ground truth (pass them).
"""
from __future__ import annotations

import hashlib
import os
import pathlib
import zipfile
from dataclasses import dataclass

import numpy as np

from evalsuite.errors import InputError
from evalsuite.motion.smplx import SmplxData
from evalsuite.motion.smplx_layout import JAW_EYES, N_JOINTS, SMPLX_PARENTS

__all__ = ["MODEL_ENV", "REGISTER_URL", "MODES", "SmplxModelMissing", "resolve_model_path", "optional_model_path",
           "rest_joints", "smplx_positions", "smplx_fk", "BodyModel", "load_body_model", "model_missing_message"]

MODEL_ENV = "EVALSUITE_SMPLX_MODEL"
REGISTER_URL = "https://smpl-x.is.tue.mpg.de"
MODES = ("full", "leaderboard")
SHAPE_SPACE = 300


class SmplxModelMissing(InputError):
    """Positions were needed but no SMPL-X model file was given."""


def model_missing_message(what: str = "this") -> str:
    """The one line said when positions are needed and no model file is known."""
    return (f"{what} needs SMPL-X joint positions: pass --smplx-model PATH (or set {MODEL_ENV}) to your SMPL-X "
            f"model .npz, e.g. SMPLX_NEUTRAL_2020.npz (register at {REGISTER_URL} to download it)")


def resolve_model_path(option: str | os.PathLike[str] | None, *, what: str = "this") -> pathlib.Path:
    """The model file from ``--smplx-model`` (``option``) or else the environment variable ``EVALSUITE_SMPLX_MODEL``.

    Raises SmplxModelMissing (one line naming both and where to register) when neither is set, and InputError
    when the file named does not exist.
    """
    value = os.fspath(option) if option is not None else os.environ.get(MODEL_ENV, "").strip()
    if not value:
        raise SmplxModelMissing(model_missing_message(what))
    path = pathlib.Path(value).expanduser()
    if not path.is_file():
        source = "--smplx-model" if option is not None else MODEL_ENV
        raise InputError(f"no such SMPL-X model file (from {source})", path=path)
    return path


def optional_model_path(option: str | os.PathLike[str] | None) -> pathlib.Path | None:
    """Like :func:`resolve_model_path`, but None when neither the option nor the environment names a file."""
    if option is None and not os.environ.get(MODEL_ENV, "").strip():
        return None
    return resolve_model_path(option)


@dataclass(frozen=True)
class BodyModel:
    """What positions need from a model file: ``J_regressor`` applied to the template and the blend shapes."""

    sha256: str
    j_template: np.ndarray      # (55, 3) J_regressor · v_template
    n_shape: int                # shape components
    n_expr: int                 # expression components
    path: str
    j_shapedirs: np.ndarray     # (55, 3, S) J_regressor · shapedirs (shape, then expression components)

    def shape_joints(self, betas: np.ndarray) -> np.ndarray:
        """J(β) (55, 3): the formula of the module docstring, J_regressor · (v_template + shapedirs · β), with
        J_regressor applied first (the same sum; the model file is read once, not once per speaker)."""
        betas = np.asarray(betas, dtype=np.float64)
        if not len(betas):
            return np.array(self.j_template)
        joints: np.ndarray = self.j_template + self.j_shapedirs[..., :len(betas)] @ betas
        return joints


_MODELS: dict[tuple[str, int, int], BodyModel] = {}
_JOINTS: dict[tuple[str, bytes], np.ndarray] = {}


def _sha256(path: pathlib.Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _arrays(path: pathlib.Path, keys: tuple[str, ...]) -> dict[str, np.ndarray]:
    if path.suffix.lower() == ".pkl":
        raise InputError("pickled SMPL-X model files are not read; use the .npz model file of the SMPL-X download "
                         "(e.g. SMPLX_NEUTRAL_2020.npz)", path=path)
    try:
        with np.load(path, allow_pickle=False) as npz:
            missing = [k for k in keys if k not in npz.files]
            if missing:
                raise InputError(f"not an SMPL-X model file: missing key {missing[0]!r} (expected {', '.join(keys)})",
                                 path=path)
            out = {}
            for k in keys:
                try:
                    out[k] = np.asarray(npz[k])
                except ValueError:
                    raise InputError("holds pickled Python objects; evalsuite reads plain arrays only (use the "
                                     ".npz model file of the SMPL-X download)", path=path, field=k) from None
            return out
    except InputError:
        raise
    except (zipfile.BadZipFile, ValueError, OSError, EOFError) as exc:
        raise InputError(f"not a readable SMPL-X model .npz ({exc})", path=path) from None


def _shape_split(n_cols: int) -> tuple[int, int]:
    """(shape components, expression components) of a shapedirs with ``n_cols`` columns."""
    if n_cols >= SHAPE_SPACE:
        return SHAPE_SPACE, n_cols - SHAPE_SPACE
    return n_cols // 2, n_cols - n_cols // 2


def load_body_model(model_path: str | os.PathLike[str]) -> BodyModel:
    """Check a model file and keep what positions need (cached per file path, size and time)."""
    path = pathlib.Path(model_path)
    if not path.is_file():
        raise InputError("no such SMPL-X model file", path=path)
    st = path.stat()
    key = (os.fspath(path.resolve()), st.st_size, st.st_mtime_ns)
    if key in _MODELS:
        return _MODELS[key]
    arr = _arrays(path, ("v_template", "shapedirs", "J_regressor", "kintree_table"))
    v, sd, jr, kt = arr["v_template"], arr["shapedirs"], arr["J_regressor"], arr["kintree_table"]
    if v.ndim != 2 or v.shape[1] != 3:
        raise InputError(f"found shape {v.shape}; expected (V, 3)", path=path, field="v_template")
    n_verts = v.shape[0]
    if jr.shape != (N_JOINTS, n_verts):
        hint = " (an SMPL-H or SMPL model, not SMPL-X)" if jr.ndim == 2 and jr.shape[0] in (24, 52) else ""
        raise InputError(f"found shape {jr.shape}; expected ({N_JOINTS}, {n_verts}){hint}", path=path,
                         field="J_regressor")
    if sd.ndim != 3 or sd.shape[:2] != (n_verts, 3):
        raise InputError(f"found shape {sd.shape}; expected ({n_verts}, 3, S)", path=path, field="shapedirs")
    parents = kt[0].astype(np.int64) if kt.ndim == 2 and kt.shape == (2, N_JOINTS) else None
    if parents is None or list(parents[1:]) != list(SMPLX_PARENTS[1:]):
        raise InputError(f"found shape {kt.shape}; expected (2, {N_JOINTS}) with the SMPL-X parent table",
                         path=path, field="kintree_table")
    n_shape, n_expr = _shape_split(sd.shape[2])
    jr = jr.astype(np.float64)
    j_dirs = (jr @ sd.reshape(n_verts, -1).astype(np.float64)).reshape(N_JOINTS, 3, sd.shape[2])
    model = BodyModel(_sha256(path), jr @ v.astype(np.float64), n_shape, n_expr, os.fspath(path), j_dirs)
    _MODELS[key] = model
    return model


def rest_joints(model_path: str | os.PathLike[str], betas: np.ndarray,
                *, cache_dir: str | os.PathLike[str] | None = None) -> np.ndarray:
    """J(β), the 55 rest-joint positions (55, 3) in metres for shape coefficients ``betas`` (B,).

    Cached in memory per (model file hash, β); with ``cache_dir`` also as ``.npy`` files there (beside the
    user's data, never in the package).
    """
    model = load_body_model(model_path)
    betas = np.asarray(betas, dtype=np.float64).ravel()
    if len(betas) > model.n_shape:
        raise InputError(f"{len(betas)} betas but this model has {model.n_shape} shape components; use a model "
                         f"with {len(betas)} or more (SMPLX_NEUTRAL_2020.npz has 300)", path=model.path,
                         field="shapedirs")
    key = (model.sha256, betas.tobytes())
    if key in _JOINTS:
        return np.array(_JOINTS[key])
    disk = None
    if cache_dir is not None:
        disk = pathlib.Path(cache_dir) / (f"smplx_rest_joints_{model.sha256[:16]}_"
                                          f"{hashlib.sha256(betas.tobytes()).hexdigest()[:16]}.npy")
        if disk.is_file():
            joints: np.ndarray = np.asarray(np.load(disk, allow_pickle=False), dtype=np.float64)
            _JOINTS[key] = joints
            return np.array(joints)
    joints = np.asarray(model.shape_joints(betas), dtype=np.float64)
    if disk is not None:
        disk.parent.mkdir(parents=True, exist_ok=True)
        np.save(disk, joints)
    _JOINTS[key] = joints
    return np.array(joints)


def _expression_joints(model: BodyModel, n_expr: int) -> np.ndarray:
    """(55, 3, E): J_regressor · expression dirs, the joints' motion per expression coefficient."""
    if n_expr > model.n_expr:
        raise InputError(f"{n_expr} expression coefficients but this model has {model.n_expr}; use "
                         "SMPLX_NEUTRAL_2020.npz (100) or the leaderboard mode (expressions zeroed)",
                         path=model.path, field="shapedirs")
    return model.j_shapedirs[..., model.n_shape:model.n_shape + n_expr]


# Frames computed together: (55, 3, 3, block) temporaries stay small, and frames-last arrays make the 3x3
# products long vector operations (several times faster than batched small matmuls).
BLOCK_FRAMES = 4096
_HAS_CHILDREN = frozenset(p for p in SMPLX_PARENTS if p >= 0)


def smplx_fk(rotvecs: np.ndarray, rest: np.ndarray, trans: np.ndarray | None = None, *,
             block_frames: int = BLOCK_FRAMES) -> np.ndarray:
    """Joint positions (T, 55, 3) from axis-angle ``rotvecs`` (T, 55, 3), rest joints ``rest`` (55, 3) or
    (T, 55, 3) and ``trans`` (T, 3): the chain of the module docstring, vectorised over frames (in blocks of
    ``block_frames``; results do not depend on it)."""
    from scipy.spatial.transform import Rotation

    rotvecs = np.asarray(rotvecs, dtype=np.float64).reshape(len(rotvecs), N_JOINTS, 3)
    rest = np.asarray(rest, dtype=np.float64)
    n = len(rotvecs)
    out = np.empty((n, N_JOINTS, 3))
    for start in range(0, n, block_frames):
        stop = min(n, start + block_frames)
        mats = Rotation.from_rotvec(rotvecs[start:stop].reshape(-1, 3)).as_matrix()
        mats = np.ascontiguousarray(mats.reshape(stop - start, N_JOINTS, 3, 3).transpose(1, 2, 3, 0))
        per_frame = rest.ndim == 3
        r = np.ascontiguousarray(rest[start:stop].transpose(1, 2, 0)) if per_frame else rest   # (55, 3[, B])
        world = np.empty_like(mats)                          # (55, 3, 3, B)
        pos = np.empty((N_JOINTS, 3, stop - start))
        for j, p in enumerate(SMPLX_PARENTS):
            if p < 0:
                world[j] = mats[j]
                pos[j] = r[j] if per_frame else r[j][:, None]
                continue
            offset = r[j] - r[p]
            pos[j] = pos[p] + (np.einsum("ijt,jt->it", world[p], offset) if per_frame
                               else np.einsum("ijt,j->it", world[p], offset))
            if j in _HAS_CHILDREN:
                world[j] = np.einsum("ijt,jkt->ikt", world[p], mats[j])
        out[start:stop] = pos.transpose(2, 0, 1)
    if trans is not None:
        out += np.asarray(trans, dtype=np.float64)[:, None, :]
    return out


def smplx_positions(data: SmplxData, model_path: str | os.PathLike[str] | None, *, mode: str = "full",
                    betas: np.ndarray | None = None, cache_dir: str | os.PathLike[str] | None = None) -> np.ndarray:
    """Joint positions (T, 55, 3) in metres.

    Args:
        data: the recording.
        model_path: the user's SMPL-X model ``.npz`` (None: ``EVALSUITE_SMPLX_MODEL``; neither: the one-line
            SmplxModelMissing error).
        mode: ``"full"`` (orientation, translation, jaw, eyes, expressions applied) or ``"leaderboard"``
            (those zeroed, as the GENEA Leaderboard computes positions).
        betas: shape coefficients to use instead of ``data.betas`` (the Leaderboard: the ground truth's).
        cache_dir: where J(β) may be cached on disk (see :func:`rest_joints`).
    """
    if mode not in MODES:
        raise InputError(f"unknown positions mode {mode!r}; expected one of {', '.join(MODES)}", field="mode")
    path = resolve_model_path(model_path)
    shape = data.betas if betas is None else np.asarray(betas, dtype=np.float64).ravel()
    rest: np.ndarray = rest_joints(path, shape, cache_dir=cache_dir)
    rotvecs = data.rotvecs
    if mode == "leaderboard":
        rotvecs = rotvecs.copy()
        rotvecs[:, [0, *JAW_EYES]] = 0.0
        return smplx_fk(rotvecs, rest)
    expr = data.expressions
    if expr is not None and expr.shape[1] and np.any(expr):
        rest = rest + np.einsum("jce,te->tjc", _expression_joints(load_body_model(path), expr.shape[1]), expr)
    return smplx_fk(rotvecs, rest, data.trans)
