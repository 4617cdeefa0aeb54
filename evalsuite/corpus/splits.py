"""Seeded train/val/test splits of a corpus, and ``splits.csv`` (``segment,split``) in and out.

``by='speaker'`` keeps speakers disjoint across splits where the corpus has enough speakers (at least one
per split asked for); whole speakers are assigned in a seeded order until each split's share of the total
duration is reached. Otherwise (one speaker, or ``by='segment'``) segments are shuffled with the seed and
cut by duration. The same corpus and seed always give the same splits.
"""
from __future__ import annotations

import csv
import dataclasses
import os
from collections import Counter, defaultdict

import numpy as np

from evalsuite.corpus.types import Corpus, Segment
from evalsuite.errors import InputError

__all__ = ["split_corpus", "write_splits", "read_splits"]


def _weight(s: Segment) -> float:
    return s.duration if s.duration is not None and s.duration > 0 else 1.0


def _assign(groups: list[list[Segment]], val: float, test: float) -> list[str]:
    """Split names for groups taken in order: test first, then val, the rest train, by duration share."""
    total = sum(_weight(s) for g in groups for s in g)
    targets = [("test", test * total), ("val", val * total)]
    names: list[str] = []
    k, acc = 0, 0.0
    for g in groups:
        while k < len(targets) and (targets[k][1] <= 0 or acc >= targets[k][1] - 1e-9):
            k, acc = k + 1, 0.0
        if k >= len(targets):
            names.append("train")
            continue
        names.append(targets[k][0])
        acc += sum(_weight(s) for s in g)
    return names


def split_corpus(corpus: Corpus, val: float = 0.1, test: float = 0.1, seed: int = 0, by: str = "speaker") -> Corpus:
    """The corpus with every segment's ``split`` set to ``train``/``val``/``test`` (seeded); see the module
    docstring. ``corpus.meta['split']`` records the arguments and whether speakers are disjoint."""
    if by not in ("speaker", "segment"):
        raise InputError(f"by must be 'speaker' or 'segment', got {by!r}", field="by")
    for name, frac in (("val", val), ("test", test)):
        if not 0 <= frac < 1:
            raise InputError(f"{name} must be a fraction in [0, 1), got {frac!r}", field=name)
    if val + test >= 1:
        raise InputError(f"val + test must leave something to train on, got {val + test:g}", field="val")
    rng = np.random.default_rng(seed)
    speakers = sorted({s.speaker for s in corpus if s.speaker is not None})
    needed = 1 + (val > 0) + (test > 0)
    disjoint = by == "speaker" and len(speakers) >= needed and all(s.speaker is not None for s in corpus)
    if disjoint:
        by_speaker: dict[str, list[Segment]] = defaultdict(list)
        for s in corpus:
            assert s.speaker is not None
            by_speaker[s.speaker].append(s)
        order = [speakers[i] for i in rng.permutation(len(speakers))]
        groups = [by_speaker[sp] for sp in order]
        names = _assign(groups, val, test)
        # every split asked for gets at least one speaker: a split left empty by the greedy cut takes the last
        # speaker of the split with the most speakers (there is one with two, as speakers >= splits asked for)
        for want in ["train"] + [n for n, f in (("test", test), ("val", val)) if f > 0]:
            if want not in names:
                counts = Counter(names)
                donor = max(counts, key=lambda n: (counts[n], n))
                names[max(i for i, n in enumerate(names) if n == donor)] = want
        split_of = {s.id: n for g, n in zip(groups, names) for s in g}
    else:
        segs = [corpus.segments[i] for i in rng.permutation(len(corpus))]
        names = _assign([[s] for s in segs], val, test)
        split_of = {s.id: n for s, n in zip(segs, names)}
    new = [dataclasses.replace(s, split=split_of[s.id]) for s in corpus]
    meta = dict(corpus.meta)
    meta["split"] = {"val": val, "test": test, "seed": seed, "by": by, "speakers_disjoint": disjoint}
    return dataclasses.replace(corpus, segments=tuple(new), meta=meta)


def write_splits(corpus: Corpus, path: str | os.PathLike[str]) -> None:
    """``splits.csv``: a header ``segment,split`` and one row per segment (in id order)."""
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(["segment", "split"])
        for s in corpus:
            w.writerow([s.id, s.split or ""])


def read_splits(path: str | os.PathLike[str]) -> dict[str, str]:
    """``{segment: split}`` from a ``splits.csv``."""
    with open(path, newline="", encoding="utf-8-sig") as fh:
        rows = list(csv.reader(fh))
    if not rows or [c.strip() for c in rows[0][:2]] != ["segment", "split"]:
        raise InputError("expected a header 'segment,split'", path=path, line=1)
    out = {}
    for n, row in enumerate(rows[1:], start=2):
        if len(row) < 2 or not row[0].strip():
            raise InputError(f"expected 'segment,split', found {','.join(row)!r}", path=path, line=n)
        out[row[0].strip()] = row[1].strip()
    return out
