"""Gesture generators as plug-ins: the contract, discovery, the runner, built-in conditions, adapters.

A plug-in subclasses :class:`Generator` and declares a :class:`GeneratorSpec`; see ``docs/generators.md``.
Importing this package is cheap: no torch, no plug-in's heavy modules.
"""
from __future__ import annotations

from evalsuite.generators.contract import (
    GenerationRequest,
    GenerationResult,
    Generator,
    GeneratorError,
    GeneratorSpec,
    TrainingResult,
)
from evalsuite.generators.registry import find_generator, list_generators

__all__ = ["Generator", "GeneratorSpec", "GenerationRequest", "GenerationResult", "GeneratorError",
           "TrainingResult", "find_generator", "list_generators"]
