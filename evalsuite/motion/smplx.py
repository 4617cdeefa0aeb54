"""SMPL-X motion files (BEAT2, the GENEA Leaderboard, AMASS-style ``.npz``): reading, writing, detection.

A file is an ``.npz`` archive with:

==================  ============================  ==============================================================
key                 shape                         meaning
==================  ============================  ==============================================================
``poses``           (T, 165) or (T, 55, 3)        axis-angle rotation of the 55 SMPL-X joints (radians), in
                                                  :data:`~evalsuite.motion.smplx_layout.SMPLX_JOINT_NAMES` order;
                                                  joint 0 is the global orientation
                    (T, 156) or (T, 52, 3)        the SMPL-H layout: the same joints without jaw and eyes
                                                  (read with jaw and eyes at zero, written back as 156)
``trans``           (T, 3)                        translation of the body (metres); optional (zeros)
``betas``           (B,) or (1, B)                shape coefficients (BEAT2: 300); optional (none)
``expressions``     (T, E)                        face expression coefficients (BEAT2: 100); optional
``model``           text                          e.g. ``smplx2020``; optional
``gender``          text                          ``neutral``, ``male`` or ``female``; optional
``mocap_frame_rate``  scalar                      frames per second (AMASS spells it ``mocap_framerate``)
==================  ============================  ==============================================================

Any other key is kept as it is (``SmplxData.extra``) and written back. Arrays must be plain numbers
(no pickled objects). NaN in ``poses``, ``trans``, ``betas`` or ``expressions`` is an error naming the key,
frame and joint unless ``nan="zero"`` (what the GENEA Leaderboard's scripts do: NaN read as 0); infinities
are always an error. :func:`write_smplx` writes what :func:`read_smplx` read with the same keys, key order,
shapes and dtypes, so an unchanged file round-trips with byte-identical arrays.
"""
from __future__ import annotations

import math
import os
import pathlib
import zipfile
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from evalsuite.errors import InputError
from evalsuite.motion.smplx_layout import (
    JAW_EYES,
    N_JOINTS,
    POSE_WIDTH,
    SMPLH_JOINTS,
    SMPLH_POSE_WIDTH,
    SMPLX_JOINT_NAMES,
)

__all__ = ["SmplxData", "read_smplx", "write_smplx", "is_smplx_npz", "FPS_KEYS", "NAN_MODES"]

FPS_KEYS = ("mocap_frame_rate", "mocap_framerate")
NAN_MODES = ("error", "zero")
_KNOWN = ("poses", "trans", "betas", "expressions", "model", "gender") + FPS_KEYS
_EXPECTED_POSES = ("(T, 165) or (T, 55, 3) for SMPL-X (55 joints x axis-angle), or (T, 156) or (T, 52, 3) for "
                   "the SMPL-H layout (52 joints: no jaw and eyes)")


@dataclass(eq=False)
class SmplxData:
    """One SMPL-X recording (compared by identity: its fields are arrays).

    Attributes:
        poses: ``(T, 165)`` float64, axis-angle per joint in radians (joint ``j`` is columns ``3j:3j+3``).
        trans: ``(T, 3)`` float64, metres.
        betas: ``(B,)`` float64 shape coefficients.
        expressions: ``(T, E)`` float64 or None.
        model, gender: as stored (``""`` when absent).
        fps: frames per second.
        source: the file read, or None.
        extra: other keys of the file, unchanged.
        stored: how the file stored things (dtypes, shapes, key order, absent keys), used by
            :func:`write_smplx` to write the same layout back; empty for data made in code.
    """

    poses: np.ndarray
    trans: np.ndarray
    betas: np.ndarray
    expressions: np.ndarray | None = None
    model: str = ""
    gender: str = ""
    fps: float = 30.0
    source: str | None = None
    extra: dict[str, np.ndarray] = field(default_factory=dict)
    stored: dict[str, Any] = field(default_factory=dict)

    @property
    def n_frames(self) -> int:
        return int(self.poses.shape[0])

    @property
    def duration(self) -> float:
        """Seconds (``n_frames / fps``)."""
        return self.n_frames / self.fps

    @property
    def rotvecs(self) -> np.ndarray:
        """``(T, 55, 3)`` view of :attr:`poses`."""
        return self.poses.reshape(self.n_frames, N_JOINTS, 3)


def is_smplx_npz(path: str | os.PathLike[str]) -> bool:
    """True for a readable ``.npz`` archive holding a ``poses`` array (looks at the archive's names only)."""
    path = pathlib.Path(path)
    if path.suffix.lower() != ".npz" or not path.is_file():
        return False
    try:
        with zipfile.ZipFile(path) as zf:
            return "poses.npy" in zf.namelist()
    except (zipfile.BadZipFile, OSError):
        return False


def _text(value: np.ndarray, key: str, path: pathlib.Path) -> str:
    if value.ndim > 1 or value.size != 1 or value.dtype.kind not in "USO":
        raise InputError(f"expected one text value, found dtype {value.dtype} and shape {value.shape}",
                         path=path, field=key)
    item = value.reshape(()).item()
    return item.decode("utf-8", "replace") if isinstance(item, bytes) else str(item)


def _floats(value: np.ndarray, key: str, path: pathlib.Path) -> np.ndarray:
    if value.dtype.kind != "f":
        raise InputError(f"expected floating-point numbers, found dtype {value.dtype}", path=path, field=key)
    return value.astype(np.float64)


def _finite(arr: np.ndarray, key: str, path: pathlib.Path, nan: str, per_frame: bool) -> np.ndarray:
    bad = ~np.isfinite(arr)
    if not bad.any():
        return arr
    inf = np.isinf(arr)
    where = np.argwhere(inf if inf.any() else bad)[0]
    if per_frame and key == "poses":
        pos = f"frame {where[0]}, joint {SMPLX_JOINT_NAMES[where[1] // 3]!r}"
    else:
        pos = f"frame {where[0]}" if per_frame else f"index {where[0]}"
    if inf.any():
        raise InputError(f"infinite value at {pos}", path=path, field=key)
    if nan == "error":
        raise InputError(f"NaN at {pos} ({int(bad.sum())} NaN values in all); pass nan='zero' to read NaN as 0, "
                         "as the GENEA Leaderboard's scripts do", path=path, field=key)
    return np.where(bad, 0.0, arr)


def _poses(raw: np.ndarray, path: pathlib.Path) -> tuple[np.ndarray, int]:
    """(T, 165) float64 poses and the width the file stored (165 or 156)."""
    arr = _floats(raw, "poses", path)
    if arr.ndim == 3 and arr.shape[2] == 3 and arr.shape[1] in (N_JOINTS, len(SMPLH_JOINTS)):
        arr = arr.reshape(len(arr), -1)
    if arr.ndim != 2 or arr.shape[1] not in (POSE_WIDTH, SMPLH_POSE_WIDTH):
        raise InputError(f"found shape {raw.shape}; expected {_EXPECTED_POSES}", path=path, field="poses")
    if arr.shape[0] == 0:
        raise InputError("no frames (shape (0, ...))", path=path, field="poses")
    width = arr.shape[1]
    if width == SMPLH_POSE_WIDTH:
        full = np.zeros((len(arr), N_JOINTS, 3))
        full[:, list(SMPLH_JOINTS)] = arr.reshape(len(arr), -1, 3)
        arr = full.reshape(len(arr), POSE_WIDTH)
    return arr, width


def _fps(contents: dict[str, np.ndarray], path: pathlib.Path) -> tuple[float, str]:
    keys = [k for k in FPS_KEYS if k in contents]
    if not keys:
        raise InputError(f"no frame rate: expected a key {FPS_KEYS[0]!r} (or {FPS_KEYS[1]!r}, as AMASS writes it); "
                         f"the archive has {sorted(contents)}", path=path)
    key = keys[0]
    raw = contents[key]
    try:
        value = float(raw.reshape(()).item()) if raw.size == 1 and raw.dtype.kind in "fiu" else math.nan
    except (TypeError, ValueError):
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise InputError(f"expected one positive number (frames per second), found {raw!r}", path=path, field=key)
    if len(keys) == 2:
        other = contents[keys[1]]
        if other.size != 1 or other.dtype.kind not in "fiu" or float(other.reshape(()).item()) != value:
            raise InputError(f"both {keys[0]!r} ({value:g}) and {keys[1]!r} ({other!r}) are given and disagree",
                             path=path)
    return value, key


def read_smplx(path: str | os.PathLike[str], *, nan: str = "error") -> SmplxData:
    """Read an SMPL-X ``.npz`` (see the module docstring for keys, shapes and units).

    Args:
        path: the file.
        nan: ``"error"`` (default): NaN is an InputError naming key, frame and joint; ``"zero"``: NaN read as 0.

    Raises:
        InputError naming the file, the key, the shape or dtype found and what was expected.
    """
    if nan not in NAN_MODES:
        raise ValueError(f"nan must be one of {NAN_MODES}, got {nan!r}")
    path = pathlib.Path(path)
    if not path.exists():
        raise InputError("no such file", path=path)
    try:
        with np.load(path, allow_pickle=False) as archive:
            order = list(archive.files)
            contents: dict[str, np.ndarray] = {}
            for key in order:
                try:
                    contents[key] = archive[key]
                except ValueError:
                    raise InputError("holds pickled Python objects; evalsuite reads plain arrays only",
                                     path=path, field=key) from None
            compressed = _is_compressed(path)
    except InputError:
        raise
    except (zipfile.BadZipFile, ValueError, OSError, EOFError) as exc:
        raise InputError(f"not a readable .npz archive ({exc})", path=path) from None
    if "poses" not in contents:
        raise InputError(f"missing key 'poses' (T, 165); the archive has {sorted(contents)}", path=path)
    poses, width = _poses(contents["poses"], path)
    n = len(poses)
    poses = _finite(poses, "poses", path, nan, True)
    fps, fps_key = _fps(contents, path)
    stored: dict[str, Any] = {"order": order, "pose_width": width, "compressed": compressed, "fps_key": fps_key,
                              "raw": {k: contents[k] for k in ("model", "gender") + FPS_KEYS if k in contents},
                              "dtypes": {k: contents[k].dtype for k in contents},
                              "shapes": {k: contents[k].shape for k in contents}}
    trans = np.zeros((n, 3))
    if "trans" in contents:
        trans = _floats(contents["trans"], "trans", path)
        if trans.shape != (n, 3):
            raise InputError(f"found shape {contents['trans'].shape}; expected ({n}, 3) (one x, y, z per frame of "
                             "'poses')", path=path, field="trans")
        trans = _finite(trans, "trans", path, nan, True)
    betas = np.zeros(0)
    if "betas" in contents:
        betas = _floats(contents["betas"], "betas", path)
        if betas.ndim == 2 and betas.shape[0] == 1:
            betas = betas[0]
        if betas.ndim != 1:
            raise InputError(f"found shape {contents['betas'].shape}; expected (B,) or (1, B)", path=path,
                             field="betas")
        betas = _finite(betas, "betas", path, nan, False)
    expressions = None
    if "expressions" in contents:
        expressions = _floats(contents["expressions"], "expressions", path)
        if expressions.ndim != 2 or len(expressions) != n:
            raise InputError(f"found shape {contents['expressions'].shape}; expected ({n}, E) (one row per frame "
                             "of 'poses')", path=path, field="expressions")
        expressions = _finite(expressions, "expressions", path, nan, True)
    model = _text(contents["model"], "model", path) if "model" in contents else ""
    gender = _text(contents["gender"], "gender", path) if "gender" in contents else ""
    extra = {k: v for k, v in contents.items() if k not in _KNOWN}
    return SmplxData(poses, trans, betas, expressions, model, gender, fps, os.fspath(path), extra, stored)


def _is_compressed(path: pathlib.Path) -> bool:
    with zipfile.ZipFile(path) as zf:
        return any(info.compress_type != zipfile.ZIP_STORED for info in zf.infolist())


def _cast(arr: np.ndarray, key: str, stored: dict[str, Any]) -> np.ndarray:
    dtype = stored.get("dtypes", {}).get(key)
    shape = stored.get("shapes", {}).get(key)
    out = arr.astype(dtype) if dtype is not None else arr
    return out.reshape(shape) if shape is not None and int(np.prod(shape)) == out.size else out


def write_smplx(path: str | os.PathLike[str], data: SmplxData) -> None:
    """Write ``data`` as an SMPL-X ``.npz``.

    Data read by :func:`read_smplx` is written with the file's keys, order, dtypes and shapes (a 156-wide
    file stays 156 wide, which needs jaw and eyes at zero); data made in code gets ``poses`` (T, 165),
    ``trans``, ``betas``, ``expressions`` (when set), ``model``, ``gender`` and ``mocap_frame_rate``.
    """
    path = pathlib.Path(path)
    stored = data.stored
    n = data.n_frames
    poses = np.asarray(data.poses, dtype=np.float64)
    if poses.shape != (n, POSE_WIDTH):
        raise InputError(f"poses must have shape (T, {POSE_WIDTH}), got {poses.shape}", path=path, field="poses")
    if stored.get("pose_width") == SMPLH_POSE_WIDTH:
        rot = poses.reshape(n, N_JOINTS, 3)
        if np.any(rot[:, list(JAW_EYES)]):
            raise InputError("the file was 156 wide (no jaw and eyes) but the jaw or eye rotations are not zero; "
                             "clear data.stored to write all 165 columns", path=path, field="poses")
        poses = rot[:, list(SMPLH_JOINTS)].reshape(n, SMPLH_POSE_WIDTH)
    raw = stored.get("raw", {})
    fps_key = stored.get("fps_key", FPS_KEYS[0])
    fps_raw = raw.get(fps_key)
    if fps_raw is None or float(fps_raw.reshape(()).item()) != data.fps:
        fps_raw = np.array(int(data.fps)) if float(data.fps).is_integer() else np.array(float(data.fps))
    arrays: dict[str, np.ndarray] = {"poses": _cast(poses, "poses", stored)}
    order = stored.get("order") or ["poses", "trans", "betas", "expressions", "model", "gender", fps_key]
    for key in ("trans", "betas"):
        if key in order:
            arrays[key] = _cast(np.asarray(getattr(data, key), dtype=np.float64), key, stored)
    if data.expressions is not None:
        arrays["expressions"] = _cast(np.asarray(data.expressions, dtype=np.float64), "expressions", stored)
    for key in ("model", "gender"):
        text = getattr(data, key)
        old = raw.get(key)
        if key in order or text:
            arrays[key] = old if old is not None and _text(old, key, path) == text else np.array(text)
    arrays[fps_key] = fps_raw
    arrays.update(data.extra)
    ordered = {k: arrays[k] for k in order if k in arrays}
    ordered.update({k: v for k, v in arrays.items() if k not in ordered})
    with open(path, "wb") as fh:
        if stored.get("compressed"):
            np.savez_compressed(fh, **ordered)  # type: ignore[arg-type]  # (numpy's stub: **arrays vs allow_pickle)
        else:
            np.savez(fh, **ordered)  # type: ignore[arg-type]
