"""A short training of each re-implementation's ``paper`` preset beside its ``cpu-small`` preset (issue 39).

For each system, ``evalsuite train -g NAME --corpus DIR --preset P --set KEY=VALUE ...`` runs in a fresh process
with the same fixed budget for both presets: a number of epochs (steps) per stage, given in ``BUDGETS`` and
printed, never a wall-clock budget, so the load of the machine changes the times but not the weights. The paper
presets keep their architecture, losses, features and optimiser; only their schedule is cut to the budget (so is
``cpu-small``'s). ``patience`` is set to the epochs, so neither preset stops early. One training at a time.

Each model generates the corpus's test split, scored as ``benchmarks/bench_generators.py`` scores (against the
natural test motion and speech, :mod:`evalsuite.generators.evaluation` and :mod:`evalsuite.generators.criteria`):

* ``pose_err``: mean squared world-position error of the upper body, as a ratio to ``mean_pose``'s;
* ``r``: the best speech-energy / wrist-speed correlation within +-0.3 s;
* ``swap``: the pose error when each segment gets the next segment's audio, as a ratio to the error with its own;
* ``lexical``: lexical contrast of the keyword classes (mean over up/wide/self/point) as a ratio to natural's;
* ``hellinger``: wrist-speed histogram distance to natural; ``div_k``: spread of the poses (natural's is
  printed; near 0 is a collapse to one pose); ``fgd``: FGD against the natural test motion (one encoder, trained
  on the natural training split, for every row).

Reference rows measured in the same run: ``mean_pose`` (the training split's mean pose, the baseline) and
``natural via 20 fps`` (the natural test motion through the re-implementations' 20 fps). A training that fails
(an error, the divergence guard) is a row with its error, and the run goes on.

Usage: python benchmarks/bench_presets.py [--minutes 10] [--seed 0] [--corpus DIR] [--only NAME ...]
       [--presets cpu-small,paper] [--out DIR] [--markdown FILE] [--reuse-models]
``--reuse-models`` scores the models already in OUT/models (same preset and budget, else an error) instead of
training them again, e.g. after an interrupted run.
Prints one table (Markdown) and writes it with the command, date, load and corpus size to OUT/presets.md (and to
``--markdown`` when given); rows also to OUT/presets.json.
"""
from __future__ import annotations

import argparse
import datetime
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time
from typing import Any

# the fixed budget per system, the same for both presets: (options set, how it reads in the table)
BUDGETS: dict[str, tuple[dict[str, Any], str]] = {
    "gesticulator": ({"epochs": 20}, "20 epochs (paper schedule 95)"),
    "aud2pose": ({"epochs": 1, "patience": 1}, "1 epoch (paper 120)"),
    "aud2motion": ({"epochs": 15, "patience": 15}, "15 epochs (paper 500)"),
    "aud2repr2pose": ({"epochs": 1, "patience": 1, "dae_epochs": 3}, "DAE 3 + 1 epochs (paper 20 + 120)"),
    "gesture2vec": ({"dae_epochs": 3, "vq_epochs": 3, "vq_decoder_epochs": 3, "translation_epochs": 15},
                    "3 + 3 + 3 + 15 epochs (paper 20 + 20 + 20 + 250)"),
    "ferstl-mogan": ({"classifier_epochs": 5, "pretrain_epochs": 5, "adversarial_steps": 100,
                      "realism_pretrain_steps": 30}, "5 + 5 epochs, 30 + 100 steps (default 30 + 30, 100 + 400)"),
}
AUDIO_DRIVEN = {"gesticulator", "aud2pose", "aud2motion", "aud2repr2pose", "ferstl-mogan"}
COLUMNS = ("system", "preset", "parameters", "budget", "train_s", "pose_err", "r", "swap", "lexical", "hellinger",
           "div_k", "fgd")


def count_parameters(model_dir: pathlib.Path) -> int:
    """Number of tensor elements in the model folder's ``*.pt`` files (every network the plug-in saved)."""
    import torch

    def count(obj: Any) -> int:
        if isinstance(obj, torch.Tensor):
            return int(obj.numel())
        if isinstance(obj, dict):
            return sum(count(v) for v in obj.values())
        if isinstance(obj, (list, tuple)):
            return sum(count(v) for v in obj)
        return 0
    return sum(count(torch.load(p, map_location="cpu", weights_only=True)) for p in sorted(model_dir.glob("*.pt")))


def train_command(system: str, preset: str, corpus: pathlib.Path, out: pathlib.Path, seed: int) -> list[str]:
    """The ``evalsuite train`` command of one training with the system's budget."""
    sets = [a for k, v in BUDGETS[system][0].items() for a in ("--set", f"{k}={v}")]
    return [sys.executable, "-m", "evalsuite", "train", "-g", system, "--corpus", str(corpus), "--preset", preset,
            *sets, "--seed", str(seed), "--checkpoint-every", "off", "-o", str(out)]


def reusable(model_dir: pathlib.Path, system: str, preset: str) -> bool:
    """Whether ``model_dir`` holds a finished training of ``system`` with ``preset`` and this script's budget
    (``--reuse-models``); False when there is none, an error when it was trained otherwise."""
    if not (model_dir / "model.json").is_file():
        return False
    record = json.loads((model_dir / "model.json").read_text())
    config = record.get("config", {})
    if record.get("preset") != preset or any(config.get(k) != v for k, v in BUDGETS[system][0].items()):
        raise SystemExit(f"{model_dir}: trained with another preset or budget than {preset} "
                         f"{BUDGETS[system][1]}; remove it or drop --reuse-models")
    return True


def markdown(rows: list[dict[str, Any]]) -> str:
    def fmt(v: Any) -> str:
        if v is None or (isinstance(v, float) and v != v):
            return ""
        return f"{v:.3g}" if isinstance(v, float) else f"{v:,}" if isinstance(v, int) else str(v)
    lines = ["| " + " | ".join(COLUMNS) + " |", "|" + "---|" * len(COLUMNS)]
    return "\n".join(lines + ["| " + " | ".join(fmt(r.get(c)) for c in COLUMNS) + " |" for r in rows])


def score(folder: pathlib.Path, corpus: Any, base_mse: float, natural: dict[str, Any],
          natural_20: dict[str, Any]) -> dict[str, Any]:
    """The table's metrics of one generated folder (FGD is added for all folders at the end)."""
    from evalsuite.generators import criteria as C
    from evalsuite.generators.evaluation import evaluate_condition

    own = evaluate_condition(folder, corpus)
    gen = C.generated_motions(folder, corpus)
    return {"pose_err": own["pose_mse"] / base_mse, "r": own.get("energy_speed_r"),
            "lexical": own["lexical_mean"] / natural["lexical_mean"],
            "hellinger": C.wrist_speed_hellinger(gen, natural_20), "div_k": C.diversity(gen)["div_k"],
            "_pose_mse": own["pose_mse"]}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--minutes", type=float, default=10.0, help="minutes of the synthetic-speaker corpus made")
    ap.add_argument("--seed", type=int, default=0, help="the corpus's and the trainings' seed")
    ap.add_argument("--corpus", type=pathlib.Path, default=None, help="an existing corpus instead of a new one")
    ap.add_argument("--only", nargs="*", default=None, help="systems to train (default: all six)")
    ap.add_argument("--presets", default="cpu-small,paper", help="comma-separated presets trained per system")
    ap.add_argument("--out", type=pathlib.Path, default=None, help="working folder (default: a new temporary one)")
    ap.add_argument("--markdown", type=pathlib.Path, default=None, help="also write the report here")
    ap.add_argument("--reuse-models", action="store_true",
                    help="score a model already in OUT/models/SYSTEM_PRESET instead of training it again")
    args = ap.parse_args(argv)
    unknown = sorted(set(args.only or []) - set(BUDGETS))
    if unknown:
        ap.error(f"--only: unknown {unknown}; expected some of {', '.join(BUDGETS)}")
    presets = [p for p in args.presets.split(",") if p]
    if not presets or set(presets) - {"cpu-small", "paper"}:
        ap.error(f"--presets: expected cpu-small and/or paper, got {args.presets!r}")

    from evalsuite.corpus import load_corpus
    from evalsuite.generators import criteria as C
    from evalsuite.generators import find_generator
    from evalsuite.generators.evaluation import evaluate_condition, natural_through_rate, swapped_audio
    from evalsuite.generators.pose_repr import MODEL_FPS
    from evalsuite.generators.requests import requests_from_corpus
    from evalsuite.generators.runner import generate
    from evalsuite.synth.corpus import synthesize_corpus

    out = args.out or pathlib.Path(tempfile.mkdtemp(prefix="bench-presets-"))
    corpus_dir = args.corpus or out / "corpus"
    load_start = os.getloadavg()
    print(f"load average at start: {load_start}", flush=True)
    if not (corpus_dir / "corpus.json").is_file():
        synthesize_corpus(corpus_dir, args.minutes, seed=args.seed, progress=False)
    corpus = load_corpus(corpus_dir)
    splits = {s: len(corpus.split(s)) for s in ("train", "val", "test")}
    corpus_text = (f"{len(corpus)} segments, {sum(s.duration or 0 for s in corpus) / 60:.1f} min of speech "
                   f"(train {splits['train']}, val {splits['val']}, test {splits['test']} segments)")
    print(f"corpus: {corpus_text}", flush=True)
    reqs = requests_from_corpus(corpus, "test", 30.0)
    generate(find_generator("mean_pose"), reqs, out / "mean_pose",
             config={"from": str(corpus_dir / "trn" / "main-agent" / "bvh")}, progress=False)
    generate(find_generator("natural"), reqs, out / "natural", progress=False)
    base_mse = evaluate_condition(out / "mean_pose", corpus)["pose_mse"]
    natural = evaluate_condition(out / "natural", corpus)
    natural_20 = C.natural_motions(corpus, "test", MODEL_FPS)
    folders = {"mean_pose": out / "mean_pose",
               "natural via 20 fps": natural_through_rate(corpus, out / "natural_via_20fps", MODEL_FPS)}
    rows = [{"system": name, "preset": "reference", **score(folder, corpus, base_mse, natural, natural_20)}
            for name, folder in folders.items()]
    for name in [s for s in BUDGETS if not args.only or s in args.only]:
        for preset in presets:
            run = f"{name}_{preset}"
            model_dir = out / "models" / run
            row: dict[str, Any] = {"system": name, "preset": preset, "budget": BUDGETS[name][1]}
            cmd = train_command(name, preset, corpus_dir, model_dir, args.seed)
            print(" ".join(cmd[1:]), flush=True)
            t0 = time.perf_counter()
            reused = args.reuse_models and reusable(model_dir, name, preset)
            proc = subprocess.CompletedProcess(cmd, 0) if reused else subprocess.run(cmd, capture_output=True, text=True)
            row["train_s"] = round(time.perf_counter() - t0)
            if proc.returncode != 0:
                lines = [ln for ln in (proc.stderr + proc.stdout).splitlines() if ln.strip()]
                row["error"] = lines[-1] if lines else f"exit status {proc.returncode}"
                rows.append(row)
                print(json.dumps(row), flush=True)
                continue
            record = json.loads((model_dir / "model.json").read_text())
            row["train_s"] = round(record.get("training_seconds", row["train_s"]))
            row["parameters"] = count_parameters(model_dir)
            row["weights_sha256"] = record.get("weights_sha256", "")[:12]
            row["last_val_loss"] = next((h.get("val_loss") for h in reversed(record.get("history", []))
                                         if h.get("val_loss") is not None), None)
            entry = find_generator(name)
            generate(entry, reqs, out / run, model_dir=model_dir, progress=False, check_determinism=False)
            row.update(score(out / run, corpus, base_mse, natural, natural_20))
            folders[run] = out / run
            if name in AUDIO_DRIVEN:
                generate(entry, swapped_audio(reqs), out / f"{run}_swapped", model_dir=model_dir, progress=False,
                         check_determinism=False)
                row["swap"] = evaluate_condition(out / f"{run}_swapped", corpus)["pose_mse"] / row["_pose_mse"]
            rows.append(row)
            print(json.dumps({k: (round(v, 3) if isinstance(v, float) else v) for k, v in row.items()}), flush=True)
    fgd = C.fgd_against_natural(corpus, {k: C.generated_motions(f, corpus) for k, f in folders.items()})
    for row in rows:
        key = row["system"] if row["preset"] == "reference" else f"{row['system']}_{row['preset']}"
        row["fgd"] = fgd.get(key)
        row.pop("_pose_mse", None)
    table = markdown(rows)
    errors = [f"* `{r['system']}` `{r['preset']}` did not train: {r['error']}" for r in rows if "error" in r]
    load_end = os.getloadavg()
    argv_text = " ".join(sys.argv[1:] if argv is None else argv)
    report = "\n".join([
        f"Command: `python benchmarks/bench_presets.py {argv_text}`",
        f"Date: {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC; load average at start "
        f"{', '.join(f'{v:.2f}' for v in load_start)}, at end {', '.join(f'{v:.2f}' for v in load_end)} "
        f"({os.cpu_count()} cores, shared).",
        f"Corpus: synthetic speaker ({corpus_dir if args.corpus else f'made here, seed {args.seed}'}): {corpus_text}; "
        f"training seed {args.seed}.",
        f"Natural test motion (20 fps): div_k {C.diversity(natural_20)['div_k']:.3g}; mean pose error of "
        f"`mean_pose` {base_mse:.3g} units^2.", "", table, *([""] + errors if errors else [])])
    print(report)
    (out / "presets.md").write_text(report + "\n")
    (out / "presets.json").write_text(json.dumps(rows, indent=1, default=str))
    if args.markdown:
        args.markdown.write_text(report + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
