"""``evalsuite features``: compute one recipe's features of a WAV file (and/or a transcript) into a ``.npy`` file."""
from __future__ import annotations

import json
import pathlib

import click
import numpy as np

from evalsuite.corpus.types import Transcript
from evalsuite.errors import InputError

__all__ = ["features", "read_transcript_file"]


def read_transcript_file(path: str | pathlib.Path) -> Transcript:
    """A transcript file in any format of :func:`evalsuite.corpus.transcripts.read_transcript`."""
    from evalsuite.corpus.transcripts import read_transcript

    path = pathlib.Path(path)
    if not path.is_file():
        raise InputError("no such transcript file", path=path)
    return read_transcript(path)


def _parse_options(pairs: tuple[str, ...]) -> dict:
    out = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep or not key:
            raise InputError(f"expected KEY=VALUE, got {pair!r}", field="--option")
        try:
            out[key] = json.loads(value)
        except ValueError:
            out[key] = value
    return out


def _listing() -> str:
    from evalsuite.features import list_recipes

    lines = []
    for r in list_recipes():
        rate = f"{r.native_fps:.6g} fps" if r.native_fps else "any fps"
        dim = "x".join(map(str, r.dim)) if isinstance(r.dim, tuple) else str(r.dim or "model's")
        needs = ", ".join(x for x in ("audio" if r.needs_audio else "", "transcript" if r.needs_transcript else "",
                                      f"extra [{r.extra}]" if r.extra else "") if x)
        opts = ", ".join(f"{k}={v!r}" for k, v in r.params.items())
        lines.append(f"{r.name}\n    {dim} per frame, {rate}; needs {needs}\n    reproduces: {r.reproduces}"
                     f"\n    quirks: {r.quirks}" + (f"\n    options: {opts}" if opts else ""))
    return "\n".join(lines)


@click.command("features")
@click.argument("audio", required=False, type=click.Path(dir_okay=False, path_type=pathlib.Path))
@click.option("--recipe", "-r", help="recipe name (see --list)")
@click.option("--fps", type=float, default=None, help="frame rate (default: the recipe's native rate)")
@click.option("--n-frames", type=int, default=None, help="crop or edge-pad to exactly this many frames")
@click.option("--transcript", "-t", type=click.Path(dir_okay=False, path_type=pathlib.Path),
              help="word timings (GENEA TSV: start, end, word) for the text recipes")
@click.option("--option", "options", multiple=True, metavar="KEY=VALUE", help="a recipe option (repeatable)")
@click.option("--cache-dir", type=click.Path(file_okay=False, path_type=pathlib.Path), default=None,
              help="feature cache folder (default: ~/.cache/evalsuite/features or $EVALSUITE_CACHE_DIR)")
@click.option("--no-cache", is_flag=True, help="neither read nor write the cache")
@click.option("--output", "-o", type=click.Path(dir_okay=False, path_type=pathlib.Path), help="the .npy file to write")
@click.option("--list", "list_", is_flag=True, help="list the recipes and exit")
def features(audio, recipe, fps, n_frames, transcript, options, cache_dir, no_cache, output, list_):
    """Speech or text features of AUDIO.wav by recipe, as the reference systems compute them.

    \b
    evalsuite features speech.wav --recipe mfcc_kucherenko -o mfcc.npy          # (T, 26) at 20 fps
    evalsuite features speech.wav --recipe aud2repr2pose_demo_windows -o x.npy  # (T, 61, 30)
    evalsuite features speech.wav --recipe words_minilm -t speech.tsv -o w.npy  # (T, 384)
    evalsuite features --list
    """
    if list_:
        click.echo(_listing())
        return
    if not recipe:
        raise click.UsageError("give --recipe NAME (or --list)")
    if output is None:
        raise click.UsageError("give -o OUT.npy")
    from evalsuite.features import extract

    words = read_transcript_file(transcript) if transcript is not None else None
    data = extract(recipe, audio, fps=fps, n_frames=n_frames, transcript=words, cache=not no_cache,
                   cache_dir=cache_dir, **_parse_options(options))
    output.parent.mkdir(parents=True, exist_ok=True)
    np.save(output, data)
    from evalsuite.features import get_recipe

    native = get_recipe(recipe).native_fps
    how = ""
    if native is not None and fps is not None and abs(fps - native) > 1e-9 * fps:
        how = f" (resampled from {native:.6g} fps by linear interpolation in time)"
    click.echo(f"{output}: {recipe} {tuple(data.shape)} float32{how}")
