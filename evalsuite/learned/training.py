"""Training the motion autoencoder on natural motion, on CPU, reproducibly.

The recipe is the GENEA ``train_AE.py`` one: windows of z-normalised pose vectors, Adam
(``betas=(0.5, 0.999)``), loss per window = mean L1 reconstruction error + mean L1 error of
frame-to-frame differences, summed over the batch; batches of 64, incomplete last batch
dropped. Added here: a validation split (the last ``val_fraction`` of every sequence's
frames, cut into windows separately so no window straddles the split) with its loss
reported every epoch, and determinism: the seed drives the weight initialisation and the
batch order, ``torch.use_deterministic_algorithms(True)`` is on and, by default, one CPU
thread is used while training (the two settings are restored afterwards). Same data, seed,
evalsuite/torch versions and machine give bit-identical weights and the same content hash.
"""
from __future__ import annotations

import contextlib
import platform

import numpy as np
import torch
from tqdm.auto import tqdm

from evalsuite.errors import InputError
from evalsuite.learned.data import array_sha256, file_sha256
from evalsuite.learned.modelfile import FeatureModel, new_meta
from evalsuite.learned.network import Architecture, EmbeddingNet
from evalsuite.learned.presets import architecture_preset, resolve_joint_spec
from evalsuite.learned.representation import REPRESENTATIONS, cut_windows, default_bones, pose_vectors

# Positions are divided by their training std, floored at this fraction of the largest dimension's std. A joint
# that the training motion keeps (almost) still, e.g. a lower spine joint, has a std of micrometres: divided by
# it, a generated motion's millimetre deviation there became thousands of standard deviations and alone made FGD
# 19,200 for a model whose motion was ordinary (Ferstl et al.'s re-implementation; issue 39). The floor is
# relative, so it does not depend on the units (cm or m).
STD_FLOOR_FRACTION = 0.01


def reconstruction_loss(target: torch.Tensor, recon: torch.Tensor) -> torch.Tensor:
    """Per-window loss ``(B,)``: mean |recon - target| + mean |diff(recon) - diff(target)|."""
    loss = (recon - target).abs().mean(dim=(1, 2))
    return loss + (recon.diff(dim=1) - target.diff(dim=1)).abs().mean(dim=(1, 2))


@contextlib.contextmanager
def deterministic_torch(threads: int | None):
    prev_det = torch.are_deterministic_algorithms_enabled()
    prev_threads = torch.get_num_threads()
    torch.use_deterministic_algorithms(True)
    if threads:
        torch.set_num_threads(threads)
    try:
        yield
    finally:
        torch.use_deterministic_algorithms(prev_det)
        torch.set_num_threads(prev_threads)


def _split(vectors: np.ndarray, window: int, stride: int, val_fraction: float):
    n_val = int(round(len(vectors) * val_fraction))
    if n_val < window or len(vectors) - n_val < window:
        return cut_windows(vectors, window, stride), cut_windows(vectors[:0], window, stride)
    return (cut_windows(vectors[:len(vectors) - n_val], window, stride),
            cut_windows(vectors[len(vectors) - n_val:], window, stride))


def train_model(sequences, *, joints="all", window: int = 30, stride: int | None = None, fps: float = 30.0,
                epochs: int = 50, seed: int = 0, batch_size: int = 64, learning_rate: float = 5e-4,
                val_fraction: float = 0.1, representation: str = "positions", bones=None,
                convention: str | None = None, architecture: str = "genea2023", threads: int | None = 1,
                progress: bool = True, log=None) -> FeatureModel:
    """Train an encoder on natural motion and return it as a :class:`FeatureModel`.

    Args:
        sequences: ``{name: Motion}`` (or a list of motions) of natural motion.
        joints: a preset (``genea2023`` also sets the PyMO convention), ``"A,B,C"``, a list,
            or ``"all"`` (every joint of the first sequence).
        window, stride: window length in frames (at ``fps``) and step (default window // 2).
        fps: frame rate the model works at; sequences are resampled to it.
        epochs, seed, batch_size, learning_rate: training settings (seed fixes everything).
        val_fraction: share of every sequence's frames (at its end) held out for validation.
        representation: ``positions`` or ``bone_directions`` (Yoon et al.; ``bones`` as
            ``[[parent, child], ...]``, default: each joint to its nearest selected ancestor).
        convention: BVH translation convention (default: the joint preset's, else as loaded).
        architecture: ``genea2023``/``genea2022`` (128/64 channels), ``genea2020``, ``yoon2020``.
        threads: CPU threads while training (1 = reproducible across thread settings).
        log: a function taking one line of text (e.g. ``click.echo``) for the epoch summaries.
    """
    if isinstance(sequences, dict):
        items = sorted(sequences.items())
    else:
        items = [(m.name or f"seq{i}", m) for i, m in enumerate(sequences)]
    if not items:
        raise InputError("no training motion given")
    if representation not in REPRESENTATIONS:
        raise InputError(f"unknown representation {representation!r}; expected one of {', '.join(REPRESENTATIONS)}")
    if not (0.0 <= val_fraction < 0.5):
        raise InputError(f"val_fraction must be in [0, 0.5), got {val_fraction}")
    if epochs < 1 or batch_size < 2:
        raise InputError("epochs must be >= 1 and batch_size >= 2")
    stride = int(stride or max(window // 2, 1))
    names, preset_convention = resolve_joint_spec(joints, items[0][1].joint_names)
    convention = convention or preset_convention
    rep: dict[str, object] = {"kind": representation, "joints": names, "convention": convention}
    if representation == "bone_directions":
        rep["bones"] = [list(b) for b in (bones or default_bones(items[0][1], names))]

    train_parts, val_parts, frames, data_info = [], [], [], []
    for name, motion in items:
        vec = pose_vectors(motion, rep, fps)
        tr, va = _split(vec, window, stride, val_fraction)
        train_parts.append(tr)
        val_parts.append(va)
        frames.append(vec[: len(vec) - int(round(len(vec) * val_fraction))] if len(va) else vec)
        data_info.append({"name": name, "frames": int(len(vec)), "source_fps": float(motion.fps),
                          "file_sha256": file_sha256(motion.source), "pose_vectors_sha256": array_sha256(vec)})
    train_raw = np.concatenate(train_parts)
    val_raw = np.concatenate(val_parts)
    if len(train_raw) < 2:
        raise InputError(f"too little training motion: {len(train_raw)} window(s) of {window} frames at "
                         f"{fps:g} fps; need at least 2 (more for a useful model)")

    all_frames = np.concatenate(frames)
    mean = all_frames.mean(axis=0)
    if representation == "bone_directions":
        std = np.ones_like(mean)  # Yoon et al. subtract the mean direction only
        floored = np.zeros(mean.shape, dtype=bool)
    else:
        std = all_frames.std(axis=0)
        floor = STD_FLOOR_FRACTION * std.max() if std.max() > 0 else 1.0
        floored = std < floor
        std = np.maximum(std, floor)

    arch = Architecture(pose_dim=train_raw.shape[2], window=window, **architecture_preset(architecture))
    train_x = torch.from_numpy(((train_raw - mean) / std).astype(np.float32))
    val_x = torch.from_numpy(((val_raw - mean) / std).astype(np.float32))

    history = []
    with deterministic_torch(threads):
        torch.manual_seed(seed)
        net = EmbeddingNet(arch)
        optimizer = torch.optim.Adam(net.parameters(), lr=learning_rate, betas=(0.5, 0.999))
        order_rng = torch.Generator().manual_seed(seed)
        n = len(train_x)
        per_epoch = n // batch_size if n >= batch_size else 1
        bar = tqdm(total=epochs * per_epoch, desc="training", unit="batch", disable=not progress, leave=False)
        for epoch in range(epochs):
            net.train()
            perm = torch.randperm(n, generator=order_rng)
            total, count = 0.0, 0
            for b in range(per_epoch):
                idx = perm[b * batch_size:(b + 1) * batch_size] if n >= batch_size else perm
                target = train_x[idx]
                optimizer.zero_grad()
                _, recon = net(target)
                loss = reconstruction_loss(target, recon).sum()
                loss.backward()
                optimizer.step()
                total += float(loss.item())
                count += len(idx)
                bar.update(1)
            train_loss = total / count
            val_loss = _evaluate(net, val_x) if len(val_x) else float("nan")
            history.append({"epoch": epoch + 1, "train_loss": train_loss, "val_loss": val_loss})
            bar.set_postfix(train=f"{train_loss:.4f}", val=f"{val_loss:.4f}")
            if log is not None:
                log(f"epoch {epoch + 1:>3}/{epochs}  train loss {train_loss:.4f}  validation loss {val_loss:.4f}")
        bar.close()
    net.eval()

    provenance = {
        "kind": "trained", "seed": int(seed), "epochs": int(epochs), "batch_size": int(batch_size),
        "learning_rate": float(learning_rate), "optimizer": "Adam(betas=(0.5, 0.999))",
        "loss": "mean L1 + mean L1 of frame differences, summed over the batch",
        "val_fraction": float(val_fraction), "train_windows": int(len(train_x)), "val_windows": int(len(val_x)),
        "history": history, "data": data_info, "train_windows_sha256": array_sha256(train_raw),
        "torch_version": str(torch.__version__), "threads": threads, "architecture_preset": architecture,
        "machine": platform.machine(),
    }
    normalization = {"source": "training frames: mean and population std per dimension"
                               + (" (std fixed to 1, as Yoon et al.)" if representation == "bone_directions" else ""),
                     "std_floor": (f"{STD_FLOOR_FRACTION:g} x the largest std" if representation == "positions" else None),
                     "dims_at_std_floor": int(floored.sum()) if representation == "positions" else 0}
    meta = new_meta(arch, rep, fps, stride, "complete", normalization, provenance, int(seed))
    return FeatureModel(net, meta, mean, std)


def _evaluate(net: EmbeddingNet, x: torch.Tensor, batch: int = 512) -> float:
    net.eval()
    total = 0.0
    with torch.inference_mode():
        for s in range(0, len(x), batch):
            target = x[s:s + batch]
            _, recon = net(target)
            total += float(reconstruction_loss(target, recon).sum())
    net.train()
    return total / len(x)
