"""Speech and text features as the reference gesture generators compute them, by recipe name.

>>> from evalsuite import features
>>> x = features.extract("mfcc_kucherenko", "speech.wav", n_frames=motion.n_frames)   # doctest: +SKIP

:func:`extract` runs a registered recipe (:func:`list_recipes`, :func:`get_recipe`) through the content-hash
cache and applies the frame-rate and length rules (:mod:`evalsuite.features.base`). Each recipe is one
module that registers itself; ``docs/features.md`` lists them with what they reproduce and their quirks.
Text features per frame (word ids, Gesticulator's timing features, word embeddings) are in
:mod:`evalsuite.features.text` and :mod:`evalsuite.features.embeddings`.
"""
from __future__ import annotations

from evalsuite.features import demo_recipes, embeddings, logmel, mfcc, prosody, text  # noqa: F401  (registration)
from evalsuite.features.base import Audio, Recipe, get_recipe, list_recipes, load_audio, register_recipe
from evalsuite.features.pipeline import extract

__all__ = ["Audio", "Recipe", "extract", "get_recipe", "list_recipes", "load_audio", "register_recipe"]
