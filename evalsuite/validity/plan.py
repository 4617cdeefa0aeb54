"""The conditions of the known-truth benchmark, their graded families, and their generation.

Every condition is made by a generator plug-in (:func:`evalsuite.generators.find_generator`) through the
runner (:func:`evalsuite.generators.runner.generate`), so the benchmark exercises exactly what a study uses:

* ``natural`` (the reference), ``oracle`` (the speaker's own model, another seed: another performance);
* graded families of the oracle, each ordered from the oracle (best) to the strongest degradation:
  ``offset`` (speech-gesture time offsets, oracle option ``offset_s``), ``semantic`` (semantic gestures
  removed), ``beats`` (beats removed), ``amplitude`` (gestures attenuated by 25/50/75 %), ``jitter``
  (``gaussian_noise`` on the oracle's rotations), ``smoothing`` (``smoothed``, growing moving-average
  windows);
* the floors ``mismatched``, ``random_segments``, ``mean_pose`` and any trained model, each a two-level
  family "oracle better than it" (the oracle is the speaker itself, so nothing can beat it).
"""
from __future__ import annotations

import json
import pathlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from evalsuite.errors import InputError

__all__ = ["Condition", "Plan", "build_plan", "check_synthetic", "generate_conditions", "parse_models",
           "OFFSETS", "AMPLITUDES", "JITTER", "SMOOTHING", "PARALLEL_FROM"]

OFFSETS = (0.1, 0.3, 0.6, 1.2)          # seconds
AMPLITUDES = (0.75, 0.5, 0.25)          # gesture scale: attenuated by 25, 50, 75 %
JITTER = (0.005, 0.01, 0.02)            # radians on every rotation vector; 0.02 is the GENEA Leaderboard's
SMOOTHING = (5, 9, 15)                  # moving-average windows in frames (at 30 fps: 0.17, 0.3, 0.5 s)
PARALLEL_FROM = 60                      # segments: fewer are generated in this process (see generate_conditions)


@dataclass(frozen=True)
class Condition:
    """One condition: a generator with options; ``of`` names a condition whose output is its source."""

    name: str
    generator: str
    config: dict[str, Any] = field(default_factory=dict)
    of: str | None = None
    model_dir: pathlib.Path | None = None


@dataclass
class Plan:
    """The conditions in generation order and the graded families (name -> condition names, best first)."""

    conditions: list[Condition]
    families: dict[str, list[str]]
    levels: dict[str, list[str]]       # family -> level labels (e.g. "0.3 s"), parallel to families


def _g(x: float) -> str:
    return f"{x:g}"


def build_plan(models: Sequence[tuple[str, pathlib.Path, str]] = (), offsets: Sequence[float] = OFFSETS,
               amplitudes: Sequence[float] = AMPLITUDES, jitter: Sequence[float] = JITTER,
               smoothing: Sequence[int] = SMOOTHING) -> Plan:
    """The benchmark's conditions; ``models`` are ``(condition name, model folder, generator name)``."""
    conds = [Condition("natural", "natural"), Condition("oracle", "oracle")]
    fams: dict[str, list[str]] = {}
    levels: dict[str, list[str]] = {}

    def family(name: str, members: list[tuple[str, str, Condition]]) -> None:
        conds.extend(c for _, _, c in members)
        fams[name] = ["oracle"] + [n for n, _, _ in members]
        levels[name] = ["oracle"] + [lab for _, lab, _ in members]

    family("offset", [(f"offset_{_g(s)}", f"{_g(s)} s", Condition(f"offset_{_g(s)}", "oracle", {"offset_s": s}))
                      for s in offsets])
    family("semantic", [("no_semantic", "removed", Condition("no_semantic", "oracle", {"semantic": False}))])
    family("beats", [("no_beats", "removed", Condition("no_beats", "oracle", {"beats": False}))])
    family("amplitude", [(f"amplitude_{_g(a)}", f"x{_g(a)}", Condition(f"amplitude_{_g(a)}", "oracle",
                                                                       {"amplitude": a})) for a in amplitudes])
    family("jitter", [(f"jitter_{_g(s)}", f"{_g(s)} rad", Condition(f"jitter_{_g(s)}", "gaussian_noise",
                                                                     {"sigma": s}, of="oracle")) for s in jitter])
    family("smoothing", [(f"smoothed_{w}", f"{w} frames", Condition(f"smoothed_{w}", "smoothed",
                                                                     {"method": "moving_average", "window": int(w)},
                                                                     of="oracle")) for w in smoothing])
    for floor in ("mismatched", "random_segments", "mean_pose"):
        family(floor, [(floor, floor, Condition(floor, floor))])
    for name, folder, gen in models:
        family(name, [(name, name, Condition(name, gen, model_dir=folder))])
    names = [c.name for c in conds]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise InputError(f"condition name(s) used twice: {', '.join(dup)}; name each --model differently",
                         field="--model")
    for fam, members in fams.items():
        if len(members) < 2:
            raise InputError(f"family {fam!r} needs at least one level besides the oracle", field=fam)
    return Plan(conds, fams, levels)


def parse_models(items: Sequence[str]) -> list[tuple[str, pathlib.Path, str]]:
    """``NAME=DIR`` items -> ``(name, folder, generator)``, the generator read from the folder's model.json
    (written by ``evalsuite train``)."""
    out = []
    for item in items:
        name, sep, folder = item.partition("=")
        if not sep or not name.strip() or not folder.strip():
            raise InputError(f"--model takes NAME=DIR (a model folder written by `evalsuite train`), got {item!r}",
                             field="--model")
        path = pathlib.Path(folder.strip())
        meta = path / "model.json"
        if not meta.is_file():
            raise InputError("not a model folder of evalsuite (no model.json); train one with `evalsuite train`",
                             path=path, field="--model")
        try:
            record = json.loads(meta.read_text(encoding="utf-8"))
            gen = record.get("target") or record["generator"]["name"]
        except (ValueError, KeyError, TypeError, AttributeError):
            raise InputError("model.json does not name its generator (expected generator.name)", path=meta,
                             field="--model") from None
        out.append((name.strip(), path, str(gen)))
    return out


def check_synthetic(corpus: Any) -> None:
    """InputError unless ``corpus`` was written by the synthetic speaker (the oracle needs its model)."""
    model = (corpus.meta.get("corpus_json") or corpus.meta).get("model")
    if not isinstance(model, dict) or "params" not in model:
        raise InputError("not a synthetic-speaker corpus (its corpus.json has no model parameters): the known-truth "
                         "benchmark needs the oracle, which exists only for corpora written by the synthetic "
                         "speaker: evalsuite corpus synth -o corpus/ --minutes 10 --seed 0",
                         path=corpus.root, field="--corpus")


def generate_conditions(plan: Plan, corpus: Any, requests: Sequence[Any], out_dir: pathlib.Path, *, seed: int = 0,
                        jobs: int = 1, progress: bool = True,
                        echo: Callable[[str], None] | None = None) -> dict[str, pathlib.Path]:
    """Generate every condition of ``plan`` into ``out_dir/<condition>/`` (the runner's cache makes a rerun with
    the same settings instant) -> condition name -> folder. The built-in conditions take milliseconds per
    segment, so worker processes (which cost seconds each to start, per condition) are used only from
    :data:`PARALLEL_FROM` segments on."""
    from evalsuite.generators import find_generator
    from evalsuite.generators.runner import generate

    folders: dict[str, pathlib.Path] = {}
    for cond in plan.conditions:
        entry = find_generator(cond.generator)
        assert entry.spec is not None
        config = dict(cond.config)
        if "corpus" in entry.spec.config:
            config.setdefault("corpus", str(pathlib.Path(corpus.root).resolve()))
        if cond.of is not None:
            config["of"] = str(folders[cond.of].resolve())
        folder = out_dir / cond.name
        parallel = cond.model_dir is not None or len(requests) >= PARALLEL_FROM
        run = generate(entry, requests, folder, config=config, model_dir=cond.model_dir, seed=seed,
                       jobs=jobs if parallel else 1,
                       progress=progress, extra_record={"validity_condition": cond.name})
        if echo is not None:
            echo(f"  {cond.name:<18} {len(run.files)} files" + (" (up to date)" if run.cached else ""))
        folders[cond.name] = folder
    return folders
