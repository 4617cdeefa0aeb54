"""The divergence guard: a training whose loss or output scale is off by orders of magnitude stops with an error
instead of leaving a model folder behind, so a diverged model can never be generated from (or shown in a demo).

Two checks, run by :func:`evalsuite.generators.training.train` after the plug-in's ``fit``:

* **loss** (:func:`loss_divergence`): every history column whose name ends in ``loss`` (``train_loss``,
  ``val_loss``, ``generator_loss``, …), in row order, separately per training stage (the rows' ``stage``: a
  new stage may have another loss). NaN or ±inf is divergence; so is a value ``|L_t| > k · |L_1|`` with
  ``L_1`` the column's first value in that stage and ``k`` = :attr:`DivergenceLimits.loss_factor` (100): the
  loss grew a hundredfold above where the stage started.
* **output scale** (:func:`scale_ratio`): the trained model generates one segment (the first of the val split,
  else of the train split); with ``P`` the root-relative positions ``(T, J, 3)`` of the joints the output and
  the segment's natural motion share,

      ratio = mean_{j,c} std_t(P_gen[t, j, c]) / mean_{j,c} std_t(P_nat[t, j, c])

  and a ratio above :attr:`DivergenceLimits.max_std_ratio` (100) or below
  :attr:`DivergenceLimits.min_std_ratio` (1e-4: the output does not move at all) is divergence. Short, honest
  trainings give damped output (ratios of 1e-3 to 1e-1 after a few epochs on the synthetic speaker), so the
  lower limit only catches a model whose output is still.
"""
from __future__ import annotations

import math
import pathlib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from evalsuite.generators.contract import GeneratorError

__all__ = ["DivergenceLimits", "DivergenceError", "loss_divergence", "scale_ratio", "output_divergence"]


@dataclass(frozen=True)
class DivergenceLimits:
    loss_factor: float = 100.0      # k: a loss above k x its value at the start of its stage
    max_std_ratio: float = 100.0    # generated spread above 100 x the natural one
    min_std_ratio: float = 1e-4     # generated spread below 1e-4 x the natural one (still output)


class DivergenceError(GeneratorError):
    """The training diverged; no model was written."""


def loss_divergence(history: Sequence[Mapping[str, Any]], limits: DivergenceLimits = DivergenceLimits()) -> str | None:
    """Why the loss columns of ``history`` (one row per epoch/step) diverged, or None."""
    columns: dict[tuple[str, str], list[tuple[int, float]]] = {}
    for i, row in enumerate(history):
        for key, value in row.items():
            if key.endswith("loss") and isinstance(value, (int, float)) and not isinstance(value, bool):
                columns.setdefault((str(row.get("stage", "")), key), []).append((i, float(value)))
    for (stage, key), values in columns.items():
        where = f" (stage {stage})" if stage else ""
        for i, v in values:
            if not math.isfinite(v):
                return f"{key} is {v} at row {i + 1} of the training history{where}"
        early = abs(values[0][1])
        for i, v in values[1:]:
            if early > 0 and abs(v) > limits.loss_factor * early:
                return (f"{key} reached {v:.4g} at row {i + 1} of the training history{where}, more than "
                        f"{limits.loss_factor:g} x its first value {early:.4g}")
    return None


def _spread(motion: Any, joints: Sequence[str]) -> float:
    """mean over joints and coordinates of the std over time of the root-relative positions (of the axis-angle
    rotations for SMPL-X motion without a body model, whose positions cannot be computed)."""
    smplx = getattr(motion, "smplx", None)
    if smplx is not None and not getattr(motion, "has_positions", True):
        return float(np.mean(np.std(np.asarray(smplx.poses, dtype=np.float64), axis=0)))
    pos = np.asarray(motion.positions(), dtype=np.float64)
    root = int(motion.skeleton.roots[0]) if motion.is_hierarchical else None
    idx = [motion.joint_index(j) for j in joints]
    rel = pos[:, idx] - (pos[:, root:root + 1] if root is not None and motion.joint_names[root] not in joints
                         else 0.0)
    return float(np.mean(np.std(rel, axis=0)))


def scale_ratio(generated: Any, natural: Any) -> float:
    """``ratio`` of the module doc between a generated and a natural :class:`~evalsuite.motion.Motion` (NaN when
    they share no joint)."""
    joints = [j for j in generated.joint_names if j in natural.joint_names]
    if not joints:
        return math.nan     # another skeleton: nothing to compare
    nat = _spread(natural, joints)
    gen = _spread(generated, joints)
    if not math.isfinite(gen):
        return math.inf
    return gen / nat if nat > 0 else (math.inf if gen > 0 else 1.0)


def output_divergence(entry: Any, corpus: Any, model_dir: pathlib.Path, config: Mapping[str, Any],
                      limits: DivergenceLimits = DivergenceLimits()) -> str | None:
    """Generate one segment with the freshly trained model and compare its spread with the natural motion's."""
    from evalsuite.generators.registry import generator_class
    from evalsuite.generators.requests import requests_from_corpus

    names = {s.split for s in corpus.segments}
    split = "val" if "val" in names else "train"
    segment = corpus.split(split)[0]
    natural = segment.load_motion()
    requests = requests_from_corpus(corpus, [split], float(natural.fps), segments=[segment.id])
    gen = generator_class(entry.target)()
    try:
        gen.load(dict(config), model_dir)
        out = gen.generate(requests[0])
    finally:
        gen.close()
    if out.motion is None:
        return None
    smplx = getattr(out.motion, "smplx", None)
    values = np.asarray(smplx.poses if smplx is not None else out.motion.positions(), dtype=np.float64)
    if not np.isfinite(values).all():
        return f"the generated motion of segment {segment.id!r} holds NaN or infinite values"
    ratio = scale_ratio(out.motion, natural)
    if not math.isnan(ratio) and not limits.min_std_ratio <= ratio <= limits.max_std_ratio:
        return (f"the generated motion of segment {segment.id!r} spreads {ratio:.3g} x as much as the natural "
                f"motion (allowed {limits.min_std_ratio:g} to {limits.max_std_ratio:g})")
    return None
