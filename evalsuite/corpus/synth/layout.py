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

from evalsuite.corpus.types import Corpus, Segment, Stream, Transcript, Word, canonical_split
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
    """A synthetic-speaker corpus folder as a :class:`Corpus` (to be replaced by
    ``evalsuite.corpus.load_corpus``). Segment ``meta`` holds ``motion_seed`` and ``emphasis``."""
    root = pathlib.Path(root)
    meta = read_meta(root)
    segments = []
    for seg_id, info in sorted(meta["segments"].items()):
        split = canonical_split(info["split"]) or "train"
        paths = segment_paths(root, split, seg_id)
        for key in ("wav", "bvh", "tsv"):
            if not paths[key].is_file():
                raise InputError(f"segment {seg_id!r}: missing {key} file", path=paths[key])
        stream = Stream(paths["wav"], read_tsv(paths["tsv"]), paths["bvh"])
        segments.append(Segment(seg_id, stream, float(info["duration"]), meta.get("speaker"), split,
                                labels=paths["labels"] if paths["labels"].is_file() else None,
                                meta={"motion_seed": int(info["motion_seed"]),
                                      "emphasis": [int(i) for i in info["emphasis"]]}))
    return Corpus(root, "genea2023", tuple(segments), meta=meta)
