"""``manifest.csv``: the private map from blinded stimulus video names to what they show.

Written by ``evalsuite render stimuli`` (:mod:`renderers.stimuli`, all of :data:`COLUMNS`), read by the study
app (:func:`study_app.definition.load_manifest`), which needs :data:`REQUIRED` and reads the optional
``kind``, ``expected``, ``check``, ``motion_segment``, ``block`` and ``duration_s`` (seconds; the server checks
time on a page against it). A hand-made manifest needs only the required ones.
"""
from __future__ import annotations

__all__ = ["COLUMNS", "REQUIRED", "KINDS", "AUDIO_CHECKS", "EMBODIMENT"]

# In the order the renderer writes them.
COLUMNS = ("file", "condition", "segment", "kind", "expected", "sha256", "check", "source_file",
           "motion_segment", "text", "appear_s", "duration_s", "n_frames", "fps", "width", "height",
           "input_hash", "style", "character", "framing", "face")
# How the stimuli show the motion (the render settings' body style, character file name, framing and face), so a
# paper can report the embodiment; the study app shows them on the admin page and in the raw export.
EMBODIMENT = ("style", "character", "framing", "face")
REQUIRED = ("file", "condition", "segment")
# Row kinds: a stimulus of a condition, or an attention-check video (``expected``: the attentive answer).
KINDS = ("stimulus", "attention")
# Attention checks (``check`` column) that only sound reveals: unusable in a muted block.
AUDIO_CHECKS = ("distorted_audio",)
