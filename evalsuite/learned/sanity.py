"""Sanity checks any user can run on their own FGD model (after the Fréchet Motion Distance study).

The natural sequences are split in two halves (alternate sequences in name order; a single
sequence is split at its middle frame). Half A is the reference; half B is scored as is and
after perturbations of the model's joint positions:

* ``gaussian noise``: i.i.d. N(0, (level * s)^2) added to every coordinate, where ``s`` is the
  mean over joints and axes of the per-coordinate temporal std of half A (the motion's scale);
* ``temporal jitter``: each frame replaced by frame ``t + round(N(0, level^2))`` (level in
  frames, clipped to the sequence), i.e. locally shuffled time;
* ``static mean pose``: every frame replaced by the sequence's mean pose.

Expected: FGD(natural halves) near 0 (below every strongest perturbation and below 10 % of
the static-pose FGD), FGD strictly increasing with the noise level and with the jitter level
(across the levels; the weakest level may fall within the natural halves' sampling noise,
whose FGD is mostly the small-sample bias of the estimator), and the static pose far from
natural. Everything is seeded. The halves are held to the small-sample rule of ``evalsuite
score`` (:func:`evalsuite.metrics.frechet.sample_size_warnings`: windows per half against the
feature dimension, sequences per half); what it finds is in ``warnings`` and, when the natural
halves check fails, in that check's detail.
"""
from __future__ import annotations

import numpy as np

from evalsuite.errors import InputError
from evalsuite.learned.fgd import score_fgd
from evalsuite.learned.modelfile import FeatureModel, load_model
from evalsuite.learned.network import LATENT_DIM
from evalsuite.learned.representation import joint_positions
from evalsuite.metrics.frechet import sample_size_warnings
from evalsuite.motion import Motion

NOISE_LEVELS = (0.3, 1.0, 3.0)
JITTER_LEVELS = (1.0, 3.0, 9.0)
NEAR_ZERO_FRACTION = 0.1


def _halves(model: FeatureModel, natural: dict) -> tuple[dict, dict]:
    """Two halves of positional motions at the model's fps (joints in the model's order)."""
    rep = model.representation
    pos = {name: joint_positions(natural[name], model.joints, model.fps, rep.get("convention"))
           for name in sorted(natural)}
    if not pos:
        raise InputError("no natural sequences")

    def motion(name, p):
        return Motion.from_positions(p, model.joints, model.fps, name=name)

    names = sorted(pos)
    if len(names) >= 2:
        return ({n: motion(n, pos[n]) for n in names[0::2]}, {n: motion(n, pos[n]) for n in names[1::2]})
    (name,) = names
    p = pos[name]
    mid = len(p) // 2
    return {f"{name}_a": motion(f"{name}_a", p[:mid])}, {f"{name}_b": motion(f"{name}_b", p[mid:])}


def perturb_noise(pos: np.ndarray, sigma: float, rng: np.random.Generator) -> np.ndarray:
    return pos + rng.normal(0.0, sigma, size=pos.shape)


def perturb_jitter(pos: np.ndarray, frames: float, rng: np.random.Generator) -> np.ndarray:
    t = np.arange(len(pos))
    src = np.clip(t + np.rint(rng.normal(0.0, frames, size=len(pos))).astype(np.int64), 0, len(pos) - 1)
    return pos[src]


def perturb_static(pos: np.ndarray) -> np.ndarray:
    return np.broadcast_to(pos.mean(axis=0), pos.shape).copy()


def check_model(model, natural: dict, *, seed: int = 0, noise_levels=NOISE_LEVELS, jitter_levels=JITTER_LEVELS,
                n_bootstrap: int = 0) -> dict:
    """Run the sanity suite; returns ``{"rows": [...], "checks": [...], "passed": bool}``.

    ``rows``: ``perturbation, level, fgd, ci_low, ci_high, n_windows``; ``checks``: ``name,
    passed, detail``; ``warnings``: why the halves are too small for FGD (empty when they are not).
    """
    model = model if isinstance(model, FeatureModel) else load_model(model)
    half_a, half_b = _halves(model, natural)
    scale = float(np.mean([m.positions().std(axis=0).mean() for m in half_a.values()]))
    rng = np.random.default_rng(seed)
    variants: list[tuple[str, float, dict]] = [("natural (other half)", 0.0, half_b)]

    def mapped(fn):
        return {n: m.with_positions(fn(m.positions())) for n, m in half_b.items()}

    for level in noise_levels:
        variants.append(("gaussian noise", level, mapped(lambda p, s=level * scale: perturb_noise(p, s, rng))))
    for level in jitter_levels:
        variants.append(("temporal jitter", level, mapped(lambda p, f=level: perturb_jitter(p, f, rng))))
    variants.append(("static mean pose", 1.0, mapped(perturb_static)))

    conditions = {f"{i}": v[2] for i, v in enumerate(variants)}
    scored = score_fgd(model, half_a, conditions, raw=False, n_bootstrap=n_bootstrap, seed=seed)
    rows = []
    for (kind, level, _), r in zip(variants, scored):
        rows.append({"perturbation": kind, "level": level, "fgd": r["value"], "ci_low": r["ci_low"],
                     "ci_high": r["ci_high"], "n_windows": r["n_windows_condition"],
                     "n_windows_reference": r["n_windows_reference"]})
    natural_fgd = rows[0]["fgd"]
    static_fgd = rows[-1]["fgd"]
    checks = []

    def family(kind):
        return [r["fgd"] for r in rows if r["perturbation"] == kind]

    strongest = [family("gaussian noise")[-1], family("temporal jitter")[-1], static_fgd]
    near_zero = natural_fgd < min(strongest) and natural_fgd <= NEAR_ZERO_FRACTION * static_fgd
    checks.append({"name": "natural halves near 0", "passed": bool(near_zero),
                   "detail": f"{natural_fgd:.4g} (static pose {static_fgd:.4g}; must be <= "
                             f"{NEAR_ZERO_FRACTION:g} x that and below every strongest perturbation)"})
    for kind in ("gaussian noise", "temporal jitter"):
        vals = family(kind)
        # Across levels only: the weakest level may sit within the natural halves' sampling noise.
        ok = all(b > a for a, b in zip(vals, vals[1:])) and vals[-1] > natural_fgd
        checks.append({"name": f"{kind} increases FGD", "passed": bool(ok),
                       "detail": " < ".join(f"{v:.4g}" for v in vals) + f" (natural {natural_fgd:.4g})"})
    checks.append({"name": "static mean pose far from natural", "passed": bool(static_fgd > natural_fgd),
                   "detail": f"{static_fgd:.4g} > {natural_fgd:.4g}"})
    # the rule of `evalsuite score`: with halves this small the natural halves' FGD is mostly bias
    small = sample_size_warnings((rows[0]["n_windows_reference"], rows[0]["n_windows"]), LATENT_DIM,
                                 (len(half_a), len(half_b)), "windows")
    if small and not near_zero:
        checks[0]["detail"] = f"{checks[0]['detail']} - the halves are too small for FGD (see the warnings)"
    return {"rows": rows, "checks": checks, "passed": all(c["passed"] for c in checks), "warnings": small,
            "model_hash": model.content_hash, "motion_scale": scale,
            "n_sequences": (len(half_a), len(half_b))}


def format_table(result: dict) -> str:
    """The sanity table as Markdown."""
    lines = ["| perturbation | level | FGD | windows |", "|---|---:|---:|---:|"]
    for r in result["rows"]:
        level = "" if r["perturbation"].startswith(("natural", "static")) else (
            f"{r['level']:g} x scale" if r["perturbation"] == "gaussian noise" else f"{r['level']:g} frames")
        lines.append(f"| {r['perturbation']} | {level} | {r['fgd']:.4f} | {r['n_windows']} |")
    lines.append("")
    lines.append("| check | result | detail |")
    lines.append("|---|---|---|")
    for c in result["checks"]:
        lines.append(f"| {c['name']} | {'pass' if c['passed'] else 'FAIL'} | {c['detail']} |")
    return "\n".join(lines)
