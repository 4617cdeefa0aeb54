"""The files of a synthetic-speaker corpus (the GENEA 2023 layout plus labels and ``corpus.json``), and a
small reader of that layout.

``DIR/{trn,val,tst}/main-agent/{wav,bvh,tsv,labels}/<id>.{wav,bvh,tsv,csv}`` and ``DIR/corpus.json``.

:func:`read_synth_corpus` is a stop-gap: it will be replaced by ``evalsuite.corpus.load_corpus`` (the
corpus readers), which reads GENEA 2023 folders in general.
"""
from __future__ import annotations

import json
import pathlib
from typing import Any

from evalsuite.corpus.types import Corpus, Transcript, Word
from evalsuite.errors import InputError

__all__ = ["FORMAT", "FORMAT_VERSION", "SPLIT_DIRS", "segment_paths", "read_tsv", "format_tsv",
           "read_synth_corpus", "read_meta"]

FORMAT = "evalsuite-synthetic-speaker"
FORMAT_VERSION = 1
SPLIT_DIRS = {"train": "trn", "val": "val", "test": "tst"}
_EXT = {"wav": "wav", "bvh": "bvh", "tsv": "tsv", "labels": "csv"}


def segment_paths(root: pathlib.Path, split: str, seg_id: str) -> dict[str, pathlib.Path]:
    base = pathlib.Path(root) / SPLIT_DIRS[split] / "main-agent"
    return {k: base / k / f"{seg_id}.{ext}" for k, ext in _EXT.items()}


def format_tsv(transcript: Transcript) -> str:
    """GENEA TSV: ``start<TAB>end<TAB>word`` per line, seconds with 6 decimals."""
    return "".join(f"{w.start:.6f}\t{w.end:.6f}\t{w.text}\n" for w in transcript.words)


def read_tsv(path: pathlib.Path) -> Transcript:
    words = []
    for n, line in enumerate(pathlib.Path(path).read_text(encoding="utf-8").splitlines(), start=1):
        if not line.strip():
            continue
        parts = line.split("\t")
        if len(parts) != 3:
            raise InputError(f"expected start<TAB>end<TAB>word, got {len(parts)} fields", path=path, line=n)
        try:
            words.append(Word(parts[2], float(parts[0]), float(parts[1])))
        except ValueError:
            raise InputError("start and end must be numbers (seconds)", path=path, line=n) from None
    return Transcript(tuple(words), source=str(path))


def read_meta(root: str | pathlib.Path) -> dict[str, Any]:
    """``corpus.json`` of a synthetic corpus (checked for its format name)."""
    path = pathlib.Path(root) / "corpus.json"
    if not path.is_file():
        raise InputError("no corpus.json: not a synthetic-speaker corpus folder", path=root)
    try:
        meta = json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise InputError(f"not valid JSON ({exc})", path=path) from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        raise InputError(f"expected format {FORMAT!r}", path=path, field="format")
    return meta


def read_synth_corpus(root: str | pathlib.Path) -> Corpus:
    """A synthetic-speaker corpus folder as a :class:`Corpus`: checks that ``corpus.json`` is the speaker's,
    then reads the folder with :func:`evalsuite.corpus.load_corpus` (GENEA 2023 layout) and adds each
    segment's ``motion_seed`` and ``emphasis`` (indices of emphasised words) from ``corpus.json`` to its meta."""
    import dataclasses

    from evalsuite.corpus.readers import load_corpus

    info = read_meta(root)["segments"]
    corpus = load_corpus(root, layout="genea2023")
    return corpus.with_segments([dataclasses.replace(s, meta={**s.meta, "motion_seed": int(info[s.id]["motion_seed"]),
                                                             "emphasis": [int(i) for i in info[s.id]["emphasis"]]})
                                 for s in corpus.segments])
