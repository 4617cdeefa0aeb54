"""``evalsuite corpus``: look into a corpus folder (``info``) and assign seeded splits (``split``).

More subcommands register in :data:`SUBCOMMANDS` (name -> ``"module:attribute"``), imported only when used,
so adding one (e.g. ``synth``) is one line here plus its own module.
"""
from __future__ import annotations

import contextlib
import functools
import importlib
import importlib.util
import json
import pathlib
import warnings
from collections import Counter
from collections.abc import Iterator
from typing import Any

import click

from evalsuite.corpus.readers import LAYOUTS, MISMATCH_POLICIES, load_corpus, mismatch_policy
from evalsuite.corpus.splits import split_corpus, write_splits
from evalsuite.corpus.types import SPLITS, Corpus
from evalsuite.errors import InputError

# Lazily imported subcommands: name -> "module:attribute" (a click command).
SUBCOMMANDS: dict[str, str] = {"synth": "evalsuite.synth.cli:synth",
                               "mean-velocity": "evalsuite.leaderboard.meanvel_cli:mean_velocity_command"}


def _exists(module: str) -> bool:
    try:
        return importlib.util.find_spec(module) is not None
    except ImportError:
        return False


class _CorpusGroup(click.Group):
    """Built-in subcommands plus the lazily imported :data:`SUBCOMMANDS` whose module is present."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        lazy = {n for n, target in SUBCOMMANDS.items() if _exists(target.split(":")[0])}
        return sorted(set(super().list_commands(ctx)) | lazy)

    def get_command(self, ctx: click.Context, name: str) -> click.Command | None:
        cmd = super().get_command(ctx, name)
        if cmd is None and name in SUBCOMMANDS and _exists(SUBCOMMANDS[name].split(":")[0]):
            module, attr = SUBCOMMANDS[name].split(":")
            cmd = getattr(importlib.import_module(module), attr)
        return cmd


@contextlib.contextmanager
def _user_errors() -> Iterator[None]:
    try:
        yield
    except InputError as exc:
        raise click.ClickException(str(exc)) from exc


def _group_help() -> str:
    layouts = "\n".join(f"  {n}: {lay.description}" for n, lay in LAYOUTS.items())
    return ("Speech-gesture corpora: audio, word-timed transcripts and motion per segment.\n\n"
            "\b\nLayouts read (detected, or named with --layout):\n" + layouts + "\n\n"
            "\b\nExamples:\n"
            "  evalsuite corpus info GENEA2023/\n"
            "  evalsuite corpus info my_takes/ --layout folder --json\n"
            "  evalsuite corpus split my_takes/ --val 0.1 --test 0.1 --seed 0 -o my_takes/splits.csv\n")


@click.group(cls=_CorpusGroup, help=_group_help(), context_settings={"help_option_names": ["-h", "--help"]})
def corpus() -> None:
    pass


def _load_options(f: Any) -> Any:
    f = click.option("--motion-fps", type=float, default=None,
                     help="Frame rate of motion files that store none (.npy, .csv).")(f)
    f = click.option("--tolerance-rel", type=float, default=0.02, show_default=True,
                     help="Relative audio/motion duration tolerance (of the longer).")(f)
    f = click.option("--tolerance", type=float, default=0.5, show_default=True,
                     help="Absolute audio/motion duration tolerance in seconds; the larger of the two applies.")(f)
    f = click.option("--layout", type=click.Choice(sorted(LAYOUTS)), default=None,
                     help="The corpus layout (default: detected).")(f)
    return f


def on_mismatch_option(f: Any) -> Any:
    """``--on-mismatch`` for a command that loads a corpus: the command runs inside
    ``mismatch_policy(on_mismatch)``, so every corpus it reads applies the option and a mismatch error names it.
    The command function itself takes no ``on_mismatch`` parameter."""
    @functools.wraps(f)
    def run(*args: Any, on_mismatch: str, **kwargs: Any) -> Any:
        with mismatch_policy(on_mismatch):
            return f(*args, **kwargs)

    return click.option("--on-mismatch", type=click.Choice(MISMATCH_POLICIES), default="error", show_default=True,
                        help="Corpus segments whose audio and motion durations disagree: stop at the first (error), "
                             "keep them with a warning (warn), or leave them out (skip).")(run)


def _seconds(t: float) -> str:
    m, s = divmod(t, 60.0)
    h, m = divmod(int(m), 60)
    return f"{t:.1f} s ({h}:{m:02d}:{s:04.1f})"


def summarize(c: Corpus) -> dict[str, Any]:
    """What ``corpus info`` reports, as plain data (the ``--json`` output)."""
    def dur(segs: Any) -> float:
        return float(sum(s.duration or 0.0 for s in segs))

    def split_name(seg: Any) -> str:
        return str(seg.split) if seg.split is not None else "unassigned"

    names = {split_name(seg) for seg in c}
    order = [n for n in SPLITS if n in names] + sorted(names - set(SPLITS))
    splits = {}
    for name in order:
        segs = [s for s in c if split_name(s) == name]
        splits[name] = {"segments": len(segs), "duration": dur(segs),
                        "speakers": sorted({str(s.speaker) for s in segs if s.speaker is not None})}
    missing: dict[str, list[str]] = {}
    for s in c:
        for part in s.meta.get("missing", []):
            missing.setdefault(part, []).append(s.id)
    return {
        "root": str(c.root), "layout": c.layout, "segments": len(c), "duration": dur(c), "splits": splits,
        "speakers": list(c.speakers),
        "audio_rates": {str(k): v for k, v in sorted(Counter(s.meta.get("audio_rate") for s in c
                                                           if s.audio is not None).items())},
        "audio_channels": {str(k): v for k, v in sorted(Counter(s.meta.get("audio_channels") for s in c
                                                              if s.audio is not None).items())},
        "motion_fps": {f"{k:g}" if isinstance(k, float) else str(k): v
                       for k, v in sorted(Counter(s.meta.get("motion_fps") for s in c if s.motion is not None).items(),
                                          key=lambda kv: (kv[0] is None, kv[0] or 0))},
        "transcripts": sum(s.transcript is not None for s in c),
        "estimated_transcripts": sum(s.transcript is not None and s.transcript.estimated for s in c),
        "interlocutor_streams": sum(s.interlocutor is not None for s in c),
        "labels": sum(s.labels is not None for s in c),
        "missing": missing, "mismatches": c.meta.get("mismatches", []), "skipped": c.meta.get("skipped", []),
        "corpus_json": c.meta.get("corpus_json"), "metadata_files": c.meta.get("metadata_files"),
        "beat2": c.meta.get("beat2"),
    }


def _counts(d: dict[str, int], unit: str) -> str:
    return ", ".join(f"{k}{unit} x{v}" for k, v in d.items()) or "none"


def _print_info(info: dict[str, Any]) -> None:
    echo = click.echo
    echo(f"corpus:     {info['root']}")
    echo(f"layout:     {info['layout']}")
    echo(f"segments:   {info['segments']}, {_seconds(info['duration'])}")
    for name, sp in info["splits"].items():
        echo(f"  {name:<10} {sp['segments']} segments, {_seconds(sp['duration'])}, "
             f"{len(sp['speakers'])} speakers")
    spk = info["speakers"]
    echo(f"speakers:   {len(spk)}" + (f" ({', '.join(spk[:20])}{', ...' if len(spk) > 20 else ''})" if spk else ""))
    if info.get("metadata_files") is not None:  # the GENEA layouts: where the speaker ids come from
        echo("metadata:   " + (", ".join(info["metadata_files"]) or "none found (speaker ids come from metadata.csv "
                                                                     "in each split folder or at the root)"))
    if info.get("beat2") is not None:  # languages, semantic annotations and body shapes of BEAT2
        _print_beat2(info["beat2"])
    echo(f"audio:      {_counts(info['audio_rates'], ' Hz')}; channels {_counts(info['audio_channels'], '')}")
    echo(f"motion:     {_counts(info['motion_fps'], ' fps')}")
    echo(f"transcripts: {info['transcripts']} ({info['estimated_transcripts']} with estimated timings)")
    if info["interlocutor_streams"]:
        echo(f"interlocutor: {info['interlocutor_streams']} segments")
    if info["labels"]:
        echo(f"labels:     {info['labels']} segments with per-frame labels")
    if info["corpus_json"] is not None:
        echo(f"corpus.json: {json.dumps(info['corpus_json'], sort_keys=True)[:200]}")
    if info["missing"]:
        for part, ids in info["missing"].items():
            echo(f"missing {part}: {len(ids)} segments ({', '.join(ids[:5])}{', ...' if len(ids) > 5 else ''})")
    else:
        echo("missing:    nothing")
    if not info["mismatches"]:
        echo("mismatches: none (audio and motion durations agree)")
    for m in info["mismatches"]:
        echo(f"MISMATCH {m['segment']}: audio {m['audio']} {m['audio_duration']:.3f} s, motion {m['motion']} "
             f"{m['motion_duration']:.3f} s (tolerance {m['tolerance']:.3f} s; {m['action']})")


def _print_beat2(beat2: dict[str, Any]) -> None:
    click.echo("languages:  " + (", ".join(f"{k} ({v} segments)" for k, v in beat2["languages"].items()) or "none"))
    click.echo(f"sem:        {beat2['sem_files']} segments with semantic relevance annotations (sem/*.txt)")
    shapes = [f"{spk}: {v['n_betas'][0] if len(v['n_betas']) == 1 else v['n_betas']} betas"
              + ("" if v["distinct"] == 1 else f", {v['distinct']} different") for spk, v in beat2["betas"].items()]
    click.echo("betas:      " + ("; ".join(shapes) if shapes else "none in the motion files"))


@corpus.command()
@click.argument("directory", type=click.Path(file_okay=False, path_type=pathlib.Path))
@_load_options
@click.option("--on-mismatch", type=click.Choice(MISMATCH_POLICIES), default="warn", show_default=True,
              help="Segments whose audio and motion durations disagree: list them (warn), leave them out (skip), "
                   "or stop at the first (error).")
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON.")
def info(directory: pathlib.Path, layout: str | None, tolerance: float, tolerance_rel: float,
         motion_fps: float | None, on_mismatch: str, as_json: bool) -> None:
    """Layout, segments per split, durations, speakers, audio rates and channels, motion fps, what is missing
    and which segments' audio and motion durations disagree.

    \b
    Examples:
      evalsuite corpus info GENEA2023/
      evalsuite corpus info beat_english_v0.2.1/ --layout beat --json
      evalsuite corpus info takes/ --on-mismatch error --tolerance 0.1
    """
    with _user_errors(), warnings.catch_warnings(), mismatch_policy(on_mismatch):
        warnings.simplefilter("ignore")  # mismatches are listed in the report
        c = load_corpus(directory, layout, on_mismatch=on_mismatch, tolerance=tolerance, tolerance_rel=tolerance_rel,
                        motion_fps=motion_fps)
    data = summarize(c)
    if as_json:
        click.echo(json.dumps(data, indent=1, default=str))
    else:
        _print_info(data)


@corpus.command()
@click.argument("directory", type=click.Path(file_okay=False, path_type=pathlib.Path))
@click.option("--val", type=float, default=0.1, show_default=True, help="Share of the duration for validation.")
@click.option("--test", type=float, default=0.1, show_default=True, help="Share of the duration for testing.")
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of the assignment.")
@click.option("--by", type=click.Choice(["speaker", "segment"]), default="speaker", show_default=True,
              help="Keep speakers disjoint across splits (when there are enough speakers), or split segments.")
@click.option("-o", "--output", type=click.Path(dir_okay=False, path_type=pathlib.Path), default=None,
              help="Where to write splits.csv (default: DIRECTORY/splits.csv).")
@_load_options
@click.option("--on-mismatch", type=click.Choice(MISMATCH_POLICIES), default="error", show_default=True,
              help="Segments whose audio and motion durations disagree.")
def split(directory: pathlib.Path, val: float, test: float, seed: int, by: str, output: pathlib.Path | None,
          layout: str | None, tolerance: float, tolerance_rel: float, motion_fps: float | None,
          on_mismatch: str) -> None:
    """Assign seeded train/val/test splits and write splits.csv (segment,split).

    The same corpus and seed give the same file. With --by speaker, whole speakers go to one split where the
    corpus has at least one speaker per split.

    \b
    Examples:
      evalsuite corpus split takes/ --val 0.1 --test 0.1 --seed 0
      evalsuite corpus split BEAT/ --layout beat --seed 3 -o beat_splits.csv
    """
    with _user_errors(), mismatch_policy(on_mismatch):
        c = load_corpus(directory, layout, on_mismatch=on_mismatch, tolerance=tolerance, tolerance_rel=tolerance_rel,
                        motion_fps=motion_fps)
        c = split_corpus(c, val=val, test=test, seed=seed, by=by)
        out = output or directory / "splits.csv"
        write_splits(c, out)
    data = summarize(c)
    for name, sp in data["splits"].items():
        click.echo(f"{name:<6} {sp['segments']} segments, {_seconds(sp['duration'])}, speakers: "
                   f"{', '.join(sp['speakers']) or '-'}")
    note = "speakers disjoint" if c.meta["split"]["speakers_disjoint"] else "split by segment"
    click.echo(f"wrote {out} ({note}, seed {seed})")
