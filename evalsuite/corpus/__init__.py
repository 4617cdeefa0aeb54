"""Speech and gesture corpora: segments of (speech audio, transcript with word timings, motion).

The data model is in :mod:`evalsuite.corpus.types`; readers for the layouts users have on disk, the
transcript formats and the synthetic speaker are modules beside it.
"""
from __future__ import annotations

from evalsuite.corpus.types import SPLITS, Corpus, Segment, Stream, Transcript, Word, canonical_split

__all__ = ["SPLITS", "Corpus", "Segment", "Stream", "Transcript", "Word", "canonical_split"]
