"""``evalsuite features``: compute one recipe's features of a WAV file (and/or a transcript) into a ``.npy`` file."""
from __future__ import annotations

import importlib
import json
import pathlib

import click
import numpy as np

from evalsuite.corpus.types import Transcript, Word
from evalsuite.errors import InputError

__all__ = ["features", "read_transcript_file"]


def _read_tsv(path: pathlib.Path) -> Transcript:
    """A GENEA 2022/2023-style TSV (start, end, word per line; seconds).

    Interim reader: to be replaced by ``evalsuite.corpus.transcripts.read_transcript`` (the corpus readers),
    which :func:`read_transcript_file` uses as soon as it exists."""
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read the transcript ({exc})", path=path) from None
    words: list[Word] = []
    for lineno, line in enumerate(text.splitlines(), start=1):
        if not line.strip():
            continue
        parts = line.rstrip("\r\n").split("\t")
        if len(parts) < 3:
            raise InputError(f"expected 3 tab-separated fields (start, end, word), got {len(parts)}",
                             path=path, line=lineno)
        try:
            start, end = float(parts[0]), float(parts[1])
        except ValueError:
            if lineno == 1 and not words:
                continue                      # a header line
            raise InputError(f"expected start and end times in seconds, got {parts[0]!r}, {parts[1]!r}",
                             path=path, line=lineno) from None
        words.append(Word("\t".join(parts[2:]).strip(), start, end))
    return Transcript(tuple(words), source=str(path))


def read_transcript_file(path: str | pathlib.Path) -> Transcript:
    """A transcript file through the corpus readers when present, else the interim TSV reader."""
    path = pathlib.Path(path)
    if not path.is_file():
        raise InputError("no such transcript file", path=path)
    try:
        readers = importlib.import_module("evalsuite.corpus.transcripts")
    except ImportError:
        return _read_tsv(path)
    result: Transcript = readers.read_transcript(path)
    return result


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
