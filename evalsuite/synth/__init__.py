"""The synthetic speaker: espeak-ng speech with exact word timings and motion from a documented procedural
model whose speech-gesture coupling is known (docs/corpus.md § The synthetic speaker).

* :func:`synthesize_corpus` writes a corpus (GENEA 2023 layout + per-frame labels + ``corpus.json``);
* :func:`oracle_motion` runs the same model on any transcript (the *oracle* condition), with the switches
  of :class:`MotionParams` (time offset, beats off, semantic gestures off, amplitude);
* :func:`segment_oracle` reproduces (or re-performs with another seed) one segment of a corpus.
"""
from __future__ import annotations

from evalsuite.synth.corpus import Layout, synthesize_corpus
from evalsuite.synth.grammar import KEYWORD_CLASSES, keyword_class
from evalsuite.synth.layout import read_synth_corpus
from evalsuite.synth.model import FrameLabels, oracle_motion
from evalsuite.synth.oracle import emphasis_from_audio, segment_oracle
from evalsuite.synth.params import KINDS, PHASES, MotionParams
from evalsuite.synth.speech import Voice

__all__ = ["synthesize_corpus", "oracle_motion", "segment_oracle", "emphasis_from_audio", "read_synth_corpus",
           "MotionParams", "Layout", "Voice", "FrameLabels", "KEYWORD_CLASSES", "keyword_class", "PHASES", "KINDS"]
