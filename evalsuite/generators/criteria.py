"""Distribution-level learning criteria of generated folders against a corpus split (issue 15), beside the
per-segment ones of :mod:`evalsuite.generators.evaluation`.

* :func:`wrist_speed_hellinger`: Hellinger distance between the histograms of per-frame wrist speed (units/s,
  central differences at the generated rate, both wrists pooled) of a generated folder and of the split's
  natural motion; 60 bins from 0 to the natural speeds' 99.5th percentile times 1.5, plus the overflow bin
  (:func:`evalsuite.metrics.histograms.hellinger_distance`);
* :func:`diversity`: ``l1div`` and ``div_k`` (:mod:`evalsuite.metrics.distribution`) of the hip-centred positions
  of the GENEA 2020 upper-body joints the motions share;
* :func:`latent_nsd`: NSD (:func:`evalsuite.learned.latent.nsd`, k = 1) of per-sequence latent windows against
  a shuffled control (the same windows in a seeded random order within each sequence);
* :func:`fgd_against_natural`: FGD (:func:`evalsuite.learned.fgd.score_fgd`) of folders against the split's
  natural motion with an encoder trained on the corpus's natural training split.
"""
from __future__ import annotations

import pathlib
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from evalsuite.corpus.types import Corpus
from evalsuite.errors import InputError
from evalsuite.motion import Motion
from evalsuite.motion.io import list_motion_files, load_motion
from evalsuite.motion.ops import resample
from evalsuite.motion.presets import GENEA2020_UPPER

__all__ = ["generated_motions", "natural_motions", "wrist_speeds", "wrist_speed_hellinger", "diversity",
           "latent_nsd", "fgd_against_natural"]


def generated_motions(folder: str | pathlib.Path, corpus: Corpus, split: str = "test",
                      sample: int | None = None) -> dict[str, Motion]:
    """The generated motion of each segment of ``split`` (``<id>.*``, or ``<id>_<sample>.*``)."""
    files = list_motion_files(folder)
    out = {}
    for seg in corpus.split(split):
        path = files.get(seg.id) if sample is None else files.get(f"{seg.id}_{sample}")
        path = path or files.get(f"{seg.id}_0")
        if path is None:
            raise InputError(f"no generated file for segment {seg.id!r}", path=folder)
        out[seg.id] = load_motion(path)
    return out


def natural_motions(corpus: Corpus, split: str = "test", fps: float | None = None) -> dict[str, Motion]:
    out = {}
    for seg in corpus.split(split):
        m = seg.load_motion()
        out[seg.id] = resample(m, fps) if fps else m
    return out


def _wrists(m: Motion) -> np.ndarray:
    from evalsuite.metrics.coupling import wrist_indices

    return m.positions()[:, wrist_indices(m.joint_names)]


def wrist_speeds(motions: Mapping[str, Motion]) -> np.ndarray:
    """Per-frame speeds of both wrists pooled over the motions (units/s)."""
    parts = []
    for m in motions.values():
        w = _wrists(m)
        parts.append(np.linalg.norm(np.gradient(w, axis=0) * m.fps, axis=-1).ravel())
    return np.concatenate(parts)


def wrist_speed_hellinger(generated: Mapping[str, Motion], natural: Mapping[str, Motion],
                          n_bins: int = 60) -> float:
    from evalsuite.metrics.histograms import hellinger_distance, joint_histograms

    ref = wrist_speeds(natural)
    edges = np.linspace(0.0, 1.5 * float(np.percentile(ref, 99.5)), n_bins + 1)
    h_ref = joint_histograms(ref[:, None], edges)[0]
    h_gen = joint_histograms(wrist_speeds(generated)[:, None], edges)[0]
    return hellinger_distance(h_ref, h_gen)


def _upper_positions(m: Motion, joints: Sequence[str]) -> np.ndarray:
    """Positions relative to ``Hips`` when the motion has it (generated positions are hip-centred already)."""
    pos = m.positions()
    if "Hips" in m.joint_names:
        pos = pos - pos[:, m.joint_index("Hips"):m.joint_index("Hips") + 1]
    return pos[:, [m.joint_index(j) for j in joints]]


def diversity(motions: Mapping[str, Motion], joints: Sequence[str] | None = None) -> dict[str, float]:
    """``l1div`` (units) and ``div_k`` (units²) of hip-centred positions of ``joints`` (default: the joints of the
    first preset of :mod:`evalsuite.generators.joint_presets`, the GENEA 2020 upper body on its skeleton, that all
    the motions have)."""
    from evalsuite.generators.joint_presets import default_joints
    from evalsuite.metrics.distribution import div_k, l1div

    if joints is None:
        shared = [j for j in next(iter(motions.values())).joint_names
                  if all(j in m.joint_names for m in motions.values())]
        joints = [j for j in default_joints(shared) if j in shared]
    seqs = [_upper_positions(m, joints) for m in motions.values()]
    return {"l1div": l1div(seqs), "div_k": div_k(seqs)}


def latent_nsd(sequences: Sequence[np.ndarray], seed: int = 0) -> dict[str, float]:
    """``nsd`` of the latent windows of each sequence (in order) and ``nsd_shuffled`` of the same windows in a
    seeded random order within each sequence (the control: neighbours no closer than any pair)."""
    from evalsuite.learned.latent import nsd

    rng = np.random.default_rng(seed)
    seqs = [np.asarray(s) for s in sequences if len(s) >= 3]
    if not seqs:
        raise InputError("NSD needs sequences of at least 3 latent windows")
    shuffled = [s[rng.permutation(len(s))] for s in seqs]
    return {"nsd": nsd(seqs, ks=(1,), seed=seed)["nsd_k1"], "nsd_shuffled": nsd(shuffled, ks=(1,), seed=seed)["nsd_k1"]}


def fgd_against_natural(corpus: Corpus, conditions: Mapping[str, Mapping[str, Motion]], *, split: str = "test",
                        epochs: int = 20, window: int = 30, fps: float = 20.0, seed: int = 0,
                        joints: Sequence[str] = GENEA2020_UPPER) -> dict[str, Any]:
    """FGD of each condition's motions against the split's natural motion; the encoder (window frames at
    ``fps``) is trained on the natural motion of the corpus's train split (``joints``: the GENEA 2020 upper
    body by default)."""
    from evalsuite.learned.fgd import score_fgd
    from evalsuite.learned.training import train_model

    model = train_model(natural_motions(corpus, "train"), joints=",".join(joints), window=window, fps=fps, epochs=epochs,
                        seed=seed, learning_rate=1e-3, progress=False)
    rows = score_fgd(model, dict(natural_motions(corpus, split)), {k: dict(v) for k, v in conditions.items()},
                     raw=False, n_bootstrap=0, seed=seed)
    return {r["condition"]: r["value"] for r in rows if r["metric"] == "fgd"}
