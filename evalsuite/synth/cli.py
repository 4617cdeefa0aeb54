"""``evalsuite corpus synth``: write a synthetic-speaker corpus (the click command; the ``corpus`` group
attaches it)."""
from __future__ import annotations

import pathlib
import time

import click

from evalsuite.synth.skeletons import SKELETONS


@click.command("synth")
@click.option("-o", "--out", "out_dir", required=True, type=click.Path(file_okay=False, path_type=pathlib.Path),
              help="Folder to create (must be new or empty).")
@click.option("--minutes", type=click.FloatRange(min=0.05), default=10.0, show_default=True,
              help="About how many minutes of speech.")
@click.option("--seed", type=int, default=0, show_default=True, help="Seed: one seed gives identical files.")
@click.option("--segment-seconds", type=click.FloatRange(min=5.0), default=20.0, show_default=True,
              help="About how long each segment is (several sentences).")
@click.option("--speaker", default="synth01", show_default=True, help="Speaker id written to corpus.json.")
@click.option("--jobs", type=click.IntRange(min=1), default=2, show_default=True,
              help="Parallel espeak-ng processes.")
@click.option("--skeleton", type=click.Choice(SKELETONS), default="genea2020", show_default=True,
              help="Skeleton of the motion files: the speaker's GENEA 2020 upper body, the GENEA 2022/2023 "
                   "hierarchy with fingers, BEAT's Mixamo-style names, or SMPL-X .npz rotations (docs/corpus.md).")
@click.option("--quiet", is_flag=True, help="No progress bar.")
def synth(out_dir: pathlib.Path, minutes: float, seed: int, segment_seconds: float, speaker: str, jobs: int,
          skeleton: str, quiet: bool) -> None:
    """Synthesise a speaker corpus: espeak-ng speech with exact word times and motion from a documented
    procedural gesture model (docs/corpus.md § The synthetic speaker), in the GENEA 2023 layout with per-frame gesture
    labels and corpus.json.

    Example: evalsuite corpus synth -o corpus/ --minutes 10 --seed 0 [--skeleton genea2023]
    """
    from evalsuite.synth import Layout, synthesize_corpus

    t0 = time.perf_counter()
    meta = synthesize_corpus(out_dir, minutes, seed, layout=Layout(segment_s=segment_seconds), speaker=speaker,
                             jobs=jobs, progress=not quiet, skeleton=skeleton)
    total = sum(s["duration"] for s in meta["segments"].values())
    counts = ", ".join(f"{k} {len(v)}" for k, v in meta["splits"].items())
    if not quiet:
        click.echo(f"Wrote {len(meta['segments'])} segments ({total / 60:.1f} min; {counts}) to {out_dir} "
                   f"in {time.perf_counter() - t0:.1f} s")
