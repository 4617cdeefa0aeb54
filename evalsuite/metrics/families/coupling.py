"""Speech-gesture coupling family (:mod:`evalsuite.metrics.coupling`), active with ``--corpus DIR``.

Each condition's file is matched to the corpus segment of the same name (stem = segment id), whose speech
and transcript it is scored against: the correlation of speech energy with wrist speed (best lag within
+-0.3 s), lexical contrast of the corpus's keyword classes (corpus.json's ``keyword_classes``, as the synthetic speaker
writes them; each class's feature from :data:`CLASS_FEATURES`; not measured where the corpus has none), and, where a
per-frame label file exists for the file (``labels/<stem>.csv`` beside or one folder above the motion's
folder, as the synthetic corpus writes them), phase-structure statistics.
"""
from __future__ import annotations

import pathlib

import numpy as np

from evalsuite.errors import InputError
from evalsuite.metrics.coupling import (
    CLASS_FEATURES,
    energy_speed_correlation,
    joint_speed,
    lexical_classes,
    lexical_contrasts,
    phase_statistics,
    read_phase_labels,
    speech_energy,
    wrist_indices,
)
from evalsuite.metrics.families.base import MetricFamily, MetricInfo, ReduceContext, SequenceContext

__all__ = ["CouplingFamily", "FAMILY"]

MAX_LAG_S = 0.3
PHASE_METRICS = {"phase_stroke_fraction": ("stroke", "fraction"), "phase_rest_fraction": ("rest", "fraction"),
                 "phase_stroke_duration": ("stroke", "duration")}


def _labels_path(motion_path: str | None) -> pathlib.Path | None:
    if not motion_path:
        return None
    p = pathlib.Path(motion_path)
    for folder in (p.parent / "labels", p.parent.parent / "labels"):
        if (folder / f"{p.stem}.csv").is_file():
            return folder / f"{p.stem}.csv"
    return None


class CouplingFamily(MetricFamily):
    """Per sequence: energy-speed correlation and its lag, lexical contrast per keyword class, phase statistics."""

    name = "coupling"
    metrics = (
        MetricInfo("energy_speed_r", "r", "higher",
                   description=f"best correlation of speech energy and wrist speed, lags within +-{MAX_LAG_S:g} s"),
        MetricInfo("energy_speed_lag", "s", "closer to natural", description="lag of the best correlation"),
        *(MetricInfo(f"lexical_contrast_{c}", "deg/s" if feature == "head_yaw_speed" else "units", "higher",
                     description=f"{feature} after the corpus's {c!r} keywords minus its sequence mean")
          for c, feature in CLASS_FEATURES.items()),
        *(MetricInfo(m, "s" if what == "duration" else "fraction", "closer to natural",
                     description=f"{what} of {phase} frames (from a per-frame label file)")
          for m, (phase, what) in PHASE_METRICS.items()),
    )
    default = False
    needs_corpus = True

    def measure(self, ctx: SequenceContext) -> None:
        seg = ctx.segment
        if seg is None or ctx.audio is None:
            return
        motion = ctx.motion
        pos = np.asarray(motion.positions())
        names = list(motion.joint_names)
        n, fps = len(pos), ctx.fps
        signal, sr = ctx.audio
        energy = ctx.natural_cache.setdefault(("coupling_energy", n, fps), speech_energy(signal, sr, fps, n))
        try:
            speed = joint_speed(pos[:, wrist_indices(names)], fps)
        except InputError as exc:
            ctx.record.setdefault("warnings", []).append(f"coupling: {exc}")
            return
        r, lag, _ = energy_speed_correlation(energy, speed, fps, MAX_LAG_S)
        ctx.record["energy_speed_r"], ctx.record["energy_speed_lag"] = r, lag
        classes = lexical_classes(seg.meta.get("keyword_classes"))
        if seg.transcript is not None and classes:
            rot = None
            if motion.is_hierarchical and "Head" in names:
                rot = motion.world_rotations()[:, names.index("Head")]
            words = [(w.text, w.start) for w in seg.transcript.words]
            try:
                for c, v in lexical_contrasts(words, pos, names, fps, classes, head_rotations=rot).items():
                    ctx.record[f"lexical_contrast_{c}"] = v
            except InputError as exc:
                ctx.record.setdefault("warnings", []).append(f"lexical contrast: {exc}")
        labels = _labels_path(motion.source)
        if labels is not None:
            stats = phase_statistics(read_phase_labels(labels), fps)
            for m, (phase, what) in PHASE_METRICS.items():
                table = stats.proportion if what == "fraction" else stats.mean_duration
                ctx.record[m] = float(table.get(phase, float("nan")))

    def reduce(self, ctx: ReduceContext) -> None:
        for info in self.metrics:
            q = info.name
            if ctx.wants(q) and any(q in ctx.recs[s] for s in ctx.names):
                ctx.mean_metric(q, [float(ctx.recs[s].get(q, float("nan"))) for s in ctx.names])


FAMILY = CouplingFamily()
