"""Figures of a scoring run (matplotlib, Agg backend; each written as PNG and SVG).

* ``hist_<quantity>_<group>``: normalised speed / acceleration histograms of every condition as
  lines against natural motion (black), one figure per joint group — the figure of the GENEA
  and "Moving fast and slow" papers. The clipped (above-range) share is given in the legend.
* ``wrist_distribution``: where the wrists are, accumulated over all frames of all sequences,
  one column per condition (top: density in the frontal plane, lateral x against height y,
  relative to the root's ground-plane position; bottom: wrist height over time in the first
  sequence) — in the spirit of Ferstl et al.'s motion-distribution figure.
* ``gac_coverage`` (with the ``gac`` family): one column per condition; top: the share of sequences that
  cover each pixel; bottom: the first sequence's coverage against the natural one (grey: both, red: the
  condition only (FP), blue: natural only (FN)), as in Tonoli et al.'s figures.
* ``fgd_inf`` (with ``--fgd MODEL --fgd-inf``): FGD against 1/N per condition, the draws (dots), their
  means and the fitted line down to its intercept FGD∞ at 1/N = 0 (Chong & Forsyth's figure for FID).
"""
from __future__ import annotations

import pathlib
from typing import Any

import numpy as np

from evalsuite.metrics.engine import ScoreResult

__all__ = ["histogram_figures", "wrist_distribution_figure", "gac_figure", "fgd_inf_figure", "write_figures"]


def _plt() -> Any:
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def _save(fig: Any, base: pathlib.Path) -> list[pathlib.Path]:
    paths = [base.with_suffix(".png"), base.with_suffix(".svg")]
    fig.savefig(paths[0], dpi=120)
    fig.savefig(paths[1])
    return paths


def histogram_figures(result: ScoreResult, out_dir: str | pathlib.Path) -> list[pathlib.Path]:
    plt = _plt()
    out = pathlib.Path(out_dir)
    setup, conv, plan = result.setup, result.convention, result.plan
    paths = []
    by_key: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for h in result.histograms:
        by_key.setdefault((h["quantity"], h["group"]), []).append(h)
    for (q, group), hists in by_key.items():
        edges = setup.edges[q]
        centres = (edges[:-1] + edges[1:]) / 2
        fig, ax = plt.subplots(figsize=(7, 4.2))
        for h in sorted(hists, key=lambda h: h["condition"] != plan.reference):
            counts = np.asarray(h["counts"], dtype=float)
            total = counts.sum() if conv.overflow else counts[:-1].sum()
            if total <= 0:
                continue
            clipped = counts[-1] / counts.sum() if counts.sum() else 0.0
            natural = h["condition"] == plan.reference
            ax.plot(centres, 100 * counts[:-1] / total, color="black" if natural else None,
                    lw=2.2 if natural else 1.2, label=f"{h['condition']} (clipped {100 * clipped:.1f}%)")
        order = {"speed": 1, "acceleration": 2}[q]
        ax.set_xlabel(f"{q} ({conv.unit(order)})")
        ax.set_ylabel("frequency (%)")
        ax.set_title(f"{q} histogram, joints: {group}")
        ax.legend(fontsize=8)
        fig.tight_layout()
        paths += _save(fig, out / f"hist_{q}_{group}")
        plt.close(fig)
    return paths


def wrist_distribution_figure(result: ScoreResult, out_dir: str | pathlib.Path) -> list[pathlib.Path]:
    plt = _plt()
    plan = result.plan
    tracks = {c: np.concatenate([t.reshape(-1, 3) for t, _ in ts]) for c, ts in result.wrist_tracks.items() if ts}
    first = {c: ts[0] for c, ts in result.wrist_tracks.items() if ts}
    if plan.reference not in tracks:
        return []
    ref = tracks[plan.reference]
    lo = np.percentile(ref, 0.5, axis=0)
    hi = np.percentile(ref, 99.5, axis=0)
    pad = 0.25 * (hi - lo) + 1e-6
    lo, hi = lo - pad, hi + pad
    conds = [c for c in plan.conditions if c in tracks]
    fig, axes = plt.subplots(2, len(conds), figsize=(2.6 * len(conds) + 0.6, 6.0), squeeze=False)
    for ax, c in zip(axes[1], conds):
        track, rate = first[c]
        t = np.arange(len(track)) / rate
        for w in range(track.shape[1]):
            ax.plot(t, track[:, w, 1], lw=1)
        ax.set_ylim(lo[1], hi[1])
        ax.set_xlabel("time (s), first sequence", fontsize=8)
        ax.tick_params(labelsize=7)
    axes[1][0].set_ylabel("wrist height y (units)", fontsize=8)
    for ax, c in zip(axes[0], conds):
        t = tracks[c]
        ax.hist2d(t[:, 0], t[:, 1], bins=40, range=[[lo[0], hi[0]], [lo[1], hi[1]]], cmap="magma", cmin=1)
        ax.set_title(c, fontsize=9)
        ax.set_aspect("equal")
        ax.set_xlabel("lateral x (units)", fontsize=8)
        ax.tick_params(labelsize=7)
    axes[0][0].set_ylabel("height y (units)", fontsize=8)
    fig.suptitle("wrist positions: distribution over all frames (top), height over time (bottom); "
                 "relative to the root on the ground plane", fontsize=9)
    fig.tight_layout()
    paths = _save(fig, pathlib.Path(out_dir) / "wrist_distribution")
    plt.close(fig)
    return paths


def gac_figure(result: ScoreResult, out_dir: str | pathlib.Path) -> list[pathlib.Path]:
    data = result.figure_data.get("gac", {})
    conds = [c for c in result.plan.conditions if c in data]
    if not conds:
        return []
    plt = _plt()
    fig, axes = plt.subplots(2, len(conds), figsize=(2.6 * len(conds) + 0.6, 5.6), squeeze=False)
    for col, c in enumerate(conds):
        d = data[c]
        packed_own, packed_nat, shape = d["first"]
        size = int(np.prod(shape))
        own = np.unpackbits(packed_own)[:size].reshape(shape).astype(bool)
        nat = np.unpackbits(packed_nat)[:size].reshape(shape).astype(bool)
        rgb = np.ones(shape + (3,))
        rgb[own & nat] = (0.45, 0.45, 0.45)
        rgb[own & ~nat] = (0.85, 0.2, 0.15)
        rgb[nat & ~own] = (0.2, 0.35, 0.85)
        axes[0][col].imshow(d["share"], cmap="Greys", vmin=0, vmax=1, interpolation="nearest")
        axes[0][col].set_title(c, fontsize=9)
        axes[1][col].imshow(rgb, interpolation="nearest")
        for ax in (axes[0][col], axes[1][col]):
            ax.set_xticks([])
            ax.set_yticks([])
    axes[0][0].set_ylabel("share of sequences", fontsize=8)
    axes[1][0].set_ylabel("first sequence: grey TP,\nred FP, blue FN", fontsize=8)
    fig.suptitle(f"Gesture Area Coverage ({data[conds[0]]['convention']})", fontsize=9)
    fig.tight_layout()
    paths = _save(fig, pathlib.Path(out_dir) / "gac_coverage")
    plt.close(fig)
    return paths


def fgd_inf_figure(result: ScoreResult, out_dir: str | pathlib.Path) -> list[pathlib.Path]:
    data = result.figure_data.get("fgd_inf", {})
    if not data:
        return []
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for cond, d in data.items():
        x = 1.0 / np.asarray(d["ns"], dtype=float)
        draws = np.asarray(d["draws"])
        line = ax.plot([0.0, x.max()], [d["value"], d["value"] + d["slope"] * x.max()], lw=1.2,
                       label=f"{cond}: FGD∞ = {d['value']:.4g}")[0]
        ax.scatter(np.repeat(x, draws.shape[1]), draws.ravel(), s=4, alpha=0.3, color=line.get_color())
        ax.plot(x, d["fgd_n"], "o", ms=4, color=line.get_color())
    ax.set_xlim(left=0.0)
    ax.set_xlabel("1 / N (N: windows per side)")
    ax.set_ylabel("FGD")
    ax.set_title("FGD against 1/N and its extrapolation to N = ∞", fontsize=9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    paths = _save(fig, pathlib.Path(out_dir) / "fgd_inf")
    plt.close(fig)
    return paths


def write_figures(result: ScoreResult, out_dir: str | pathlib.Path) -> list[pathlib.Path]:
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    return (histogram_figures(result, out) + wrist_distribution_figure(result, out) + gac_figure(result, out)
            + fgd_inf_figure(result, out))
