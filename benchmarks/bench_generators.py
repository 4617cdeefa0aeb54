"""Learning criteria of the re-implemented generators on a synthetic-speaker corpus (issues 14 and 15).

For each trainable generator: train on the corpus's train split within a time budget (validation on its val
split), generate the test split, and measure on it, against the natural motion and speech:

* pose error (mean squared world-position error of the GENEA 2020 upper body) as a ratio to ``mean_pose``'s;
* the best energy / wrist-speed correlation within +-0.3 s;
* speech dependence: the pose error when every segment gets the next segment's audio, as a ratio to the
  error with its own audio (audio-driven generators);
* lexical contrast of the keyword classes (mean over up/wide/self/point) as a ratio to the natural motion's;
* training time, and generation speed as seconds of speech per second of computing.

A reference row, ``natural via 20 fps``, is the natural test motion resampled to the re-implementations' 20 fps
and back to the corpus's rate: what a 20-fps copy of the speaker's own performance keeps. Its energy / wrist-speed r is lower than the
natural motion's at the corpus's rate (0.50 against 0.60 on the seed-0 corpus), because the wrist's flick within
each syllable lasts about four frames at 20 fps and the resampling's interpolation smooths it.

A second reference row, ``mean of 16 performances via 20 fps``, is the mean world positions of 16 other
performances of each test segment's speech by the synthetic speaker (its conditional mean given the speech,
estimated), through 20 fps: what a deterministic model trained on the pose error converges to at best. Its energy /
wrist-speed r (0.54 on the seed-0 corpus) is what such a model can reach at 20 fps.

Two more reference rows, ``causal mean of 64 performances ...``, estimate the same for a causal model (Aud2Motion's
forward GRU hears the speech only up to the frame it outputs): per frame, the mean of 64 performances in which the
words not yet begun (or begun less than 0.3 s before) are drawn at random from the training transcripts
(``causal_mean_through_rate``). On the seed-0 corpus: pose error 0.41 and 0.48 x the mean pose's.

Issue 15's criteria follow for the systems of that issue that ran:

* ``gesture2vec``: lexical contrast against half the natural motion's, codebook perplexity against 0.3 K, the
  NSD of its latent space against a shuffled control, held-out FGD against ``mean_pose``'s;
* ``ferstl-mogan``, beside its ablations (``--mogan-ablations``, default the MSE-only one the criteria compare
  with): wrist-speed Hellinger distance to natural, ``l1div`` / ``div_k`` distance to natural, energy / wrist-speed
  r, the difference of two samples per segment, the phase classifier's F1; and the paper's Figure 1-style
  distribution plots of the full model, its ablations and natural motion (OUT/figures).

With ``--train-seeds 0,1,2,3,4`` each system is trained once per seed (the paper of Aud2Repr2Pose averaged five
re-trainings): one row per training, then a summary per system (mean and spread of the pose error and r, and in
how many trainings issue 14's criteria held). ``--set KEY=VALUE`` passes an option to every system trained, to
measure a variant the same way (e.g. ``--only aud2repr2pose --set dae_inputs=poses``).

Usage: python benchmarks/bench_generators.py [--minutes 30] [--seed 0] [--train-seed S | --train-seeds S,S,...]
       [--corpus DIR] [--budget 9] [--only NAME ...] [--set KEY=VALUE ...] [--mogan-ablations mse_only,...]
       [--out DIR] [--preset cpu-small|paper]
Every row names the preset the systems were trained with (evalsuite train --preset; docs/generators.md).
Prints the tables (Markdown) and writes them to OUT/criteria.md / .csv, OUT/criteria_seeds.md (with several
training seeds) and OUT/criteria_issue15.md / .json.
Other processes on the machine slow every timing down; the script prints the load average.
"""
from __future__ import annotations

import argparse
import json
import os
import pathlib
import sys
import tempfile
import time

import numpy as np
import pandas as pd

from evalsuite.corpus import load_corpus
from evalsuite.generators import find_generator
from evalsuite.generators.evaluation import (
    causal_mean_through_rate,
    conditional_mean_through_rate,
    evaluate_condition,
    natural_through_rate,
    swapped_audio,
)
from evalsuite.generators.pose_repr import MODEL_FPS
from evalsuite.generators.registry import BUILTIN
from evalsuite.generators.requests import requests_from_corpus
from evalsuite.generators.runner import generate
from evalsuite.generators.training import train
from evalsuite.synth.corpus import synthesize_corpus

# row label -> (generator, options); "gesticulator-audio" is the paper's audio-only ablation
SYSTEMS: dict[str, tuple[str, dict]] = {
    "gesticulator": ("gesticulator", {}), "gesticulator-audio": ("gesticulator", {"inputs": "audio"}),
    "aud2pose": ("aud2pose", {}), "aud2motion": ("aud2motion", {}), "aud2repr2pose": ("aud2repr2pose", {}),
    "gesture2vec": ("gesture2vec", {}), "ferstl-mogan": ("ferstl-mogan", {})}
AUDIO_DRIVEN = {"gesticulator", "aud2pose", "aud2motion", "aud2repr2pose", "ferstl-mogan"}
MOGAN_ABLATIONS = ("no_phase", "no_realism", "no_minibatch", "no_displacement", "mse_only")
HOLDS = {">=": lambda v, b: v >= b, ">": lambda v, b: v > b, "<": lambda v, b: v < b}
CAUSAL_HEARD_AFTER = (0.0, 0.3)  # the causal reference rows: a word known at its start, or 0.3 s into it
ISSUE14 = {"gesticulator", "aud2pose", "aud2motion", "aud2repr2pose"}   # the systems issue 14's criteria judge


def issue14_holds(row: dict) -> bool:
    """Issue 14's learning criteria for one training's row: pose error <= 0.6 x mean pose's, r >= 0.5, >= +20 %
    error with another segment's audio; for gesticulator also lexical contrast >= half natural's, and present
    (> 0) with the audio silenced."""
    ok = (row["pose_err_vs_mean_pose"] <= 0.6 and row["energy_speed_r"] >= 0.5
          and row["swapped_audio_err_ratio"] >= 1.2)
    if row["generator"] == "gesticulator":
        ok = ok and row["lexical_vs_natural"] >= 0.5 and row["lexical_text_only_vs_natural"] > 0
    return bool(ok)


def seeds_summary(rows: list[dict]) -> pd.DataFrame:
    """Per system trained with several seeds: mean and standard deviation (ddof 1) of the pose error and r, their
    range, and in how many trainings issue 14's criteria held."""
    table = pd.DataFrame([r for r in rows if "train_seed" in r])
    out = []
    for name, group in table.groupby("generator", sort=False):
        pose, r = group["pose_err_vs_mean_pose"], group["energy_speed_r"]
        out.append({"generator": name, "trainings": len(group),
                    "pose_err mean": pose.mean(), "pose_err sd": pose.std(), "pose_err range": f"{pose.min():.3f}-{pose.max():.3f}",
                    "r mean": r.mean(), "r sd": r.std(), "r range": f"{r.min():.3f}-{r.max():.3f}",
                    "criteria held": (f"{sum(issue14_holds(row) for row in group.to_dict('records'))} of {len(group)}"
                                      if name in ISSUE14 else "")})
    return pd.DataFrame(out)


def markdown(table: pd.DataFrame) -> str:
    cols = list(table.columns)
    fmt = [[f"{v:.3g}" if isinstance(v, float) else str(v) for v in row] for row in table.itertuples(index=False)]
    lines = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    return "\n".join(lines + ["| " + " | ".join(r) + " |" for r in fmt])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--minutes", type=float, default=30.0)
    ap.add_argument("--budget", type=float, default=9.0, help="training budget per generator, minutes")
    ap.add_argument("--only", nargs="*", default=None)
    ap.add_argument("--seed", type=int, default=0, help="the synthetic corpus's seed")
    ap.add_argument("--train-seed", type=int, default=None, help="the trainings' seed (default: --seed)")
    ap.add_argument("--train-seeds", default=None,
                    help="comma-separated training seeds: each system trained once per seed, then summarised")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", dest="options",
                    help="an option for every system trained (repeatable)")
    ap.add_argument("--corpus", type=pathlib.Path, default=None, help="an existing corpus instead of a new one")
    ap.add_argument("--mogan-ablations", default="mse_only",
                    help=f"ferstl-mogan ablations trained beside it, comma-separated: {', '.join(MOGAN_ABLATIONS)}")
    ap.add_argument("--out", type=pathlib.Path, default=None)
    ap.add_argument("--preset", default="cpu-small", choices=("cpu-small", "paper"),
                    help="the systems' preset (evalsuite train --preset); --set options override it")
    args = ap.parse_args(argv)
    ablations = [a for a in args.mogan_ablations.split(",") if a]
    unknown = sorted(set(ablations) - set(MOGAN_ABLATIONS))
    if unknown:
        ap.error(f"--mogan-ablations: unknown {unknown}; expected some of {', '.join(MOGAN_ABLATIONS)}")
    if args.train_seeds and args.train_seed is not None:
        ap.error("--train-seed and --train-seeds exclude each other")
    try:
        seeds = ([int(v) for v in args.train_seeds.split(",")] if args.train_seeds
                 else [args.seed if args.train_seed is None else args.train_seed])
    except ValueError:
        ap.error(f"--train-seeds: expected comma-separated integers, got {args.train_seeds!r}")
    bad = [o for o in args.options if "=" not in o]
    if bad:
        ap.error(f"--set: expected KEY=VALUE, got {bad[0]!r}")
    options = dict(o.split("=", 1) for o in args.options)
    out = args.out or pathlib.Path(tempfile.mkdtemp(prefix="bench-generators-"))
    corpus_dir = args.corpus or out / "corpus"
    print(f"load average at start: {os.getloadavg()}", flush=True)
    t0 = time.perf_counter()
    if not (corpus_dir / "corpus.json").is_file():
        synthesize_corpus(corpus_dir, args.minutes, seed=args.seed, progress=False)
    corpus = load_corpus(corpus_dir)
    print(f"corpus: {len(corpus)} segments, {sum(s.duration or 0 for s in corpus) / 60:.1f} min "
          f"({time.perf_counter() - t0:.0f} s)", flush=True)
    reqs = requests_from_corpus(corpus, "test", 30.0)
    speech_s = sum(r.duration for r in reqs)
    train_bvh = corpus_dir / "trn" / "main-agent" / "bvh"
    generate(find_generator("mean_pose"), reqs, out / "mean_pose", config={"from": str(train_bvh)}, progress=False)
    generate(find_generator("natural"), reqs, out / "natural", progress=False)
    base = evaluate_condition(out / "mean_pose", corpus)
    natural = evaluate_condition(out / "natural", corpus)
    ceiling = evaluate_condition(natural_through_rate(corpus, out / "natural_via_20fps", MODEL_FPS), corpus)
    best = evaluate_condition(conditional_mean_through_rate(corpus, out / "conditional_mean_via_20fps", 16,
                                                            MODEL_FPS), corpus)
    references = [("natural via 20 fps", ceiling), ("mean of 16 performances via 20 fps", best)]
    for heard_after in CAUSAL_HEARD_AFTER:
        folder = causal_mean_through_rate(corpus, out / f"causal_mean_{heard_after:g}s_via_20fps", 64, MODEL_FPS,
                                          heard_after=heard_after)
        known = "from its start" if heard_after == 0 else f"from {heard_after:g} s into it"
        references.append((f"causal mean of 64 performances via 20 fps (each word known {known})",
                           evaluate_condition(folder, corpus)))
    rows = [{"generator": label, "pose_err_vs_mean_pose": ref["pose_mse"] / base["pose_mse"],
             "energy_speed_r": ref.get("energy_speed_r"),
             "lexical_vs_natural": ref["lexical_mean"] / natural["lexical_mean"]}
            for label, ref in references]
    for row in rows:
        print(json.dumps({k: (round(v, 3) if isinstance(v, float) else v) for k, v in row.items()}), flush=True)
    trained = {}
    runs = [(name, seed) for name, (generator, _) in SYSTEMS.items() for seed in seeds
            if generator in BUILTIN and (not args.only or name in args.only)]
    for name, seed in runs:
        generator, config = SYSTEMS[name]
        config = {**config, **options}
        entry = find_generator(generator)
        run = name if len(seeds) == 1 else f"{name}_seed{seed}"   # folder names
        t1 = time.perf_counter()
        result = train(entry, corpus, out / "models" / run, seed=seed, budget_minutes=args.budget,
                       config=config, progress=False, preset=args.preset)
        train_s = time.perf_counter() - t1
        t2 = time.perf_counter()
        generate(entry, reqs, out / run, model_dir=out / "models" / run, progress=False, check_determinism=False)
        gen_s = time.perf_counter() - t2
        own = evaluate_condition(out / run, corpus)
        trained.setdefault(name, (result, train_s, own))   # issue 15's rows: the first seed's model
        row = {"generator": name, "preset": args.preset, **({"train_seed": seed} if len(seeds) > 1 else {}),
               "epochs": len(result.history), "train_s": round(train_s),
               "speed_x_realtime": round(speech_s / gen_s), "pose_err_vs_mean_pose": own["pose_mse"] / base["pose_mse"],
               "energy_speed_r": own.get("energy_speed_r"),
               "lexical_vs_natural": own["lexical_mean"] / natural["lexical_mean"],
               "weights_sha256": json.loads((out / "models" / run / "model.json").read_text()).get("weights_sha256",
                                                                                                  "")[:12]}
        if generator in AUDIO_DRIVEN:
            generate(entry, swapped_audio(reqs), out / f"{run}_swapped", model_dir=out / "models" / run,
                     progress=False, check_determinism=False)
            row["swapped_audio_err_ratio"] = evaluate_condition(out / f"{run}_swapped", corpus)["pose_mse"] / own["pose_mse"]
        if name == "gesticulator":
            generate(entry, reqs, out / f"{run}_text_only", model_dir=out / "models" / run,
                     config={"zero_audio": True}, progress=False, check_determinism=False)
            row["lexical_text_only_vs_natural"] = (evaluate_condition(out / f"{run}_text_only", corpus)["lexical_mean"]
                                                   / natural["lexical_mean"])
        rows.append(row)
        print(json.dumps({k: (round(v, 3) if isinstance(v, float) else v) for k, v in row.items()}), flush=True)
    table = pd.DataFrame(rows)
    print(markdown(table))
    table.to_csv(out / "criteria.csv", index=False)
    (out / "criteria.md").write_text(markdown(table) + "\n")
    if len(seeds) > 1:
        summary = markdown(seeds_summary(rows))
        print(summary)
        (out / "criteria_seeds.md").write_text(summary + "\n")
    print(f"mean_pose pose error {base['pose_mse']:.2f} units^2; natural lexical mean {natural['lexical_mean']:.2f}; "
          f"natural energy / wrist-speed r {natural.get('energy_speed_r', float('nan')):.3f}; outputs in {out}")
    issue15 = []
    if "gesture2vec" in trained:
        result, _, own = trained["gesture2vec"]
        issue15 += gesture2vec_rows(corpus, out, result, own["lexical_mean"], natural["lexical_mean"])
    if "ferstl-mogan" in trained:
        issue15 += ferstl_mogan_rows(corpus, out, trained["ferstl-mogan"][:2], ablations, seeds[0], args.budget,
                                     args.preset)
    if issue15:
        lines = [f"Preset: {args.preset}", "", "| system | criterion | measured | bound | holds |",
                 "|---|---|---|---|---|"]
        for system, what, value, op, bound in issue15:
            holds = "reported" if op == "report" else ("yes" if HOLDS[op](value, bound) else "**no**")
            lines.append(f"| {system} | {what} | {value:.4g} | {bound:.4g} | {holds} |")
        print("\n".join(lines))
        (out / "criteria_issue15.md").write_text("\n".join(lines) + "\n")
        (out / "criteria_issue15.json").write_text(json.dumps(issue15, indent=1))
    print(f"load average at the end: {os.getloadavg()}")
    return 0


def gesture2vec_rows(corpus, out: pathlib.Path, result, lexical: float, natural_lexical: float) -> list[tuple]:
    """Issue 15's criteria for the trained ``gesture2vec`` in OUT/models/gesture2vec (test split generated to
    OUT/gesture2vec, ``mean_pose`` to OUT/mean_pose)."""
    from evalsuite.generators import criteria as C
    from evalsuite.generators.gesture2vec.plugin import Gesture2Vec, code_usage
    from evalsuite.generators.gesture2vec.training import latent_windows

    model = Gesture2Vec()
    model.load({}, out / "models" / "gesture2vec")
    nsd = C.latent_nsd([latent_windows(model.model, model.rep.encode(s.load_motion())) for s in corpus.split("test")])
    fgd = C.fgd_against_natural(corpus, {k: C.generated_motions(out / k, corpus) for k in ("gesture2vec", "mean_pose")})
    k = result.meta["codebook"]
    usage = code_usage(out / "gesture2vec", out / "models" / "gesture2vec")
    print(f"gesture2vec: {result.meta['codes_used']} of {k} codes used; usage {usage}", flush=True)
    return [("gesture2vec", "lexical_mean >= 0.5 x natural", lexical, ">=", 0.5 * natural_lexical),
            ("gesture2vec", "code perplexity > 0.3 K", result.meta["code_perplexity"], ">", 0.3 * k),
            ("gesture2vec", "latent NSD < shuffled control", nsd["nsd"], "<", nsd["nsd_shuffled"]),
            ("gesture2vec", "FGD < mean_pose's", fgd["gesture2vec"], "<", fgd["mean_pose"])]


def ferstl_mogan_rows(corpus, out: pathlib.Path, full: tuple, ablations: list[str], seed: int,
                      budget: float, preset: str = "cpu-small") -> list[tuple]:
    """Issue 15's criteria for ``ferstl-mogan`` (trained in OUT/models/ferstl-mogan) against its ablations,
    each trained here with the same seed and budget; two samples per test segment; Figure 1-style plots."""
    from evalsuite.generators import criteria as C
    from evalsuite.metrics.engine import score_folders
    from evalsuite.metrics.figures import write_figures
    from evalsuite.motion.presets import GENEA2020_UPPER

    entry = find_generator("ferstl-mogan")
    reqs = requests_from_corpus(corpus, "test", MODEL_FPS)
    natural = C.natural_motions(corpus, "test", MODEL_FPS)
    nat_div = C.diversity(natural)
    measured = {}
    for ab in ["none", *ablations]:
        name = "ferstl-mogan" if ab == "none" else f"ferstl-mogan_{ab}"
        if ab == "none":
            result, train_s = full
        else:
            t1 = time.perf_counter()
            result = train(entry, corpus, out / "models" / name, seed=seed, budget_minutes=budget,
                           config={"ablation": ab}, progress=False, preset=preset)
            train_s = time.perf_counter() - t1
        t2 = time.perf_counter()
        generate(entry, reqs, out / "samples" / name, model_dir=out / "models" / name, samples=2, progress=False,
                 check_determinism=False)
        speed = 2 * sum(r.duration for r in reqs) / (time.perf_counter() - t2)
        # one sample more, named as the natural files are, which the figure code pairs by name
        generate(entry, reqs, out / "figure_input" / name, model_dir=out / "models" / name, progress=False,
                 check_determinism=False)
        g0 = C.generated_motions(out / "samples" / name, corpus, sample=0)
        g1 = C.generated_motions(out / "samples" / name, corpus, sample=1)
        measured[ab] = {"hellinger": C.wrist_speed_hellinger(g0, natural), **C.diversity(g0),
                        "energy_speed_r": evaluate_condition(out / "samples" / name, corpus)["energy_speed_r"],
                        "sample_diff_cm": float(np.mean([np.abs(g0[s].positions() - g1[s].positions()).mean()
                                                         for s in g0])),
                        "f1": result.meta["phase_classifier_f1"], "train_s": round(train_s),
                        "speed_x_realtime": round(speed)}
        print(f"{name}: {json.dumps({k: round(v, 4) for k, v in measured[ab].items()})}", flush=True)
    print(f"natural (test split, {MODEL_FPS:g} fps): {json.dumps({k: round(v, 4) for k, v in nat_div.items()})}")
    full_m = measured["none"]
    rows = [("ferstl-mogan", "phase classifier F1 (reported)", full_m["f1"], "report", float("nan")),
            ("ferstl-mogan", "energy/wrist-speed r >= 0.3", full_m["energy_speed_r"], ">=", 0.3),
            ("ferstl-mogan", "k samples differ (mean cm)", full_m["sample_diff_cm"], ">", 0.01)]
    if "mse_only" in measured:
        mse = measured["mse_only"]
        rows.append(("ferstl-mogan", "wrist-speed Hellinger < mse_only's", full_m["hellinger"], "<", mse["hellinger"]))
        rows += [("ferstl-mogan", f"|{key} - natural| < mse_only's", abs(full_m[key] - nat_div[key]), "<",
                  abs(mse[key] - nat_div[key])) for key in ("l1div", "div_k")]
    (out / "ferstl_mogan.json").write_text(json.dumps({"natural": nat_div, **measured}, indent=1))
    generate(find_generator("natural"), reqs, out / "figure_input" / "natural", progress=False)
    conditions = [str(out / "figure_input" / ("ferstl-mogan" if ab == "none" else f"ferstl-mogan_{ab}"))
                  for ab in measured]
    scored = score_folders(out / "figure_input" / "natural", conditions, joints=",".join(GENEA2020_UPPER),
                           metrics="kinematics,histograms", progress=False)
    paths = write_figures(scored, out / "figures")
    print(f"Figure 1-style plots: {', '.join(p.name for p in paths)} in {out / 'figures'}")
    return rows


if __name__ == "__main__":
    sys.exit(main())
