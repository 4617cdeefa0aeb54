"""Turning a reference FGD checkpoint (GENEA 2020/2022/2023, Yoon et al. 2020) into a model file.

A GENEA checkpoint is ``torch.save({"pose_dim": D, "n_frames": W, "gen_dict": state_dict})``
of the reference ``EmbeddingNet``; Yoon et al.'s adds ``args`` (an argparse namespace, so it
only loads with ``allow_pickle=True``: pickles can run code, use it only for files you trust)
and has no ``n_frames``. The state dict loads by name into :class:`~evalsuite.learned.network.
EmbeddingNet` (the mapping is the identity, see docs/learned.md); the architecture (window,
channel widths, fc_mu head) is read off the parameter shapes.

The normalisation vectors are not in the checkpoint: GENEA keeps them as literals in its scripts
(shipped here as presets, :mod:`evalsuite.learned.genea_stats`) or in ``*_Mean.npy``/``*_Std.npy``
files. Give a preset name (``genea2020``, ``genea2022_fullbody``, ``genea2022_upperbody``,
``genea2023``), an ``.npz`` with ``mean`` and ``std``, a ``.npy`` of shape ``(2, D)``, or
``MEAN.npy,STD.npy``; Yoon et al. use ``mean_dir_vec`` and no std (std = 1), taken from the
checkpoint's ``args`` when no stats are given.
"""
from __future__ import annotations

import hashlib
import pathlib

import numpy as np
import torch

from evalsuite.errors import InputError
from evalsuite.learned.data import file_sha256
from evalsuite.learned.genea_stats import NOT_PRESETS, STATS_PRESETS
from evalsuite.learned.modelfile import FeatureModel, new_meta
from evalsuite.learned.network import EmbeddingNet, architecture_from_state_dict
from evalsuite.learned.presets import resolve_joint_spec
from evalsuite.learned.representation import REPRESENTATIONS, WINDOW_RULES

# Yoon et al.'s 9 bones over their 10-joint upper body (scripts/utils/data_utils.py dir_vec_pairs).
YOON_BONES = [(0, 1), (1, 2), (2, 3), (1, 4), (4, 5), (5, 6), (1, 7), (7, 8), (8, 9)]


def read_checkpoint(path, allow_pickle: bool = False) -> dict:
    path = pathlib.Path(path)
    if not path.is_file():
        raise InputError("no such checkpoint file", path=path)
    try:
        ckpt = torch.load(path, map_location="cpu", weights_only=not allow_pickle)
    except Exception as exc:  # torch raises many types for foreign, pickled or corrupt files
        hint = ("" if allow_pickle else "; if it holds pickled objects (Yoon et al.'s 'args') and you trust it, "
                "pass --unsafe-pickle")
        raise InputError(f"cannot read the checkpoint ({exc.__class__.__name__}: {str(exc)[:200]}){hint}",
                         path=path) from None
    if isinstance(ckpt, dict) and "gen_dict" in ckpt:
        return ckpt
    if isinstance(ckpt, dict) and ckpt and all(isinstance(v, torch.Tensor) for v in ckpt.values()):
        return {"gen_dict": ckpt}
    raise InputError("expected a GENEA checkpoint: a dict with 'gen_dict' (the state dict), 'pose_dim' and "
                     "'n_frames', or a bare state dict", path=path)


def stats_preset(name: str) -> tuple[np.ndarray, np.ndarray, str]:
    """Mean, std (float64, shape (D,)) and a provenance line of a shipped preset, e.g. ``genea2023``."""
    if name in NOT_PRESETS:
        raise InputError(f"--stats {name}: {NOT_PRESETS[name]}")
    if name not in STATS_PRESETS:
        raise InputError(f"unknown stats preset {name!r}; expected one of {', '.join(STATS_PRESETS)} or a file")
    p = STATS_PRESETS[name]
    mean, std = np.asarray(p["mean"], dtype=np.float64), np.asarray(p["std"], dtype=np.float64)
    return mean, std, f"preset {name} ({p['what']}; {mean.size} values) from {p['source']}"


def stats_sha256(mean: np.ndarray, std: np.ndarray) -> str:
    """SHA-256 of the vectors themselves (little-endian float64 mean, then std): the same for a preset
    and for a file holding its numbers."""
    digest = hashlib.sha256()
    for vec in (mean, std):
        digest.update(np.ascontiguousarray(vec, dtype="<f8").tobytes())
    return digest.hexdigest()


def read_stats(spec) -> tuple[np.ndarray, np.ndarray]:
    """Mean and std vectors from a preset name, ``.npz`` (mean, std), ``.npy`` (2, D) or ``"MEAN.npy,STD.npy"``."""
    text = str(spec)
    if text in STATS_PRESETS or text in NOT_PRESETS:
        mean, std, _ = stats_preset(text)
        return mean, std
    if "," in text:
        parts = [pathlib.Path(p.strip()) for p in text.split(",")]
        if len(parts) != 2:
            raise InputError(f"expected MEAN.npy,STD.npy, got {text!r}")
        return _load_vector(parts[0]), _load_vector(parts[1])
    path = pathlib.Path(text)
    if not path.is_file():
        raise InputError(f"no such stats file, and not a preset ({', '.join(STATS_PRESETS)})", path=path)
    if path.suffix.lower() == ".npz":
        with np.load(path, allow_pickle=False) as data:
            if "mean" not in data.files or "std" not in data.files:
                raise InputError(f"expected arrays 'mean' and 'std'; the archive has {data.files}", path=path)
            return np.asarray(data["mean"], float).ravel(), np.asarray(data["std"], float).ravel()
    arr = _load_vector(path, flatten=False)
    if arr.ndim != 2 or arr.shape[0] != 2:
        raise InputError(f"a stats .npy must have shape (2, D) (mean row, std row), got {arr.shape}", path=path)
    return arr[0], arr[1]


def _load_vector(path, flatten: bool = True) -> np.ndarray:
    path = pathlib.Path(path)
    if not path.is_file():
        raise InputError("no such stats file", path=path)
    try:
        arr = np.asarray(np.load(path, allow_pickle=False), dtype=np.float64)
    except Exception as exc:  # numpy raises many types for corrupt files
        raise InputError(f"not a readable .npy array ({exc})", path=path) from None
    return arr.ravel() if flatten else arr


def import_checkpoint(checkpoint, *, joints, stats=None, fps: float = 30.0, stride: int | None = None,
                      convention: str | None = None, representation: str = "positions", bones=None,
                      window_rule: str = "genea", allow_pickle: bool = False) -> FeatureModel:
    """A :class:`FeatureModel` from a reference checkpoint and its normalisation vectors.

    Args:
        checkpoint: path of the ``.bin``/``.pt`` checkpoint.
        joints: the joints in the order of the checkpoint's input (preset, ``"A,B,C"``, list);
            ``genea2023`` also sets the PyMO convention.
        stats: normalisation vectors: a preset name or a file (see module docstring); required except
            for Yoon et al.
        fps: the frame rate the extractor was trained at (GENEA: 30; Yoon et al./TED: 15).
        stride: window step for scoring (default window // 2, as the GENEA scripts).
        representation: ``positions`` or ``bone_directions`` (with ``bones`` as name pairs;
            default Yoon et al.'s 9 bones over the 10 given joints).
        window_rule: ``genea`` (default: the reference scripts' windows) or ``complete``.
    """
    path = pathlib.Path(checkpoint)
    ckpt = read_checkpoint(path, allow_pickle)
    state = {k: v for k, v in ckpt["gen_dict"].items()}
    try:
        arch = architecture_from_state_dict(state, ckpt.get("n_frames"))
    except KeyError as exc:
        raise InputError(f"the state dict has no parameter {exc.args[0]!r}: not laid out like the GENEA "
                         "EmbeddingNet (see docs/learned.md for the expected names)", path=path) from None
    except ValueError as exc:
        raise InputError(str(exc), path=path) from None
    if "pose_dim" in ckpt and int(ckpt["pose_dim"]) != arch.pose_dim:
        raise InputError(f"pose_dim {ckpt['pose_dim']} disagrees with the first layer's {arch.pose_dim} inputs",
                         path=path)
    net = EmbeddingNet(arch)
    result = net.load_state_dict(state, strict=False)
    if result.missing_keys or result.unexpected_keys:
        raise InputError(f"the state dict does not fit the GENEA layout: missing {result.missing_keys[:6]}, "
                         f"unexpected {result.unexpected_keys[:6]}", path=path)

    if representation not in REPRESENTATIONS:
        raise InputError(f"unknown representation {representation!r}; expected one of {', '.join(REPRESENTATIONS)}")
    if window_rule not in WINDOW_RULES:
        raise InputError(f"unknown window rule {window_rule!r}; expected one of {', '.join(WINDOW_RULES)}")
    names, preset_convention = resolve_joint_spec(joints)
    rep: dict[str, object] = {"kind": representation, "joints": names, "convention": convention or preset_convention}
    if representation == "bone_directions":
        if bones is None:
            if len(names) != 10:
                raise InputError(f"Yoon et al.'s bones need their 10 joints in order; got {len(names)} joints "
                                 "(or give the bones explicitly)")
            bones = [[names[a], names[b]] for a, b in YOON_BONES]
        unknown = [n for b in bones for n in b if n not in names]
        if unknown:
            raise InputError(f"bones name joints that are not in the joint list: {unknown}")
        rep["bones"] = [list(b) for b in bones]
        expected = 3 * len(bones)
        what = f"{len(bones)} bones x 3"
    else:
        expected = 3 * len(names)
        what = f"{len(names)} joints x 3"
    if expected != arch.pose_dim:
        raise InputError(f"the checkpoint takes {arch.pose_dim} values per frame but {what} = {expected}",
                         path=path)

    stats_source = None
    is_preset = stats is not None and (str(stats) in STATS_PRESETS or str(stats) in NOT_PRESETS)
    if is_preset:
        mean, std, stats_source = stats_preset(str(stats))
    elif stats is not None:
        mean, std = read_stats(stats)
        stats_source = str(stats)
    elif representation == "bone_directions" and "args" in ckpt and hasattr(ckpt["args"], "mean_dir_vec"):
        mean = np.asarray(ckpt["args"].mean_dir_vec, dtype=np.float64).ravel()
        std = np.ones_like(mean)
        stats_source = "checkpoint args.mean_dir_vec (std 1)"
    else:
        raise InputError("normalisation vectors are needed: --stats PRESET (" + ", ".join(STATS_PRESETS)
                         + ") or a file (.npz with mean/std, .npy of shape (2, D) or MEAN.npy,STD.npy)")
    if mean.shape != (arch.pose_dim,) or std.shape != (arch.pose_dim,):
        what_stats = f"--stats {stats}" if is_preset else "stats"
        raise InputError(f"{what_stats} must have {arch.pose_dim} values each (the checkpoint's input), got mean "
                         f"{mean.shape[0]} and std {std.shape[0]}", path=path)
    if not (std > 0).all():
        raise InputError(f"std has {(std <= 0).sum()} non-positive value(s); the reference code would divide by them")

    if arch.variational_head:
        family = "yoon2020"
    else:
        family = "genea2022/2023" if tuple(arch.conv_channels) == (128, 64) else "genea2020"
    provenance = {"kind": "imported", "source_format": family, "checkpoint_file": path.name,
                  "checkpoint_sha256": file_sha256(path), "stats": stats_source,
                  "stats_sha256": None if stats is None or is_preset or "," in str(stats) else file_sha256(stats)}
    normalization = {"source": stats_source, "values_sha256": stats_sha256(mean, std)}
    stride = int(stride or max(arch.window // 2, 1))
    meta = new_meta(arch, rep, fps, stride, window_rule, normalization, provenance, None)
    return FeatureModel(net, meta, mean, std)
