"""Training a generator on a corpus, and the model folder that says everything needed to use it.

``train(entry, corpus, out_dir, seed, budget_minutes, config)`` calls the plug-in's ``fit`` with a progress
callback (a tqdm bar with the latest losses), then writes beside the plug-in's own files:

* ``model.json`` -- format, the generator's spec, config, seed, budget, the corpus (root, layout, segments per
  split, a hash of its listing), per-epoch history, training time, package versions, and the sha256 of every
  file the plug-in wrote;
* ``train_log.csv`` -- the per-epoch history (epoch, train_loss, val_loss, seconds, …).
"""
from __future__ import annotations

import contextlib
import csv
import hashlib
import json
import pathlib
import time
from collections.abc import Mapping
from typing import Any

from evalsuite.corpus.types import Corpus
from evalsuite.errors import InputError
from evalsuite.generators.checkpoints import check_run, parse_every, session
from evalsuite.generators.contract import GeneratorError, TrainingResult
from evalsuite.generators.presets import DEFAULT_PRESET, apply_preset
from evalsuite.generators.provenance import package_versions
from evalsuite.generators.registry import GeneratorEntry, generator_class
from evalsuite.hashing import file_sha256

__all__ = ["train", "read_model_json", "MODEL_FORMAT", "corpus_summary"]

MODEL_FORMAT = "evalsuite-model/1"


def corpus_summary(corpus: Corpus) -> dict[str, Any]:
    """Root, layout, segment counts per split and a hash of (segment id, split, durations) of the corpus."""
    splits: dict[str, int] = {}
    h = hashlib.sha256()
    for s in corpus.segments:
        splits[str(s.split)] = splits.get(str(s.split), 0) + 1
        h.update(f"{s.id}\0{s.split}\0{s.duration}\0".encode())
    return {"root": str(corpus.root), "layout": corpus.layout, "segments": len(corpus.segments), "splits": splits,
            "listing_sha256": h.hexdigest()}


def train(entry: GeneratorEntry, corpus: Corpus, out_dir: str | pathlib.Path, *, seed: int = 0,
          budget_minutes: float | None = None, config: Mapping[str, Any] | None = None,
          progress: bool = True, preset: str = DEFAULT_PRESET, checkpoint_every: str | None = None,
          resume: bool = False) -> TrainingResult:
    """Fit ``entry``'s generator on ``corpus`` and write the model folder ``out_dir`` (see the module doc).
    ``preset`` (:mod:`evalsuite.generators.presets`) sets options under ``config``'s. ``checkpoint_every``
    (``"10m"``, ``"5"`` epochs) saves the re-implementations' loops in ``out_dir/checkpoints`` and ``resume`` carries
    on from them (:mod:`evalsuite.generators.checkpoints`)."""
    from tqdm import tqdm

    assert entry.spec is not None
    if not entry.spec.trainable:
        raise GeneratorError(f"{entry.spec.name} is not trainable", field="generator")
    if budget_minutes is not None and not budget_minutes > 0:
        raise InputError(f"the budget must be a positive number of minutes, got {budget_minutes}",
                         field="--budget-minutes")
    out = pathlib.Path(out_dir)
    fresh = not out.exists() or not any(out.iterdir())
    out.mkdir(parents=True, exist_ok=True)
    gen = generator_class(entry.target)()
    gen.configure(apply_preset(entry.spec.name, preset, config or {}))
    bar = tqdm(desc=f"train {entry.spec.name}", unit="epoch", disable=not progress, leave=False)

    def on_epoch(row: dict[str, Any]) -> None:
        bar.update(1)
        bar.set_postfix({k: (f"{v:.4g}" if isinstance(v, float) else v) for k, v in row.items()
                         if k in ("stage", "train_loss", "val_loss")})

    every = parse_every(checkpoint_every)
    checkpointing = every is not None or resume
    if checkpointing:
        check_run(out, {"generator": entry.spec.name, "config": dict(gen.config), "seed": seed, "preset": preset},
                  resume)
    t0 = time.perf_counter()
    try:
        with session(out, every, resume) if checkpointing else contextlib.nullcontext() as ck:
            result = gen.fit(corpus, out, seed=seed, budget_minutes=budget_minutes, progress=on_epoch)
        if ck is not None and ck.resumed:
            result.meta["resumed_stages"] = ck.resumed
    finally:
        bar.close()
        gen.close()
    seconds = time.perf_counter() - t0
    _guard_divergence(entry, corpus, out, gen.config, result.history, fresh, time.time() - seconds)
    files = {p.relative_to(out).as_posix(): file_sha256(p) for p in sorted(out.rglob("*"))
             if p.is_file() and p.name not in ("model.json", "train_log.csv")}
    record = {"format": MODEL_FORMAT, "generator": entry.spec.as_dict(), "target": entry.target,
              "config": dict(gen.config), "preset": preset, "seed": seed, "budget_minutes": budget_minutes,
              "training_seconds": round(seconds, 2), "corpus": corpus_summary(corpus), "history": result.history,
              "files": files, "packages": package_versions(), **result.meta}
    (out / "model.json").write_text(json.dumps(record, indent=1, default=str), encoding="utf-8")
    if result.history:
        keys = list(dict.fromkeys(k for row in result.history for k in row))
        with open(out / "train_log.csv", "w", newline="", encoding="utf-8") as fh:
            writer = csv.DictWriter(fh, fieldnames=keys)
            writer.writeheader()
            writer.writerows(result.history)
    return result


def _guard_divergence(entry: GeneratorEntry, corpus: Corpus, out: pathlib.Path, config: Mapping[str, Any],
                      history: list[dict[str, Any]], fresh: bool, started: float) -> None:
    """Stop with a :class:`DivergenceError` when the loss or the output scale diverged
    (:mod:`evalsuite.generators.divergence`), removing what the training wrote: the whole folder when it was new,
    else the files written since ``started`` and ``model.json``."""
    import shutil

    from evalsuite.generators.divergence import DivergenceError, loss_divergence, output_divergence

    reason = loss_divergence(history) or output_divergence(entry, corpus, out, config)
    if reason is None:
        return
    if fresh:
        shutil.rmtree(out, ignore_errors=True)
    else:
        for p in [*out.rglob("*"), out / "model.json"]:
            if p.is_file() and (p.name == "model.json" or p.stat().st_mtime >= started - 1.0):
                p.unlink()
    assert entry.spec is not None
    raise DivergenceError(f"{entry.spec.name}: the training diverged ({reason}); no model was written. Lower the "
                          f"learning rate or check the corpus", field="training")


def read_model_json(model_dir: pathlib.Path, generator: str) -> dict[str, Any]:
    """``model.json`` of a model folder, checked to belong to ``generator``."""
    path = model_dir / "model.json"
    try:
        record = json.loads(path.read_text(encoding="utf-8"))
    except OSError:
        raise InputError(f"not a model folder of evalsuite (no model.json); train one with "
                         f"`evalsuite train -g {generator}`", path=model_dir, field="--model") from None
    except ValueError as exc:
        raise InputError(f"model.json is not valid JSON ({exc})", path=path) from None
    name = (record.get("generator") or {}).get("name") if isinstance(record, dict) else None
    if name != generator:
        raise InputError(f"this model was trained for generator {name!r}, not {generator!r}", path=path,
                         field="--model")
    return record
