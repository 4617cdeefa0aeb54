"""The demo's steps from speech to statistics; each reads what the earlier ones wrote under ``out``.

corpus -> train the re-implementations -> generate the test split with them and the built-in conditions ->
score (FGD included) -> render side-by-side videos with the speech -> build the study -> simulate participants
-> analyse -> correlate metrics with the (simulated) ratings. Every step goes through the same commands a
researcher types (``evalsuite corpus synth``, ``train``, ``generate``, ``score``, ``fgd train``, ``render``,
``study``, ``analyze``, ``correlate``), so the demo is also their integration test.
"""
from __future__ import annotations

import pathlib
import shutil
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from evalsuite.errors import InputError

__all__ = ["DemoSettings", "STEPS", "SYSTEMS", "BUILTINS", "LATENT_QUALITY"]

Echo = Callable[[str], None]

# The re-implemented seed systems the demo trains (only those this installation has), and the conditions
# every study has.
SYSTEMS = ("gesticulator", "aud2repr2pose", "gesture2vec", "ferstl-mogan")
BUILTINS = ("natural", "oracle", "mismatched", "random_segments", "mean_pose")
# SIMULATED participants rate from these stated latent qualities (a simulation, never a human result).
LATENT_QUALITY = {"natural": 1.5, "oracle": 1.3, "gesticulator": 0.5, "aud2repr2pose": 0.4, "gesture2vec": 0.3,
                  "ferstl-mogan": 0.45, "aud2repr2pose-demo": 0.35, "random_segments": 0.2, "mismatched": 0.0,
                  "mean_pose": -1.0}


@dataclass
class DemoSettings:
    out: pathlib.Path
    minutes: float = 6.0
    budget_minutes: float = 1.0
    seed: int = 0
    demo_model: pathlib.Path | None = None
    systems: tuple[str, ...] = SYSTEMS
    summary: dict[str, Any] = field(default_factory=dict)


def cli(args: list[str]) -> None:
    """Run an ``evalsuite`` command in process (as a user would type it); a failure is an InputError."""
    from click import ClickException

    from evalsuite.cli import main

    try:
        main(args, standalone_mode=False)
    except ClickException as exc:
        raise InputError(f"evalsuite {' '.join(args[:2])}: {exc.format_message()}") from None


def corpus(s: DemoSettings, echo: Echo) -> None:
    root = s.out / "corpus"
    if root.exists():
        shutil.rmtree(root)
    cli(["corpus", "synth", "-o", str(root), "--minutes", str(s.minutes), "--seed", str(s.seed), "--quiet"])
    from evalsuite.corpus import load_corpus

    c = load_corpus(root)
    echo(f"  {root}: {len(c)} segments, {sum(x.duration or 0 for x in c) / 60:.1f} min of espeak-ng speech with "
         f"the synthetic speaker's motion (train {len(c.split('train'))}, val {len(c.split('val'))}, "
         f"test {len(c.split('test'))})")


def _available(names: tuple[str, ...]) -> list[str]:
    from evalsuite.generators.registry import BUILTIN

    return [n for n in names if n in BUILTIN]


def train(s: DemoSettings, echo: Echo) -> None:
    import json

    for name in _available(s.systems):
        model = s.out / "models" / name
        cli(["train", "-g", name, "--corpus", str(s.out / "corpus"), "--budget-minutes", str(s.budget_minutes),
             "--seed", str(s.seed), "-o", str(model)])
        record = json.loads((model / "model.json").read_text())
        echo(f"  {name}: {len(record['history'])} epochs in {record['training_seconds']:.0f} s -> {model}")


def generate(s: DemoSettings, echo: Echo) -> None:
    corpus_dir, cond = str(s.out / "corpus"), s.out / "conditions"
    train_bvh = str(s.out / "corpus" / "trn" / "main-agent" / "bvh")
    for name in BUILTINS:
        extra = ["--set", f"from={train_bvh}"] if name == "mean_pose" else []
        cli(["generate", "-g", name, "--corpus", corpus_dir, "--split", "test", "--seed", str(s.seed), *extra,
             "-o", str(cond / name)])
    for name in _available(s.systems):
        cli(["generate", "-g", name, "--model", str(s.out / "models" / name), "--corpus", corpus_dir,
             "--split", "test", "--seed", str(s.seed), "-o", str(cond / name)])
    if s.demo_model is not None:
        cli(["generate", "-g", "aud2repr2pose-demo", "--model", str(s.demo_model), "--corpus", corpus_dir,
             "--split", "test", "-o", str(cond / "aud2repr2pose-demo")])
    speech = s.out / "speech"
    speech.mkdir(exist_ok=True)
    from evalsuite.corpus import load_corpus

    for seg in load_corpus(corpus_dir).split("test"):
        if seg.audio is not None:
            shutil.copyfile(seg.audio, speech / f"{seg.id}.wav")
    names = sorted(p.name for p in cond.iterdir() if p.is_dir())
    echo(f"  {len(names)} conditions of the test split in {cond}: {', '.join(names)}")


def score(s: DemoSettings, echo: Echo) -> None:
    fgd = s.out / "fgd" / "encoder.pt"
    fgd.parent.mkdir(parents=True, exist_ok=True)
    cli(["fgd", "train", str(s.out / "corpus" / "trn" / "main-agent" / "bvh"), "--joints", "genea2020_upper",
         "--epochs", "20", "--seed", str(s.seed), "--quiet", "-o", str(fgd)])
    cond = s.out / "conditions"
    others = [f"{p.name}={p}" for p in sorted(cond.iterdir()) if p.is_dir() and p.name != "natural"]
    cli(["score", "-r", f"natural={cond / 'natural'}", *others, "--joints", "genea2020_upper",
         "--audio", str(s.out / "speech"), "--corpus", str(s.out / "corpus"), "--fgd", str(fgd),
         "--bootstrap", "200", "--seed", str(s.seed), "--quiet", "-o", str(s.out / "score")])
    echo(f"  summary.csv, per-sequence and per-joint tables and figures in {s.out / 'score'} (FGD from {fgd})")


def render(s: DemoSettings, echo: Echo) -> None:
    from renderers.demo import run as render_run

    render_run(s.out, echo)


def study(s: DemoSettings, echo: Echo) -> None:
    from study_app.demo import run as study_run

    study_run(s.out, echo)


def analyse(s: DemoSettings, echo: Echo) -> None:
    from evalsuite.analysis.simulate_study import simulate_study

    cond = s.out / "conditions"
    names = [p.name for p in sorted(cond.iterdir()) if p.is_dir()]
    quality = {n: LATENT_QUALITY.get(n, 0.3) for n in names}
    results = s.out / "results.csv"
    simulate_study(quality, segments=sorted(p.stem for p in (s.out / "speech").glob("*.wav")),
                   seed=s.seed).to_csv(results, index=False)
    echo(f"  {results}: SIMULATED participants rating from stated latent qualities "
         f"({', '.join(f'{k} {v:g}' for k, v in quality.items())}); a real study replaces it with "
         "`evalsuite study export`")
    cli(["analyze", str(results), "-o", str(s.out / "analysis")])
    echo(f"  report: {s.out / 'analysis' / 'report.html'}")


def correlate(s: DemoSettings, echo: Echo) -> None:
    import contextlib
    import io

    import pandas as pd

    target = s.out / "correlate"
    with contextlib.redirect_stdout(io.StringIO()):  # its full table is in correlations.md
        cli(["correlate", str(s.out / "score" / "summary.csv"), str(s.out / "analysis" / "ratings.csv"),
             "--natural", "natural", "-o", str(target)])
    table = pd.read_csv(target / "correlations.csv")
    s.summary["correlations"] = table
    echo(f"  Spearman/Kendall of {table['metric'].nunique()} metrics with the simulated MUSHRA ratings -> "
         f"{target / 'correlations.csv'}")


STEPS: list[tuple[str, Callable[[DemoSettings, Echo], None]]] = [
    ("Corpus: synthesise a speaker (espeak-ng speech, procedural gestures with known coupling)", corpus),
    ("Train: the re-implemented seed systems, each for a short budget", train),
    ("Generate: the test split with them and the built-in conditions", generate),
    ("Score: every condition against natural motion (FGD, coupling and beat metrics included)", score),
    ("Render: side-by-side videos with the speech, and blinded study stimuli", render),
    ("Study: build a pairwise + MUSHRA study from the stimuli", study),
    ("Analyse: simulated participants, then `evalsuite analyze`", analyse),
    ("Correlate: objective metrics against the (simulated) ratings", correlate),
]
