"""Benchmark of ``gesture2vec`` and ``ferstl-mogan`` (issue 15; to be merged into bench_generators.py).

1. Builds a 30-minute synthetic-speaker corpus (seed 15) unless ``--corpus`` names one.
2. Trains ``gesture2vec`` (defaults: K = 300, chunk 30, stride 10, cpu sizes) and ``ferstl-mogan`` with each
   ablation of the paper's Figure 1 (none, no_phase, no_realism, no_minibatch, no_displacement, mse_only), each
   on one torch thread with ``--budget-minutes`` (default 15); prints training time (target: under 15 minutes
   each) and generation speed on the test split (target: at least 100x real time).
3. Prints the criteria table (tests/test_generators_g2v.py, tests/test_generators_mogan.py), and writes the
   Figure 1-style distribution plots (speed / acceleration histograms and wrist positions of ferstl-mogan, its
   ablations and natural motion) with evalsuite.metrics.figures into ``OUT/figures``.

Usage: python benchmarks/bench_generators_g2v_mogan.py [-o OUT] [--corpus DIR] [--minutes 30] [--budget-minutes 15]
       [--ablations none,mse_only] [--quick]
Other processes on the machine slow every figure down; the script prints the load average.
"""
from __future__ import annotations

import argparse
import json
import os
import pathlib
import time

import numpy as np

ABLATIONS = ("none", "no_phase", "no_realism", "no_minibatch", "no_displacement", "mse_only")


def _timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


def _generate(name, corpus, out, model, config=None, samples=1):
    from evalsuite.generators import find_generator
    from evalsuite.generators.requests import requests_from_corpus
    from evalsuite.generators.runner import generate

    reqs = requests_from_corpus(corpus, "test", 20.0)
    _, seconds = _timed(lambda: generate(find_generator(name), reqs, out, model_dir=model, seed=0, samples=samples,
                                         config=config or {}, progress=False, check_determinism=False))
    speech = sum(r.duration for r in reqs) * samples
    return speech / seconds


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("-o", "--out", default="bench_g2v_mogan_out")
    ap.add_argument("--corpus")
    ap.add_argument("--minutes", type=float, default=30.0)
    ap.add_argument("--budget-minutes", type=float, default=15.0)
    ap.add_argument("--ablations", default=",".join(ABLATIONS))
    ap.add_argument("--quick", action="store_true", help="6-minute corpus, 3-minute budgets, none + mse_only")
    args = ap.parse_args()
    if args.quick:
        args.minutes, args.budget_minutes, args.ablations = 6.0, 3.0, "none,mse_only"
    from evalsuite.corpus import load_corpus
    from evalsuite.corpus.synth.corpus import synthesize_corpus
    from evalsuite.generators import criteria as C
    from evalsuite.generators import find_generator
    from evalsuite.generators.evaluation import evaluate_condition, segment_scores
    from evalsuite.generators.gesture2vec.plugin import Gesture2Vec, code_usage
    from evalsuite.generators.gesture2vec.training import latent_windows
    from evalsuite.generators.training import train

    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    print(f"load average at start: {os.getloadavg()}")
    root = pathlib.Path(args.corpus) if args.corpus else out / "corpus"
    if not args.corpus and not (root / "corpus.json").is_file():
        _, s = _timed(lambda: synthesize_corpus(root, args.minutes, 15, jobs=2, progress=False))
        print(f"corpus: {args.minutes:g} minutes synthesised in {s:.0f} s")
    corpus = load_corpus(root)
    rows = []
    nat_rows = [segment_scores(s.load_motion(), s) for s in corpus.split("test")]
    oracle_lex = float(np.nanmean([np.nanmean([r.get(f"lexical_{c}", np.nan) for r in nat_rows])
                                   for c in ("up", "wide", "self", "point")]))
    # -- gesture2vec ------------------------------------------------------------------------------------------
    res, secs = _timed(lambda: train(find_generator("gesture2vec"), corpus, out / "gesture2vec", seed=0,
                                     budget_minutes=args.budget_minutes, progress=False))
    speed = _generate("gesture2vec", corpus, out / "gen" / "gesture2vec", out / "gesture2vec")
    scores = evaluate_condition(out / "gen" / "gesture2vec", corpus)
    g = Gesture2Vec()
    g.load({}, out / "gesture2vec")
    nsd = C.latent_nsd([latent_windows(g.model, g.rep.encode(s.load_motion())) for s in corpus.split("test")])
    _generate("mean_pose", corpus, out / "gen" / "mean_pose", None)
    fgd = C.fgd_against_natural(corpus, {k: C.generated_motions(out / "gen" / k, corpus)
                                         for k in ("gesture2vec", "mean_pose")})
    k = res.meta["codebook"]
    rows += [("gesture2vec", "lexical_mean >= 0.5 x natural", scores["lexical_mean"], ">=", 0.5 * oracle_lex),
             ("gesture2vec", "code perplexity > 0.3 K", res.meta["code_perplexity"], ">", 0.3 * k),
             ("gesture2vec", "latent NSD < shuffled control", nsd["nsd"], "<", nsd["nsd_shuffled"]),
             ("gesture2vec", "FGD < mean_pose's", fgd["gesture2vec"], "<", fgd["mean_pose"])]
    usage = code_usage(out / "gen" / "gesture2vec", out / "gesture2vec")
    print(f"gesture2vec: trained in {secs:.0f} s (stopped by budget: {res.meta['stopped_by_budget']}), "
          f"generation {speed:.0f}x real time, {res.meta['codes_used']} of {k} codes used, usage {usage}")
    # -- ferstl-mogan and its ablations -----------------------------------------------------------------------
    natural = C.natural_motions(corpus, "test", 20.0)
    nat_div = C.diversity(natural)
    measured = {}
    for ab in args.ablations.split(","):
        name = "ferstl-mogan" if ab == "none" else f"ferstl-mogan_{ab}"
        res, secs = _timed(lambda ab=ab, name=name: train(
            find_generator("ferstl-mogan"), corpus, out / name, seed=0, budget_minutes=args.budget_minutes,
            config={"ablation": ab}, progress=False))
        speed = _generate("ferstl-mogan", corpus, out / "gen" / name, out / name, samples=2)
        _generate("ferstl-mogan", corpus, out / "fig" / name, out / name)   # one sample, named as natural, for the figures
        g0 = C.generated_motions(out / "gen" / name, corpus, sample=0)
        g1 = C.generated_motions(out / "gen" / name, corpus, sample=1)
        measured[ab] = {"hellinger": C.wrist_speed_hellinger(g0, natural), **C.diversity(g0),
                        "energy_speed_r": evaluate_condition(out / "gen" / name, corpus)["energy_speed_r"],
                        "sample_diff_cm": float(np.mean([np.abs(g0[s].positions() - g1[s].positions()).mean()
                                                         for s in g0])),
                        "f1": res.meta["phase_classifier_f1"], "train_s": secs, "speed_x": speed,
                        "stopped": res.meta["stopped_by_budget"]}
        print(f"{name}: trained in {secs:.0f} s, generation {speed:.0f}x real time, {measured[ab]}")
    if "none" in measured:
        full = measured["none"]
        rows += [("ferstl-mogan", "phase classifier F1 (reported)", full["f1"], "report", float("nan")),
                 ("ferstl-mogan", "energy/wrist-speed r >= 0.3", full["energy_speed_r"], ">=", 0.3),
                 ("ferstl-mogan", "k samples differ (mean cm)", full["sample_diff_cm"], ">", 0.01)]
        if "mse_only" in measured:
            mse = measured["mse_only"]
            rows.append(("ferstl-mogan", "wrist-speed Hellinger < mse_only's", full["hellinger"], "<",
                         mse["hellinger"]))
            for key in ("l1div", "div_k"):
                rows.append(("ferstl-mogan", f"|{key} - natural| < mse_only's", abs(full[key] - nat_div[key]), "<",
                             abs(mse[key] - nat_div[key])))
    print(f"\nnatural diversity {nat_div}, natural lexical_mean {oracle_lex:.3f}\n")
    print("| system | criterion | measured | bound | holds |\n|---|---|---|---|---|")
    tests = {">=": lambda v, b: v >= b, ">": lambda v, b: v > b, "<": lambda v, b: v < b}
    for system, what, value, op, bound in rows:
        holds = "reported" if op == "report" else ("yes" if tests[op](value, bound) else "NO")
        print(f"| {system} | {what} | {value:.4g} | {bound:.4g} | {holds} |")
    # -- Figure 1-style plots -----------------------------------------------------------------------------
    from evalsuite.metrics.engine import score_folders
    from evalsuite.metrics.figures import write_figures
    from evalsuite.motion.presets import GENEA2020_UPPER

    (out / "criteria.json").write_text(json.dumps({"rows": rows, "mogan": measured}, indent=1, default=str))
    _generate("natural", corpus, out / "fig" / "natural", None)
    conds = [out / "fig" / ("ferstl-mogan" if ab == "none" else f"ferstl-mogan_{ab}") for ab in measured]
    result = score_folders(out / "fig" / "natural", [str(c) for c in conds], joints=",".join(GENEA2020_UPPER),
                           metrics="kinematics,histograms", progress=False)
    paths = write_figures(result, out / "figures")
    print(f"figures: {', '.join(p.name for p in paths)} in {out / 'figures'}; load average {os.getloadavg()}")


if __name__ == "__main__":
    main()
