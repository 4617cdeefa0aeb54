"""The scoring engine behind ``evalsuite score``: plan -> run -> reduce over the registered metric families.

The choices of a run are one :class:`~evalsuite.metrics.options.ScoreOptions`.

1. **Plan** (:mod:`evalsuite.metrics.planning`, :func:`plan_for`): pair the files of the natural folder and
   of each condition folder by name and resolve the joints; :func:`setup_for` resolves groups, metrics and
   histogram bins into the workers' :class:`ScoreSetup`.
2. **Run**: one :class:`ScoreTask` per sequence name (the natural file and every condition's file of that
   name), so the natural motion is loaded once per name. :func:`score_sequence` runs in the parent, in local processes or
   on a dask cluster (:func:`evalsuite.parallel.run`); it loads each file and lets every family measure it
   (:meth:`MetricFamily.measure`), returning plain numpy summaries, never the raw motion. A file that fails
   is reported in its record and the others go on.
3. **Reduce**: results arrive in task order whatever order they finish in; the families fold bulky
   summaries into running sums as they come (:meth:`MetricFamily.fold`) and then turn each condition's
   records into rows (:meth:`MetricFamily.reduce`) in a fixed order (conditions as given, sequences sorted),
   so the numbers are identical however the per-file work was run.

:func:`score_plan` runs 1-3 on a plan; :func:`score_folders` (``evalsuite score``) and the validity benchmark
(:mod:`evalsuite.validity.scoring`) both call it.
"""
from __future__ import annotations

import pathlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from tqdm import tqdm

from evalsuite.errors import InputError
from evalsuite.hashing import file_sha256
from evalsuite.metrics.beats import audio_onsets
from evalsuite.metrics.conventions import Convention, get_convention, reference_edges
from evalsuite.metrics.families import (
    ReduceContext,
    SequenceContext,
    bootstrap_weights,
    metric_index,
    registered_families,
)
from evalsuite.metrics.histograms import automatic_edges
from evalsuite.metrics.loading import Positions, grouped_errors, load_scored, selected_positions
from evalsuite.metrics.options import ScoreOptions, ScoreSetup, ScoreTask
from evalsuite.metrics.planning import Plan, plan_scoring, resolve_groups, resolve_metrics
from evalsuite.metrics.samples import expand_for_each, label_samples
from evalsuite.metrics.tracks import wrist_track
from evalsuite.parallel import run

__all__ = ["ScoreOptions", "ScoreSetup", "ScoreTask", "ScoreResult", "score_sequence", "probe_ranges", "plan_for",
           "setup_for", "tasks_for", "score_plan", "score_folders", "reduce_results"]


@dataclass
class ScoreResult:
    """What a scoring run produced; the report and figure writers read it."""

    summary: list[dict[str, Any]]
    per_sequence: list[dict[str, Any]]
    per_joint: list[dict[str, Any]]
    histograms: list[dict[str, Any]]
    issues: list[str]
    errors: list[str]
    fps: float
    files: dict[str, dict[str, dict[str, Any]]]
    wrist_tracks: dict[str, list[Any]]
    plan: Plan
    setup: ScoreSetup
    convention: Convention
    bootstrap: int = 0
    seed: int = 0
    resampled: list[str] = field(default_factory=list)
    task_results: list[dict[str, Any]] = field(default_factory=list)   # score_plan(..., keep_task_results=True)
    figure_data: dict[str, Any] = field(default_factory=dict)   # figure name -> condition -> data (families')


def _measure(motion: Any, pos: Callable[[], np.ndarray], setup: ScoreSetup, conv: Convention,
             natural_pos: Callable[[], np.ndarray] | None, onsets: np.ndarray | None, natural_cache: dict[Any, Any],
             audio: tuple[np.ndarray, int] | None = None, segment: Any = None) -> dict[str, Any]:
    if motion.n_frames < 4:
        raise InputError(f"only {motion.n_frames} frames; at least 4 are needed (jerk uses 3rd differences)",
                         path=motion.source)
    ctx = SequenceContext(motion, pos, setup, conv, natural_pos, onsets, natural_cache, audio, segment)
    for family in setup.active():
        family.measure(ctx)
    if setup.figures:
        try:
            ctx.record["wrist_track"] = wrist_track(motion)
        except InputError as exc:   # e.g. SMPL-X without a body model: the figure leaves this file out
            ctx.record["wrist_track_error"] = exc.reason
    return ctx.record


def score_sequence(task: ScoreTask) -> dict[str, Any]:
    """Measure one sequence in every condition (``task.entries``, the natural file first).

    Returns ``{"name", "records": {condition: record}}`` where a record holds numpy summaries, or
    ``{"error": message}`` for a file that could not be scored.
    """
    setup, audio_path, segment = task.setup, task.audio, task.segment
    conv = get_convention(setup.convention)
    records: dict[str, dict[str, Any]] = {}
    onsets = None
    audio = None
    audio_error = None
    if audio_path is not None and any(f.needs_audio or f.needs_corpus for f in setup.active()):
        from evalsuite.audio import read_wav

        try:
            signal, sr = read_wav(audio_path)
            audio = (signal.mean(axis=1), sr)
            onsets = audio_onsets(audio[0], sr)
        except InputError as exc:
            audio_error = str(exc)
    natural_pos = None
    natural_cache: dict[Any, Any] = {}
    for k, (cond, path) in enumerate(task.entries):
        try:
            motion, resampled = load_scored(path, setup)
            pos = Positions(motion, setup.joints)   # computed only if a chosen family reads positions
            if k == 0:
                natural_pos = pos
            rec = _measure(motion, pos, setup, conv, natural_pos, onsets, natural_cache, audio, segment)
            rec["sha256"] = file_sha256(path)
            rec["path"] = str(path)
            # families that resample again (FGD to its model's rate) add their own entries
            rec["resampled"] = resampled + rec.get("resampled", [])
            if audio_error:
                rec.setdefault("warnings", []).append(audio_error)
            records[cond] = rec
        except InputError as exc:
            records[cond] = {"error": str(exc), "path": str(path)}
        except Exception as exc:  # a broken file must not lose the other results
            records[cond] = {"error": f"{path}: cannot be scored ({type(exc).__name__}: {exc})", "path": str(path)}
    return {"name": task.name, "records": records}


def probe_ranges(task: tuple[pathlib.Path, ScoreSetup]) -> dict[str, Any]:
    """99.5th percentiles of pooled speed and acceleration of one natural file (for automatic bins)."""
    from evalsuite.metrics.kinematics import derivative_norms

    path, setup = task
    conv = get_convention(setup.convention)
    try:
        motion, _ = load_scored(path, setup)
        pos = selected_positions(motion, setup.joints)
        out: dict[str, Any] = {"path": str(path), "fps": motion.fps}
        for q, order in (("speed", 1), ("acceleration", 2)):
            n = derivative_norms(pos, order, conv.rate(motion.fps))
            out[q] = float(np.percentile(n, 99.5)) if n.size else float("nan")
        return out
    except Exception as exc:  # reported by the main pass
        return {"path": str(path), "error": str(exc)}


def copy_task_result(result: dict[str, Any]) -> dict[str, Any]:
    """A task result with each record copied (a family's ``fold`` may pop what it has used from a record)."""
    return {"name": result["name"], "records": {c: dict(r) for c, r in result["records"].items()}}


class _Folder:
    """Folds each result's bulky summaries into per-condition sums, in task order (see module docstring).
    With ``kept``, the results as they came are appended to it and a copy of each is folded instead (a
    family's ``fold`` may pop what it has used from a record)."""

    def __init__(self, setup: ScoreSetup, reference: str, keep: bool, kept: list[dict[str, Any]] | None = None):
        self.families, self.reference, self.keep, self.kept = setup.active(), reference, keep, kept
        self.acc: dict[str, dict[str, Any]] = {}

    def __call__(self, index: int, result: dict[str, Any]) -> dict[str, Any]:
        if self.kept is not None:
            self.kept.append(result)
            result = copy_task_result(result)
        records = result["records"]
        nat = records.get(self.reference, {})
        for cond, rec in records.items():
            if "error" in rec or "error" in nat or not nat:
                continue
            slot = self.acc.setdefault(cond, {})
            for family in self.families:
                family.fold(index, cond, rec, nat, slot)
        if not self.keep:  # every condition of this sequence has used them now
            for rec in records.values():
                for family in self.families:
                    family.drop(rec)
        return result


def reduce_results(plan: Plan, setup: ScoreSetup, results: list[dict[str, Any]], options: ScoreOptions | None = None,
                   *, acc: dict[str, Any] | None = None) -> ScoreResult:
    """Summary, per-sequence and per-joint rows, pooled histograms and issues from task results.

    With ``options.bootstrap``, the families' resampled statistics run on ``options.jobs`` threads;
    ``options.progress`` shows a bar of them (with an ETA). ``acc``: the sums folded while the tasks ran
    (default: fold ``results`` here). Without options: no bootstrap, no progress bar, not strict."""
    opts = options if options is not None else ScoreOptions(progress=False)
    bootstrap, seed, jobs, progress = opts.bootstrap, opts.seed, opts.jobs, opts.progress
    if acc is None:
        folder = _Folder(setup, plan.reference, keep=True)
        for i, res in enumerate(results):
            folder(i, res)
        acc = folder.acc
    conv = get_convention(setup.convention)
    records: dict[str, dict[str, dict[str, Any]]] = {c: {} for c in plan.conditions}
    issues, errors = list(plan.issues), []
    for res in results:
        for cond, rec in res["records"].items():
            if "error" in rec:
                errors.append(rec["error"])
                continue
            issues.extend(f"{cond}/{res['name']}: {w}" for w in rec.get("warnings", []))
            records[cond][res["name"]] = rec
    if errors and opts.strict:
        raise InputError(f"{len(errors)} file(s) could not be scored (--strict): " + grouped_errors(errors))
    issues.extend(f"skipped: {e}" for e in errors)
    no_track = [r["wrist_track_error"] for recs in records.values() for r in recs.values() if "wrist_track_error" in r]
    if no_track:
        issues.append("the wrist-track figure leaves files out: " + grouped_errors(no_track))
    fps_by_cond = {c: sorted({r["fps"] for r in recs.values()}) for c, recs in records.items() if recs}
    all_fps = sorted({f for v in fps_by_cond.values() for f in v})
    if not records[plan.reference]:
        raise InputError("no natural file could be scored: " + grouped_errors(errors), field="reference")
    if len(all_fps) > 1:
        detail = "; ".join(f"{c}: {', '.join(f'{f:g}' for f in v)} fps" for c, v in fps_by_cond.items())
        raise InputError(f"frame rates differ ({detail}); evalsuite does not mix rates: pass --resample FPS "
                         "to resample every file to one rate", field="fps")
    info = {name: mi for name, (_, mi) in metric_index({f.name: f for f in setup.family_objects}).items()}
    out = ScoreResult([], [], [], [], issues, errors, all_fps[0], {}, {}, plan, setup, conv, bootstrap, seed)
    ref = records[plan.reference]
    work = sum(f.bootstrap_work(setup) for f in setup.active()) * bootstrap * len(plan.conditions)
    bar = tqdm(total=work, desc="bootstrap", unit="resample", disable=not (progress and work), leave=False)
    for ci_, cond in enumerate(plan.conditions):
        recs = records[cond]
        names = sorted(s for s in recs if s in ref)
        if not names:
            issues.append(f"condition {cond!r}: no sequence could be scored together with its natural one")
            continue
        weights = bootstrap_weights(len(names), bootstrap, seed, ci_) if bootstrap else None
        ctx = ReduceContext(cond, plan.reference, names, recs, ref, setup, conv, weights, acc.get(cond, {}),
                            info=info, seed=seed, threads=jobs, progress=bar.update)
        for family in setup.active():
            family.reduce(ctx)
        bar.n = min(work, (ci_ + 1) * work // len(plan.conditions))  # a family that skipped its share
        bar.refresh()
        out.summary += ctx.summary
        out.per_sequence += ctx.per_sequence
        out.per_joint += ctx.per_joint
        out.histograms += ctx.histograms
        for fig, data in ctx.figure_data.items():
            out.figure_data.setdefault(fig, {}).update(data)
        issues += ctx.issues
    bar.close()
    out.files = {c: {s: {"path": r["path"], "sha256": r["sha256"], "n_frames": r["n_frames"]}
                     for s, r in sorted(records[c].items())} for c in plan.conditions}
    out.wrist_tracks = {c: [records[c][s]["wrist_track"] for s in sorted(records[c])
                            if records[c][s].get("wrist_track") is not None] for c in plan.conditions}
    out.resampled = sorted({f"{r['path']} ({e['from_fps']:g} -> {e['to_fps']:g} fps, {e['why']})"
                            for recs in records.values() for r in recs.values() for e in r.get("resampled", ())})
    return out


def plan_for(reference: str | pathlib.Path, conditions: Sequence[str | pathlib.Path], options: ScoreOptions) -> Plan:
    """The files to score (:func:`evalsuite.metrics.planning.plan_scoring`) with the options' joints, audio,
    strictness, frame rate and corpus."""
    return plan_scoring(reference, conditions, options.joints, options.audio_dir, options.strict, options.fps,
                        options.corpus)


def setup_for(plan: Plan, options: ScoreOptions) -> ScoreSetup:
    """The workers' setup: metrics of every registered family plus ``options.extra_families`` (each metric of a
    default extra family is wanted even when not named), groups, and histogram bins (probed when not given)."""
    conv = get_convention(options.convention)
    extra = options.extra_families
    families = {**registered_families(), **{f.name: f for f in extra}}
    metric_list = resolve_metrics(options.metrics, options.audio_dir is not None, families, options.corpus is not None)
    for fam in extra:
        metric_list += [m.name for m in fam.metrics if m.name not in metric_list and fam.default]
    setup = ScoreSetup(joints=plan.joints, metrics=metric_list, family_objects=tuple(families.values()),
                       convention=conv.name, fps=options.fps, resample=options.resample,
                       groups=resolve_groups(options.groups, plan.joints), sigma=options.sigma, figures=options.figures)
    if "histograms" in setup.families:
        setup.edges = _edges(plan, setup, conv, options)
    return setup


def tasks_for(plan: Plan, setup: ScoreSetup) -> list[ScoreTask]:
    """One task per sequence name of the plan (sorted), with that name's file in every condition that has it."""
    return [ScoreTask(s, tuple((c, plan.files[c][s]) for c in plan.conditions if s in plan.files[c]),
                      plan.audio.get(s), setup, plan.segments.get(s)) for s in plan.names]


def score_plan(plan: Plan, options: ScoreOptions, *, keep_task_results: bool = False) -> ScoreResult:
    """Score a plan: setup -> tasks -> run -> reduce (module docstring) -> :class:`ScoreResult`; ``plan.samples`` as
    ``options.samples`` says. ``keep_task_results``: ``result.task_results`` holds each task's result in order."""
    given, plan = plan, expand_for_each(plan) if options.samples == "each" else plan
    setup = setup_for(plan, options)
    tasks = tasks_for(plan, setup)
    kept: list[dict[str, Any]] | None = [] if keep_task_results else None
    folder = _Folder(setup, plan.reference, keep=bool(options.bootstrap), kept=kept)
    results = run(score_sequence, tasks, jobs=options.jobs, dask_address=options.dask_address,
                  progress=options.progress, weights=[len(t.entries) for t in tasks], desc="scoring",
                  consume=folder, describe=ScoreTask.describe)
    out = reduce_results(plan, setup, results, options, acc=folder.acc)
    label_samples(out, given, options.samples, setup.family_objects)
    out.task_results = kept if kept is not None else []
    return out


def score_folders(reference: str | pathlib.Path, conditions: Sequence[str | pathlib.Path],
                  options: ScoreOptions | None = None, **overrides: Any) -> ScoreResult:
    """Score condition folders against a natural folder with every registered family (plus
    ``options.extra_families``, e.g. FGD with a trained model) -> :class:`ScoreResult`.

    ``overrides`` are :class:`ScoreOptions` fields applied to ``options`` (or to the defaults), so
    ``score_folders(ref, conds, joints="genea2020_upper", bootstrap=1000)`` works too; an unknown name is a
    ``TypeError`` naming the closest option. With ``corpus``, files are matched to its segments by name
    (stem = segment id), which brings their speech and transcripts."""
    opts = (options if options is not None else ScoreOptions()).replace(**overrides)
    return score_plan(plan_for(reference, conditions, opts), opts)


def _edges(plan: Plan, setup: ScoreSetup, conv: Convention, options: ScoreOptions) -> dict[str, np.ndarray]:
    given = {q: options.bins(q) or conv.bins(q) for q in ("speed", "acceleration")}
    edges = {q: reference_edges(*b) for q, b in given.items() if b is not None}
    auto = [q for q, b in given.items() if b is None]
    if auto:
        ref_files = [plan.files[plan.reference][s] for s in plan.names]
        probes = run(probe_ranges, [(p, setup) for p in ref_files], jobs=options.jobs,
                     dask_address=options.dask_address, progress=options.progress, desc="bin ranges")
        for q in auto:
            vals = [p[q] for p in probes if "error" not in p and np.isfinite(p[q])]
            edges[q] = automatic_edges(max(vals) if vals else 1.0)
    return edges
