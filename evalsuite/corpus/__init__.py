"""Speech and gesture corpora: segments of (speech audio, transcript with word timings, motion).

The data model is in :mod:`evalsuite.corpus.types`; transcript formats in
:mod:`evalsuite.corpus.transcripts`, layout readers in :mod:`evalsuite.corpus.readers`, seeded splits in
:mod:`evalsuite.corpus.splits`. The synthetic speaker, which writes corpora, is :mod:`evalsuite.synth`.
"""
from __future__ import annotations

from evalsuite.corpus.readers import LAYOUTS, detect_layout, load_corpus, register_layout
from evalsuite.corpus.splits import read_splits, split_corpus, write_splits
from evalsuite.corpus.transcripts import read_transcript, write_transcript
from evalsuite.corpus.types import SPLITS, Corpus, Segment, Stream, Transcript, Word, canonical_split

__all__ = ["SPLITS", "Corpus", "Segment", "Stream", "Transcript", "Word", "canonical_split",
           "read_transcript", "write_transcript", "load_corpus", "detect_layout", "register_layout", "LAYOUTS",
           "split_corpus", "write_splits", "read_splits"]
