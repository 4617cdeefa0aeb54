"""``evalsuite critic train|score``: a Bradley-Terry head on a frozen encoder, learned from pairwise votes."""
from __future__ import annotations

import json
import pathlib

import click
import numpy as np
import pandas as pd
from tqdm import tqdm

from evalsuite.critic.core import ENCODERS, MOTION_SUFFIXES, evaluate, find_motion, fit_head, load_votes
from evalsuite.errors import InputError
from evalsuite.motion.io import load_motion


def _embedder(encoder: str, fgd_model, fps: float):
    windows_of = ENCODERS.get(encoder).make({"fgd_model": fgd_model})

    def run(path: pathlib.Path) -> np.ndarray:
        feats = np.asarray(windows_of(load_motion(path, fallback_fps=fps)), dtype=float)
        if feats.ndim != 2 or not len(feats):
            raise InputError(f"the {encoder} encoder gave no window features", path=path)
        return feats
    return run


@click.group()
def critic():
    """A scorer learned from pairwise votes (Bradley-Terry head on a frozen motion encoder)."""


@critic.command("train")
@click.argument("votes", type=click.Path(dir_okay=False, path_type=pathlib.Path))
@click.option("--motion", "motion_dir", required=True, type=click.Path(file_okay=False, path_type=pathlib.Path),
              help="Folder with MOTION/<condition>/<segment>.bvh (or .npy/.npz/.csv) for every voted stimulus.")
@click.option("-o", "--out", "out_dir", type=click.Path(file_okay=False, path_type=pathlib.Path),
              default=pathlib.Path("critic"), show_default=True,
              help="Folder for critic.npz (the head) and agreement.csv (the held-out evaluation).")
@click.option("--encoder", default="kinematic", show_default=True,
              help=f"Frozen encoder: {', '.join(ENCODERS.names())} (or an installed plug-in's).")
@click.option("--fgd-model", type=click.Path(dir_okay=False, path_type=pathlib.Path), default=None,
              help="FGD model file for --encoder fgd (e.g. from `evalsuite fgd train`).")
@click.option("--natural", default=None,
              help="The natural condition: the Fréchet distance to it is the baseline scored on the same votes.")
@click.option("--study", default=None, help="Study id in a results.csv holding several.")
@click.option("--question", default=None, help="The pairwise question to learn (needed when there are several).")
@click.option("--fps", type=float, default=30.0, show_default=True, help="Frame rate of files that do not state it.")
@click.option("--l2", type=click.FloatRange(0, min_open=True), default=1.0, show_default=True,
              help="L2 penalty of the head.")
@click.option("--folds", type=click.IntRange(2), default=5, show_default=True, help="Rater folds of the by-rater split.")
@click.option("--bootstrap", "n_boot", type=click.IntRange(1), default=1000, show_default=True,
              help="Rater resamples of the agreement CIs.")
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of the folds and the bootstrap.")
def train(votes, motion_dir, out_dir, encoder, fgd_model, natural, study, question, fps, l2, folds, n_boot, seed):
    """Train the head on the pairwise votes in VOTES (an evalsuite results.csv or a battles CSV) and report it
    only with held-out agreement (by rater and by system) beside the Fréchet distance's on the same votes."""
    v = load_votes(votes, study, question)
    embed = _embedder(encoder, fgd_model, fps)
    stimuli = sorted(set(zip(v["condition_a"], v["segment"])) | set(zip(v["condition_b"], v["segment"])))
    conds = sorted({c for c, _ in stimuli} | ({natural} if natural else set()))
    segments = sorted({s for _, s in stimuli})
    voted = set(stimuli)
    feats, pooled = {}, {}
    for c in tqdm(conds, desc="encoding", unit="condition"):
        mine = [s for s in segments if (c, s) in voted or c == natural]
        per = [embed(find_motion(motion_dir, c, s)) for s in mine]
        feats.update({(c, s): f.mean(0) for s, f in zip(mine, per)})
        pooled[c] = np.concatenate(per)
    table = evaluate(v, feats, pooled, natural, folds=folds, n_boot=n_boot, seed=seed, l2=l2)
    decided = v[v["answer"] != "tie"]
    ea = np.stack([feats[(a, s)] for a, s in zip(decided["condition_a"], decided["segment"])])
    eb = np.stack([feats[(b, s)] for b, s in zip(decided["condition_b"], decided["segment"])])
    both = np.concatenate([ea, eb])
    mu, sd = both.mean(0), both.std(0) + 1e-9
    w = fit_head((ea - eb) / sd, (decided["answer"] == "a").to_numpy(float), l2)
    out_dir.mkdir(parents=True, exist_ok=True)
    np.savez(out_dir / "critic.npz", w=w, mean=mu, std=sd,
             meta=json.dumps({"encoder": encoder, "fgd_model": str(fgd_model or ""), "fps": fps, "l2": l2,
                              "votes": str(votes), "n_votes": len(decided)}))
    table.to_csv(out_dir / "agreement.csv", index=False)
    click.echo(f"{len(decided)} decided votes ({int((v['answer'] == 'tie').sum())} ties left out) from "
               f"{v['participant'].nunique()} raters on {len(conds)} conditions; encoder {encoder}")
    for _, r in table.iterrows():
        click.echo(f"held out by {r['split']:<6} {r['scorer']:<10} agreement {r['agreement']:.3f} "
                   f"[{r['ci_low']:.3f}, {r['ci_high']:.3f}] on {r['n_votes']} votes")
    click.echo(f"Wrote {out_dir / 'critic.npz'} and {out_dir / 'agreement.csv'}")


@critic.command("score")
@click.argument("model", type=click.Path(dir_okay=False, path_type=pathlib.Path))
@click.option("--motion", "motion_dir", required=True, type=click.Path(file_okay=False, path_type=pathlib.Path),
              help="Folder with MOTION/<condition>/<segment>.<bvh|npy|npz|csv> to score.")
@click.option("-o", "--out", type=click.Path(dir_okay=False, path_type=pathlib.Path),
              default=pathlib.Path("critic_scores.csv"), show_default=True,
              help="condition,metric,value table (the mean score over segments; `evalsuite correlate` reads it); "
                   "per-segment scores go beside it as *_per_segment.csv.")
def score(model, motion_dir, out):
    """Score every motion under --motion with a head from `evalsuite critic train` (higher: preferred)."""
    try:
        with np.load(model) as z:
            w, mu, sd, meta = z["w"], z["mean"], z["std"], json.loads(str(z["meta"]))
    except (OSError, KeyError, ValueError) as exc:
        raise InputError(f"not a critic.npz from `evalsuite critic train` ({exc})", path=model) from None
    embed = _embedder(meta["encoder"], meta["fgd_model"] or None, float(meta["fps"]))
    files = sorted(p for p in motion_dir.glob("*/*") if p.suffix in MOTION_SUFFIXES)
    if not files:
        raise InputError("no motion files: expected MOTION/<condition>/<segment>.bvh", path=motion_dir)
    rows = [dict(condition=p.parent.name, segment=p.stem, score=float((embed(p).mean(0) - mu) / sd @ w))
            for p in tqdm(files, desc="scoring", unit="file")]
    per = pd.DataFrame(rows)
    per.to_csv(out.with_name(out.stem + "_per_segment.csv"), index=False)
    means = per.groupby("condition", as_index=False)["score"].mean()
    pd.DataFrame({"condition": means["condition"], "metric": "critic", "value": means["score"],
                  "better": "higher"}).to_csv(out, index=False)
    for _, r in means.iterrows():
        click.echo(f"{r['condition']}: {r['score']:.3f}")
    click.echo(f"Wrote {out}")
