"""The self-describing model file and the feature function.

A model file (``torch.save`` of plain dicts, lists, numbers, strings and tensors, so it loads
with ``torch.load(weights_only=True)`` and never runs pickled code) holds::

    format, format_version
    meta:        architecture, representation (kind, joints, bones, convention), fps, window,
                 stride, window_rule, normalization (where mean/std came from), training
                 (seed, epochs, losses, data hashes) or import provenance, evalsuite_version,
                 seed, created_utc, content_hash
    state_dict:  the network's parameters under the reference names (see network.py)
    mean, std:   float64 normalisation vectors (D,)

``content_hash`` is the SHA-256 of everything except ``created_utc`` and the hash itself
(canonical JSON of ``meta`` + every tensor's name, dtype, shape and bytes), so two trainings
with the same data and seed give the same hash. It is checked on load and printed with
every FGD.
"""
from __future__ import annotations

import contextlib
import datetime
import hashlib
import io
import json
import os
import pathlib

import numpy as np
import torch

from evalsuite._version import __version__
from evalsuite.errors import InputError
from evalsuite.learned.emage_aeskconv import EMAGE_FORMAT, build_model, state_from_checkpoint
from evalsuite.learned.emage_model import EmageFeatureModel
from evalsuite.learned.network import LATENT_DIM, Architecture, EmbeddingNet
from evalsuite.learned.representation import cut_windows, pose_vectors

FORMAT = "evalsuite-learned-model"
FORMAT_VERSION = 1
ENCODE_BATCH = 1024
# One thread: features do not depend on the machine's thread settings, and on a shared
# 2-core machine OpenMP threads competing with other processes are many times slower.
ENCODE_THREADS = 1


@contextlib.contextmanager
def torch_threads(n: int | None):
    """Run a block with ``n`` torch CPU threads (None: leave as is), restoring the setting."""
    previous = torch.get_num_threads()
    if n:
        torch.set_num_threads(n)
    try:
        yield
    finally:
        torch.set_num_threads(previous)


def _tensor_bytes(t: torch.Tensor) -> bytes:
    return t.detach().cpu().contiguous().numpy().tobytes()


def content_hash(meta: dict, state_dict: dict, mean: np.ndarray, std: np.ndarray) -> str:
    """SHA-256 over the canonical metadata and every tensor (see the module docstring)."""
    h = hashlib.sha256()
    public = {k: v for k, v in meta.items() if k not in ("content_hash", "created_utc")}
    h.update(json.dumps(public, sort_keys=True, separators=(",", ":")).encode())
    for name in sorted(state_dict):
        t = state_dict[name]
        h.update(f"{name}|{t.dtype}|{tuple(t.shape)}".encode())
        h.update(_tensor_bytes(t))
    for arr in (mean, std):
        a = np.ascontiguousarray(arr, dtype=np.float64)
        h.update(a.tobytes())
    return h.hexdigest()


class FeatureModel:
    """A motion encoder with everything needed to use it reproducibly.

    Use :meth:`windows` to turn a motion into raw windows, :meth:`encode` for features of
    windows (raw or normalised), :meth:`features` for a motion's features, :meth:`save`.
    """

    def __init__(self, net: EmbeddingNet, meta: dict, mean: np.ndarray, std: np.ndarray):
        self.net = net.eval()
        self.meta = meta
        self.arch: Architecture = net.arch
        self.mean = np.asarray(mean, dtype=np.float64)
        self.std = np.asarray(std, dtype=np.float64)
        if self.mean.shape != (self.arch.pose_dim,) or self.std.shape != (self.arch.pose_dim,):
            raise InputError(f"normalisation vectors must have {self.arch.pose_dim} values, got mean "
                             f"{self.mean.shape} and std {self.std.shape}")
        if not (np.isfinite(self.mean).all() and np.isfinite(self.std).all() and (self.std > 0).all()):
            raise InputError("normalisation std must be finite and positive (and mean finite)")
        if "content_hash" not in meta:
            meta["content_hash"] = content_hash(meta, net.state_dict(), self.mean, self.std)

    # --- description -------------------------------------------------------------------
    @property
    def window(self) -> int:
        return int(self.meta["window"])

    @property
    def stride(self) -> int:
        return int(self.meta["stride"])

    @property
    def fps(self) -> float:
        return float(self.meta["fps"])

    @property
    def window_rule(self) -> str:
        return self.meta.get("window_rule", "complete")

    @property
    def joints(self) -> list[str]:
        return list(self.meta["representation"]["joints"])

    @property
    def representation(self) -> dict:
        return self.meta["representation"]

    @property
    def content_hash(self) -> str:
        return self.meta["content_hash"]

    @property
    def short_hash(self) -> str:
        return self.content_hash[:12]

    def describe(self) -> str:
        """A few lines for reports."""
        rep = self.representation
        lines = [f"model {self.short_hash} (sha256 {self.content_hash})",
                 f"  {rep['kind']} of {len(rep['joints'])} joints"
                 + (f", {len(rep['bones'])} bones" if rep["kind"] == "bone_directions" else "")
                 + (f", {rep['convention']} convention" if rep.get("convention") else ""),
                 f"  window {self.window} frames at {self.fps:g} fps, stride {self.stride} ({self.window_rule})",
                 f"  conv channels {list(self.arch.conv_channels)}, fc slope {self.arch.fc_slope:g}, "
                 f"{'fc_mu head, ' if self.arch.variational_head else ''}{LATENT_DIM}-d features",
                 f"  evalsuite {self.meta.get('evalsuite_version')}, seed {self.meta.get('seed')}"]
        return "\n".join(lines)

    # --- data --------------------------------------------------------------------------
    def pose_vectors(self, motion) -> np.ndarray:
        """The motion in the model's representation ``(T, D)`` at the model's fps (raw, float64)."""
        return pose_vectors(motion, self.representation, self.fps)

    def windows(self, motion, stride: int | None = None) -> np.ndarray:
        """Raw windows ``(N, window, D)`` of a motion; InputError if it is too short for one."""
        vec = self.pose_vectors(motion)
        win = cut_windows(vec, self.window, stride or self.stride, self.window_rule)
        if len(win) == 0:
            need = self.window + (1 if self.window_rule == "genea" else 0)
            raise InputError(f"too short for one {self.window}-frame window at {self.fps:g} fps: "
                             f"{len(vec)} frames after resampling, need at least {need}",
                             path=getattr(motion, "source", None) or getattr(motion, "name", None))
        return win

    def normalize(self, windows: np.ndarray) -> np.ndarray:
        """z-normalised windows ``(x - mean) / std`` (float64)."""
        return (np.asarray(windows, dtype=np.float64) - self.mean) / self.std

    def encode(self, windows: np.ndarray, normalized: bool = False, batch_size: int = ENCODE_BATCH) -> np.ndarray:
        """Features ``(N, 32)`` (float64 copy of the float32 network output) of windows ``(N, W, D)``.

        ``normalized=False``: the windows are raw pose vectors and are z-normalised with the
        model's mean/std first; ``True``: they are already normalised (as the reference
        scripts' ``make_tensor`` returns them).
        """
        windows = np.asarray(windows)
        if windows.ndim != 3 or windows.shape[1:] != (self.window, self.arch.pose_dim):
            raise InputError(f"windows must have shape (N, {self.window}, {self.arch.pose_dim}), got {windows.shape}")
        x = windows if normalized else self.normalize(windows)
        out = np.empty((len(x), LATENT_DIM), dtype=np.float64)
        with torch.inference_mode(), torch_threads(ENCODE_THREADS):
            for start in range(0, len(x), batch_size):
                batch = torch.from_numpy(np.ascontiguousarray(x[start:start + batch_size], dtype=np.float32))
                out[start:start + len(batch)] = self.net.pose_encoder(batch).numpy()
        return out

    def features(self, motion, stride: int | None = None) -> np.ndarray:
        """Features of every window of a motion ``(N, 32)``."""
        return self.encode(self.windows(motion, stride))

    # --- persistence -------------------------------------------------------------------
    def save(self, path) -> str:
        """Write the model file; returns the content hash."""
        state = {k: v.detach().cpu().clone() for k, v in self.net.state_dict().items()}
        meta = dict(self.meta)
        meta["content_hash"] = content_hash(meta, state, self.mean, self.std)
        self.meta["content_hash"] = meta["content_hash"]
        payload = {"format": FORMAT, "format_version": FORMAT_VERSION, "meta": meta, "state_dict": state,
                   "mean": torch.from_numpy(self.mean.copy()), "std": torch.from_numpy(self.std.copy())}
        path = pathlib.Path(path)
        if path.parent and not path.parent.exists():
            path.parent.mkdir(parents=True, exist_ok=True)
        buffer = io.BytesIO()
        torch.save(payload, buffer)
        tmp = path.with_name(path.name + ".tmp")
        tmp.write_bytes(buffer.getvalue())
        os.replace(tmp, path)
        return meta["content_hash"]


def new_meta(arch: Architecture, representation: dict, fps: float, stride: int, window_rule: str,
             normalization: dict, provenance: dict, seed) -> dict:
    return {
        "architecture": arch.to_dict(),
        "representation": representation,
        "fps": float(fps),
        "window": int(arch.window),
        "stride": int(stride),
        "window_rule": window_rule,
        "normalization": normalization,
        "training": provenance,
        "evalsuite_version": __version__,
        "seed": seed,
        "created_utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
    }


AnyFeatureModel = FeatureModel | EmageFeatureModel


def load_model(path) -> AnyFeatureModel:
    """Load a model file written by :meth:`FeatureModel.save`, checking its content hash.

    A file written by ``evalsuite fgd import-emage`` gives an :class:`EmageFeatureModel` (same interface for
    the FGD family: windows, encode, fps, window, content_hash).
    """
    if isinstance(path, (FeatureModel, EmageFeatureModel)):
        return path
    path = pathlib.Path(path)
    if not path.exists():
        raise InputError("no such model file", path=path)
    try:
        payload = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as exc:  # torch raises many types for foreign or corrupt files
        raise InputError(f"not an evalsuite model file ({exc.__class__.__name__}: {str(exc)[:200]}); "
                         "GENEA checkpoints must be converted first: evalsuite fgd import-genea", path=path) from None
    if isinstance(payload, dict) and payload.get("format") == EMAGE_FORMAT:
        return EmageFeatureModel(build_model(state_from_checkpoint(payload["state_dict"], str(path))),
                                 payload["meta"], payload["state_dict"])
    if not isinstance(payload, dict) or payload.get("format") != FORMAT:
        raise InputError("not an evalsuite model file (no 'format' marker); GENEA checkpoints must be "
                         "converted first: evalsuite fgd import-genea", path=path)
    if int(payload.get("format_version", 0)) > FORMAT_VERSION:
        raise InputError(f"model file format {payload['format_version']} is newer than this evalsuite "
                         f"understands ({FORMAT_VERSION}); upgrade evalsuite", path=path)
    meta = dict(payload["meta"])
    arch = Architecture.from_dict(meta["architecture"])
    net = EmbeddingNet(arch)
    net.load_state_dict(payload["state_dict"])
    mean = payload["mean"].numpy().astype(np.float64)
    std = payload["std"].numpy().astype(np.float64)
    expected = meta.get("content_hash")
    actual = content_hash(meta, payload["state_dict"], mean, std)
    if expected != actual:
        raise InputError(f"content hash mismatch (file says {str(expected)[:12]}, contents give {actual[:12]}): "
                         "the file was modified or is corrupt", path=path)
    return FeatureModel(net, meta, mean, std)


def encode_windows(model, windows: np.ndarray, normalized: bool = False) -> np.ndarray:
    """Features ``(N, 32)`` of windows ``(N, window, D)``; ``model`` is a FeatureModel or a path.

    The function to compare evalsuite with the reference code: feed it the same normalised
    windows as the reference ``make_tensor`` and ``normalized=True``.
    """
    if not isinstance(model, FeatureModel):
        model = load_model(model)
    return model.encode(windows, normalized=normalized)
