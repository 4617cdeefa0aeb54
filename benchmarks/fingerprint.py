"""Fingerprints of what evalsuite computes, to show that a refactoring changed no number.

Trains every re-implementation for a few fixed epochs (no time budget, so the result does not depend on the
machine's speed) on a 4-minute synthetic speaker, generates the test split with each of them and with the
built-in conditions, and scores everything with the default metric families. Prints one line per trained model
(the sha256 of its weights) and one line per scored condition (the summary's figures, rounded to 9 significant
digits), then the sha256 of all the lines. Run it on two commits and compare the output:

    python benchmarks/fingerprint.py            # about 3-6 minutes on 2 cores

Nothing is downloaded; everything is written to a temporary folder.
"""
from __future__ import annotations

import hashlib
import json
import pathlib
import sys
import tempfile

from evalsuite.corpus import load_corpus
from evalsuite.generators import find_generator
from evalsuite.generators.requests import requests_from_corpus
from evalsuite.generators.runner import generate
from evalsuite.generators.training import train
from evalsuite.synth.corpus import synthesize_corpus

# Fixed-epoch configurations, as the reproducibility tests use them.
TRAINED = {
    "gesticulator": {"epochs": 5, "words": "hash"},
    "aud2repr2pose": {"epochs": 3, "dae_epochs": 2},
    "aud2motion": {"epochs": 3},
    "aud2pose": {"epochs": 3},
    "gesture2vec": {"words": "hash", "codebook": 8, "dae_epochs": 2, "vq_epochs": 2, "vq_decoder_epochs": 1,
                    "translation_epochs": 2},
    "ferstl-mogan": {"classifier_epochs": 2, "pretrain_epochs": 2, "adversarial_steps": 4, "batch_size": 4,
                     "realism_pretrain_steps": 3, "phase_pretrain_tries": 3},
}
CONDITIONS = ["natural", "mean_pose", "mismatched", "random_segments"]


def main() -> int:
    lines: list[str] = []
    with tempfile.TemporaryDirectory() as tmp:
        root = pathlib.Path(tmp)
        synthesize_corpus(root / "speaker", 4.0, seed=5, progress=False)
        corpus = load_corpus(root / "speaker")
        requests = requests_from_corpus(corpus, "test", 30.0)
        folders = {}
        for name in CONDITIONS:
            folders[name] = root / "out" / name
            generate(find_generator(name), requests, folders[name], seed=7, progress=False)
        for name, cfg in TRAINED.items():
            model = root / "models" / name
            train(find_generator(name), corpus, model, seed=0, config=cfg, progress=False)
            sha = json.loads((model / "model.json").read_text())["weights_sha256"]
            lines.append(f"weights {name} {sha}")
            folders[name] = root / "out" / name
            generate(find_generator(name), requests, folders[name], model_dir=model, seed=7, progress=False)
        from evalsuite.metrics.engine import score_folders

        result = score_folders(folders["natural"], [folders[n] for n in folders if n != "natural"],
                               corpus=root / "speaker", progress=False)
        for row in sorted(result.summary, key=lambda r: (str(r.get("condition")), str(r.get("metric")))):
            cells = []
            for key in sorted(row):
                value = row[key]
                cells.append(f"{key}={value:.9g}" if isinstance(value, float) else f"{key}={value}")
            lines.append("score " + " ".join(cells))
    for line in lines:
        print(line)
    print("fingerprint", hashlib.sha256("\n".join(lines).encode()).hexdigest())
    return 0


if __name__ == "__main__":
    sys.exit(main())
