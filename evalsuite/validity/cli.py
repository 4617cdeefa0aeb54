"""``evalsuite validate-metrics``: which objective metrics order systems correctly when the truth is known."""
from __future__ import annotations

import json
import pathlib
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import click

from evalsuite.corpus.cli import on_mismatch_option
from evalsuite.errors import InputError

__all__ = ["validate_metrics", "run_validation", "ValidityRun", "FGD_EPOCHS"]

# A small, fast encoder: 1 s windows at 30 fps, half-overlapping, a few epochs on the train split.
FGD_WINDOW, FGD_FPS, FGD_EPOCHS, FGD_ARCHITECTURE = 30, 30.0, 8, "genea2023"


@dataclass
class ValidityRun:
    results: list[Any]
    out_dir: pathlib.Path
    conditions: list[str]
    metrics: list[str]
    families: dict[str, list[str]]
    timings: dict[str, float] = field(default_factory=dict)
    files: list[pathlib.Path] = field(default_factory=list)
    mismatch: list[Any] = field(default_factory=list)    # evalsuite.validity.mismatch.MismatchResult


def _fgd_family(corpus: Any, out_dir: pathlib.Path, model: pathlib.Path | None, epochs: int, seed: int,
                echo: Callable[[str], None]) -> Any:
    try:
        from evalsuite.learned.family import FGDFamily
        from evalsuite.learned.training import train_model
    except ImportError as exc:
        raise InputError(f"FGD needs the learned extra ({exc}): pip install 'evalsuite[learned]', or pass --no-fgd",
                         field="fgd") from None
    if model is None:
        train = {s.id: s.load_motion() for s in corpus.split("train") if s.motion is not None}
        if not train:
            raise InputError("the corpus has no train split with motion to train the FGD encoder on; give "
                             "--fgd-model MODEL or --no-fgd", path=corpus.root, field="--corpus")
        net = train_model(train, joints="all", window=FGD_WINDOW, fps=FGD_FPS, epochs=epochs, seed=seed,
                          architecture=FGD_ARCHITECTURE, progress=False)
        model = out_dir / "fgd_model.pt"
        net.save(model)
        echo(f"  FGD encoder {net.short_hash} trained on {len(train)} natural train segments "
             f"({FGD_WINDOW}-frame windows, {epochs} epochs) -> {model}")
    return FGDFamily(model)


def run_validation(corpus_dir: str | pathlib.Path, out_dir: str | pathlib.Path, *, split: str = "val,test",
                   models: Sequence[str] = (), n_bootstrap: int = 200, seed: int = 0, fps: float = 30.0,
                   jobs: int = 1, fgd: bool = True, fgd_model: str | pathlib.Path | None = None,
                   fgd_epochs: int = FGD_EPOCHS, progress: bool = True, mismatch: bool = True,
                   echo: Callable[[str], None] = lambda s: None) -> ValidityRun:
    """Generate the benchmark's conditions on a synthetic corpus, score them, and write the validity table."""
    from evalsuite.corpus import load_corpus
    from evalsuite.generators.requests import requests_from_corpus
    from evalsuite.metrics.report import write_outputs
    from evalsuite.validity import analysis, plan, report, scoring
    from evalsuite.validity import mismatch as mm

    t_all = time.perf_counter()
    out = pathlib.Path(out_dir)
    timings: dict[str, float] = {}
    corpus = load_corpus(corpus_dir)
    plan.check_synthetic(corpus)
    splits = [s.strip() for s in split.split(",") if s.strip()]
    requests = requests_from_corpus(corpus, splits, fps)
    if len(requests) < 2:
        raise InputError(f"split {split!r} has {len(requests)} segment(s); the bootstrap over segments needs at "
                         "least 2 (a larger corpus, or --split all)", path=corpus.root, field="--split")
    bench = plan.build_plan(plan.parse_models(models))
    out.mkdir(parents=True, exist_ok=True)

    t0 = time.perf_counter()
    echo(f"Generating {len(bench.conditions)} conditions x {len(requests)} segments ({split}) into {out}/conditions")
    folders = plan.generate_conditions(bench, corpus, requests, out / "conditions", seed=seed, jobs=jobs,
                                       progress=progress, echo=echo)
    timings["generate_s"] = time.perf_counter() - t0
    from evalsuite.metrics.families.gac import GacFamily

    extra: list[Any] = [GacFamily(default=True)]     # Gesture Area Coverage (tonoli2024), not in score's default set
    if fgd:
        t0 = time.perf_counter()
        extra.append(_fgd_family(corpus, out, pathlib.Path(fgd_model) if fgd_model else None, fgd_epochs, seed, echo))
        timings["fgd_train_s"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    echo("Scoring every condition against natural (all metrics of `evalsuite score`, speech from the corpus)")
    scored = scoring.score_conditions(folders, pathlib.Path(corpus.root), extra_families=extra, jobs=jobs,
                                      progress=progress)
    paths = write_outputs(scored.result, out / "scores")
    timings["score_s"] = time.perf_counter() - t0
    for issue in scored.result.issues:
        echo(f"  note: {issue}")

    t0 = time.perf_counter()
    echo(f"Bootstrap: {n_bootstrap} paired resamples of the {len(requests)} segments (seed {seed})")
    summary = scored.result.summary
    better = {r["metric"]: r["better"] for r in summary if r.get("better")}
    oracle = {r["metric"] for r in summary if r["condition"] == "oracle" and r["value"] == r["value"]}
    metrics = [m for m in dict.fromkeys(r["metric"] for r in summary) if m in oracle and m in better]
    conditions = [c.name for c in bench.conditions]
    table = scoring.bootstrap_table(scored, conditions, metrics, n_bootstrap, seed, progress, jobs)
    timings["bootstrap_s"] = time.perf_counter() - t0
    results = analysis.analyse(table, conditions, metrics, better, bench.families)

    report.write_csv(results, out / "validity.csv")
    (out / "validity.md").write_text(report.markdown(results, bench.levels), encoding="utf-8")
    (out / "validity.tex").write_text(report.latex(results), encoding="utf-8")
    figures = report.write_heatmap(results, out / "validity_tau")
    mism: list[Any] = []
    if mismatch and mm.speech_metrics(scored.result.setup):
        t0 = time.perf_counter()
        echo("Mismatch test: every condition scored again with a deranged segment's speech (same speaker)")
        mism = mm.mismatch_test(scored, conditions, n_bootstrap=n_bootstrap, seed=seed, jobs=jobs, progress=progress)
        mm.write_csv(mism, out / "mismatch.csv")
        with open(out / "validity.md", "a", encoding="utf-8") as fh:
            fh.write("\n## Mismatch test (own speech vs deranged speech)\n\n" + mm.markdown(mism))
        figures.append(out / "mismatch.csv")
        timings["mismatch_s"] = time.perf_counter() - t0
    timings["total_s"] = time.perf_counter() - t_all
    (out / "validity.json").write_text(json.dumps({
        "corpus": str(pathlib.Path(corpus.root).resolve()), "split": split, "segments": [r.segment_id for r in requests],
        "bootstrap": n_bootstrap, "seed": seed, "fps": fps, "fgd": bool(fgd),
        "families": bench.families, "levels": bench.levels,
        "conditions": {c.name: {"generator": c.generator, "config": c.config, "of": c.of,
                                "model": str(c.model_dir) if c.model_dir else None} for c in bench.conditions},
        "timings_s": {k: round(v, 2) for k, v in timings.items()}}, indent=1), encoding="utf-8")
    files = [out / f"validity.{e}" for e in ("csv", "md", "tex", "json")] + figures + [paths["summary_csv"]]
    return ValidityRun(results, out, conditions, metrics, bench.families, timings, files, mism)


@click.command("validate-metrics")
@click.option("--corpus", "corpus_dir", required=True, type=click.Path(path_type=pathlib.Path),
              help="A synthetic-speaker corpus written by `evalsuite corpus synth`.")
@click.option("-o", "--out", "out_dir", default="validity", show_default=True,
              type=click.Path(file_okay=False, path_type=pathlib.Path), help="Output folder.")
@click.option("--split", default="val,test", show_default=True,
              help="Segments to generate and score (splits, comma-separated, or all); the FGD encoder trains on "
              "the train split.")
@click.option("--model", "models", multiple=True, metavar="NAME=DIR",
              help="Also a trained generator (a model folder of `evalsuite train`), as the family 'oracle better "
              "than NAME' (repeatable).")
@click.option("--bootstrap", type=click.IntRange(min=0), default=200, show_default=True,
              help="Paired bootstrap resamples over segments for the intervals.")
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of the generators and the bootstrap.")
@click.option("--fps", type=float, default=30.0, show_default=True, help="Frame rate of the generated motion.")
@click.option("-j", "--jobs", type=click.IntRange(min=1), default=1, show_default=True, help="Local worker processes.")
@click.option("--no-fgd", is_flag=True, help="Skip FGD (it needs the learned extra: torch).")
@click.option("--fgd-model", type=click.Path(exists=True, dir_okay=False, path_type=pathlib.Path), default=None,
              help="Use this FGD encoder instead of training a small one on the train split.")
@click.option("--fgd-epochs", type=click.IntRange(min=1), default=FGD_EPOCHS, show_default=True,
              help="Epochs of the small FGD encoder.")
@click.option("--no-mismatch-test", "no_mismatch", is_flag=True, help="Skip the mismatch test (each speech metric "
              "scored again with a deranged segment's speech; writes mismatch.csv).")
@click.option("--quiet", is_flag=True, help="No progress bars and no table.")
@on_mismatch_option
def validate_metrics(corpus_dir: pathlib.Path, out_dir: pathlib.Path, split: str, models: tuple[str, ...],
                     bootstrap: int, seed: int, fps: float, jobs: int, no_fgd: bool, fgd_model: pathlib.Path | None,
                     fgd_epochs: int, no_mismatch: bool, quiet: bool) -> None:
    """Known-truth validity of every metric of `evalsuite score` on a synthetic-speaker corpus.

    Generates the oracle (the speaker's own model, another performance of the same speech) and graded
    degradations of it (time offsets 0.1-1.2 s, semantic gestures or beats removed, amplitude -25/50/75 %,
    jitter, over-smoothing), plus mismatched, random segments and mean pose; scores all against natural
    (FGD from a small encoder trained on the train split); and reports, per metric and family, Kendall's
    tau with the true order and a bootstrap interval over segments. Writes validity.csv (metric, family,
    tau, ci_low, ci_high, n_levels, verdict, ...), validity.md/.tex, validity_tau.png/.svg and scores/
    (the per-condition scores, as `evalsuite score` writes them).

    \b
    Example:
      evalsuite corpus synth -o corpus/ --minutes 10 --seed 0
      evalsuite validate-metrics --corpus corpus/ -o validity/ --jobs 2
    """
    def echo(text: str) -> None:
        if not quiet:
            click.echo(text)

    from evalsuite.validity.report import speech_blind, text_table

    run = run_validation(corpus_dir, out_dir, split=split, models=models, n_bootstrap=bootstrap, seed=seed, fps=fps,
                         jobs=jobs, fgd=not no_fgd, fgd_model=fgd_model, fgd_epochs=fgd_epochs, progress=not quiet,
                         mismatch=not no_mismatch, echo=echo)
    echo("")
    echo(text_table(run.results))
    blind = speech_blind(run.results)
    echo("Blind to speech (offset 1.2 s within bootstrap noise): " + (", ".join(blind) if blind else "none"))
    if run.mismatch:
        from evalsuite.validity.mismatch import separation

        sep = separation(run.mismatch)
        echo("Mismatch test (oracle's loss from deranged speech minus the strongest offset's, 95 % interval): "
             + "; ".join(f"{m} {d:+.3g} [{lo:.3g}, {hi:.3g}]" for m, (d, lo, hi) in sep.items()))
    echo(f"Wrote {', '.join(p.name for p in run.files)} to {run.out_dir} in {run.timings['total_s']:.0f} s")
