"""Hours of data: peak memory and throughput of each re-implementation as the training corpus grows (issue 39).

One synthetic-speaker corpus of ``--base-minutes`` minutes is written once (``evalsuite corpus synth``, cached in
``--work``); the corpus of each size in ``--hours`` is that corpus with its train split repeated (symbolic links,
new segment ids: the training data grows, val and test stay the same; the features cache makes the repeats cheap
to read). Each system then trains, in a fresh process, for a fixed schedule: one epoch of each stage (Gesticulator
its minimum of five; Ferstl et al. 20 adversarial steps), and the process reports

* train frames (20 fps) and training seconds (the loops, feature extraction excluded), hence frames/s (train
  frames x passes over them, e.g. 5 for Gesticulator's five epochs, 4 for Gesture2Vec's four stages; Ferstl et
  al.'s 20 adversarial steps are not counted);
* peak resident memory of the whole process (``ru_maxrss``), feature extraction included.

The last columns divide each figure by the smallest corpus's, measured in the same run: the goal is a peak RSS
under 3 GB at 10 hours and under 2x the 1-hour figure. Other processes slow the timings down (the load average is
printed); memory does not depend on them.

Usage: python benchmarks/bench_generators_hours.py [--hours 1,10] [--base-minutes 60] [--systems a,b]
       [--work DIR] [--preset cpu-small|paper]
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import os
import pathlib
import subprocess
import sys
import tempfile

SYSTEMS = ["gesticulator", "aud2pose", "aud2motion", "aud2repr2pose", "gesture2vec", "ferstl-mogan"]
SCHEDULE = {
    "gesticulator": {"epochs": 5, "words": "hash"},
    "aud2pose": {"epochs": 1},
    "aud2motion": {"epochs": 1},
    "aud2repr2pose": {"epochs": 1, "dae_epochs": 1},
    "gesture2vec": {"words": "hash", "dae_epochs": 1, "vq_epochs": 1, "vq_decoder_epochs": 1,
                    "translation_epochs": 1},
    "ferstl-mogan": {"classifier_epochs": 1, "pretrain_epochs": 1, "adversarial_steps": 20,
                     "realism_pretrain_steps": 5, "phase_pretrain_tries": 3},
}
PASSES = {"gesticulator": 5, "aud2pose": 1, "aud2motion": 1, "aud2repr2pose": 2, "gesture2vec": 4, "ferstl-mogan": 2}
FOLDERS = ("wav", "bvh", "tsv", "labels")

# run in a fresh process per training, so that each peak RSS is that training's alone
CHILD = """
import json, resource, sys, time
from evalsuite.corpus import load_corpus
from evalsuite.generators import find_generator
from evalsuite.generators.training import train
name, corpus_dir, out, preset, config = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4], json.loads(sys.argv[5])
corpus = load_corpus(corpus_dir)
frames = sum(round(s.duration * 20.0) for s in corpus.split("train"))
t0 = time.perf_counter()
result = train(find_generator(name), corpus, out, seed=0, config=config, preset=preset, progress=False)
wall = time.perf_counter() - t0
loop = max((r.get("seconds", 0.0) for r in result.history), default=wall)
print(json.dumps({"frames": frames, "wall_s": wall, "train_s": loop,
                  "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0}))
"""


def replicate(base: pathlib.Path, out: pathlib.Path, copies: int) -> pathlib.Path:
    """``base`` with its train split ``copies`` times (copy 0 is the original; copy k's segments are named
    ``<id>_rk``): files are symbolic links, ``corpus.json`` and ``trn/metadata.csv`` list every copy."""
    if (out / "corpus.json").exists():
        return out
    meta = json.loads((base / "corpus.json").read_text())
    train_dir = meta["split_dirs"]["train"]
    out.mkdir(parents=True)
    for split_dir in meta["split_dirs"].values():
        if split_dir != train_dir:
            (out / split_dir).symlink_to((base / split_dir).resolve())
    train_ids = list(meta["splits"]["train"])
    src = base / train_dir / "main-agent"
    for folder in FOLDERS:
        (out / train_dir / "main-agent" / folder).mkdir(parents=True)
        for path in sorted((src / folder).iterdir()):
            for k in range(copies):
                name = path.name if k == 0 else f"{path.stem}_r{k}{path.suffix}"
                (out / train_dir / "main-agent" / folder / name).symlink_to(path.resolve())
    with open(base / train_dir / "metadata.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    with open(out / train_dir / "metadata.csv", "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(rows[0])
        for k in range(copies):
            writer.writerows([[r[0] if k == 0 else f"{r[0]}_r{k}", *r[1:]] for r in rows[1:]])
    for k in range(1, copies):
        for seg in train_ids:
            meta["segments"][f"{seg}_r{k}"] = meta["segments"][seg]
        meta["splits"]["train"] = meta["splits"]["train"] + [f"{s}_r{k}" for s in train_ids]
    meta["minutes"] = meta.get("minutes", 0) * copies
    (out / "corpus.json").write_text(json.dumps(meta))
    return out


def throughput(row: dict) -> float:
    """Training frames per second: train frames x passes over them (epochs of every stage) / loop seconds."""
    return row["frames"] * PASSES[row["system"]] / max(row["train_s"], 1e-9)


def measure(name: str, corpus: pathlib.Path, out: pathlib.Path, preset: str) -> dict:
    cmd = [sys.executable, "-c", CHILD, name, str(corpus), str(out), preset, json.dumps(SCHEDULE[name])]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        return {"error": (proc.stderr.strip().splitlines() or ["?"])[-1]}
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--hours", default="1,10", help="corpus sizes in hours of training speech, comma-separated")
    ap.add_argument("--base-minutes", type=float, default=60.0, help="minutes of the synthesised corpus repeated")
    ap.add_argument("--systems", default=",".join(SYSTEMS), help="re-implementations to train, comma-separated")
    ap.add_argument("--preset", default="cpu-small", choices=("cpu-small", "paper"), help="preset trained")
    ap.add_argument("--work", help="folder for the corpora and the features cache (default: a temporary one)")
    args = ap.parse_args(argv)
    hours = [float(h) for h in args.hours.split(",")]
    work = pathlib.Path(args.work) if args.work else pathlib.Path(tempfile.mkdtemp(prefix="bench_hours_"))
    os.environ.setdefault("EVALSUITE_CACHE_DIR", str(work / "features-cache"))
    base = work / f"base_{args.base_minutes:g}min"
    if not (base / "corpus.json").exists():
        from evalsuite.synth.corpus import synthesize_corpus

        synthesize_corpus(base, args.base_minutes, seed=0, progress=True)
    base_train_min = sum(s["duration"] for s in json.loads((base / "corpus.json").read_text())["segments"].values()
                         if s["split"] == "train") / 60.0
    rows = []
    for h in hours:
        copies = max(1, math.ceil(h * 60.0 / base_train_min - 1e-9))
        corpus = replicate(base, work / f"corpus_{copies}x", copies)
        for name in args.systems.split(","):
            with tempfile.TemporaryDirectory(dir=work) as tmp:
                r = measure(name, corpus, pathlib.Path(tmp) / "model", args.preset)
            r.update(system=name, hours=round(copies * base_train_min / 60.0, 2))
            rows.append(r)
            print(json.dumps(r), flush=True)
    first = {r["system"]: r for r in rows if r["hours"] == min(x["hours"] for x in rows) and "error" not in r}
    print(f"\nload average {os.getloadavg()}, {os.cpu_count()} CPUs, preset {args.preset}\n")
    print("| system | train hours | train frames | train s | frames/s | peak RSS MB | RSS x smallest | "
          "frames/s x smallest |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        if "error" in r:
            print(f"| {r['system']} | {r['hours']} | error: {r['error']} | | | | | |")
            continue
        fps = throughput(r)
        b = first.get(r["system"])
        ratio_rss = r["peak_rss_mb"] / b["peak_rss_mb"] if b else float("nan")
        ratio_fps = fps / throughput(b) if b else float("nan")
        print(f"| {r['system']} | {r['hours']} | {r['frames']} | {r['train_s']:.1f} | {fps:.0f} | "
              f"{r['peak_rss_mb']:.0f} | {ratio_rss:.2f} | {ratio_fps:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
