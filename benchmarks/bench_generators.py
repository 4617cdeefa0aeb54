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
and back to the corpus's rate: the best any 20-fps model can do. Its energy / wrist-speed r is lower than the
natural motion's at the corpus's rate (0.50 against 0.60 on the seed-0 corpus), because the wrist's flick within
each syllable lasts about four frames at 20 fps and the resampling's interpolation smooths it.

Usage: python benchmarks/bench_generators.py [--minutes 30] [--budget 10] [--only NAME ...] [--out DIR]
Prints one table (Markdown) and writes it to OUT/criteria.md and .csv.
"""
from __future__ import annotations

import argparse
import json
import pathlib
import sys
import tempfile
import time

import pandas as pd

from evalsuite.corpus import load_corpus
from evalsuite.corpus.synth.corpus import synthesize_corpus
from evalsuite.generators import find_generator
from evalsuite.generators.evaluation import evaluate_condition, natural_through_rate, swapped_audio
from evalsuite.generators.pose_repr import MODEL_FPS
from evalsuite.generators.registry import BUILTIN
from evalsuite.generators.requests import requests_from_corpus
from evalsuite.generators.runner import generate
from evalsuite.generators.training import train

# row label -> (generator, options); "gesticulator-audio" is the paper's audio-only ablation
SYSTEMS: dict[str, tuple[str, dict]] = {
    "gesticulator": ("gesticulator", {}), "gesticulator-audio": ("gesticulator", {"inputs": "audio"}),
    "aud2pose": ("aud2pose", {}), "aud2motion": ("aud2motion", {}), "aud2repr2pose": ("aud2repr2pose", {}),
    "gesture2vec": ("gesture2vec", {}), "ferstl-mogan": ("ferstl-mogan", {})}
AUDIO_DRIVEN = {"gesticulator", "aud2pose", "aud2motion", "aud2repr2pose", "ferstl-mogan"}


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
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=pathlib.Path, default=None)
    args = ap.parse_args(argv)
    out = args.out or pathlib.Path(tempfile.mkdtemp(prefix="bench-generators-"))
    corpus_dir = out / "corpus"
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
    rows = [{"generator": "natural via 20 fps", "pose_err_vs_mean_pose": ceiling["pose_mse"] / base["pose_mse"],
             "energy_speed_r": ceiling.get("energy_speed_r"),
             "lexical_vs_natural": ceiling["lexical_mean"] / natural["lexical_mean"]}]
    print(json.dumps({k: (round(v, 3) if isinstance(v, float) else v) for k, v in rows[0].items()}), flush=True)
    for name, (generator, config) in SYSTEMS.items():
        if generator not in BUILTIN or (args.only and name not in args.only):
            continue
        entry = find_generator(generator)
        t1 = time.perf_counter()
        result = train(entry, corpus, out / "models" / name, seed=args.seed, budget_minutes=args.budget,
                       config=config, progress=False)
        train_s = time.perf_counter() - t1
        t2 = time.perf_counter()
        generate(entry, reqs, out / name, model_dir=out / "models" / name, progress=False, check_determinism=False)
        gen_s = time.perf_counter() - t2
        own = evaluate_condition(out / name, corpus)
        row = {"generator": name, "epochs": len(result.history), "train_s": round(train_s),
               "speed_x_realtime": round(speech_s / gen_s), "pose_err_vs_mean_pose": own["pose_mse"] / base["pose_mse"],
               "energy_speed_r": own.get("energy_speed_r"),
               "lexical_vs_natural": own["lexical_mean"] / natural["lexical_mean"],
               "weights_sha256": json.loads((out / "models" / name / "model.json").read_text()).get("weights_sha256",
                                                                                                   "")[:12]}
        if generator in AUDIO_DRIVEN:
            generate(entry, swapped_audio(reqs), out / f"{name}_swapped", model_dir=out / "models" / name,
                     progress=False, check_determinism=False)
            row["swapped_audio_err_ratio"] = evaluate_condition(out / f"{name}_swapped", corpus)["pose_mse"] / own["pose_mse"]
        if name == "gesticulator":
            generate(entry, reqs, out / f"{name}_text_only", model_dir=out / "models" / name,
                     config={"zero_audio": True}, progress=False, check_determinism=False)
            row["lexical_text_only_vs_natural"] = (evaluate_condition(out / f"{name}_text_only", corpus)["lexical_mean"]
                                                   / natural["lexical_mean"])
        rows.append(row)
        print(json.dumps({k: (round(v, 3) if isinstance(v, float) else v) for k, v in row.items()}), flush=True)
    table = pd.DataFrame(rows)
    print(markdown(table))
    table.to_csv(out / "criteria.csv", index=False)
    (out / "criteria.md").write_text(markdown(table) + "\n")
    print(f"mean_pose pose error {base['pose_mse']:.2f} units^2; natural lexical mean {natural['lexical_mean']:.2f}; "
          f"natural energy / wrist-speed r {natural.get('energy_speed_r', float('nan')):.3f}; outputs in {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
