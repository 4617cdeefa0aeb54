"""``oracle``: the synthetic speaker's own procedural model run on each segment's speech.

With another seed than the corpus's it is another performance of the same speech by the same "speaker": the
upper bound any generator can reach on a synthetic corpus. Its switches make the graded conditions of the
known-truth benchmark: ``offset_s`` (speech-gesture time offset), ``beats=false``, ``semantic=false``,
``amplitude`` (scale of every gesture). ``same_seed=true`` reproduces the corpus's motion exactly.
Needs the corpus (``--corpus``; the command passes it as the option ``corpus``) written by
``evalsuite corpus synth``: the model's parameters, each segment's emphasis and motion seed are in its
``corpus.json``.
"""
from __future__ import annotations

import pathlib
from collections.abc import Mapping
from typing import Any

from evalsuite.generators.contract import (
    GenerationRequest,
    GenerationResult,
    Generator,
    GeneratorError,
    GeneratorSpec,
)

__all__ = ["Oracle"]

SWITCHES = ("offset_s", "beats", "semantic", "amplitude")


class Oracle(Generator):
    spec = GeneratorSpec(
        name="oracle", version="1", kind="condition", stochastic=True, transcript="required",
        word_timings="required", native_fps=30.0, output="bvh", units="cm",
        summary="The synthetic speaker's procedural model on each segment's transcript and emphasis: another "
                "performance of the same speech (the upper bound of a generator), with graded switches.",
        config={"corpus": "the synthetic corpus folder (set by --corpus)",
                "offset_s": "delay every speech-driven event by this many seconds (default 0)",
                "beats": "true (default) / false: beat gestures, batons and nods on or off",
                "semantic": "true (default) / false: keyword gestures and head shakes on or off",
                "amplitude": "scale of every gesture's excursion (default 1)",
                "same_seed": "true: the corpus's own motion seed (reproduces the natural motion exactly)"})

    def load(self, config: Mapping[str, Any], model_dir: pathlib.Path | None = None) -> None:
        super().load(config, model_dir)
        from evalsuite.corpus import load_corpus
        from evalsuite.synth.params import MotionParams

        root = self.option("corpus")
        if not root:
            raise GeneratorError("oracle needs the synthetic corpus: give --corpus DIR", field="corpus")
        self.corpus = load_corpus(root)
        model = (self.corpus.meta.get("corpus_json") or self.corpus.meta).get("model")
        if not isinstance(model, dict) or "params" not in model:
            raise GeneratorError(f"{root} is not a synthetic-speaker corpus (its corpus.json has no model "
                                 "parameters); the oracle exists only for `evalsuite corpus synth` corpora",
                                 field="corpus")
        changes = {k: self.config[k] for k in SWITCHES if k in self.config}
        for k in ("beats", "semantic"):
            if k in changes:
                changes[k] = bool(changes[k])
        for k in ("offset_s", "amplitude"):
            if k in changes:
                changes[k] = float(changes[k])
        self.params = MotionParams.from_dict(model["params"]).replace(**changes)

    def generate(self, request: GenerationRequest) -> GenerationResult:
        from evalsuite.synth.oracle import segment_oracle

        seed = None if self.bool_option("same_seed", False) else request.seed
        try:
            motion, _ = segment_oracle(self.corpus, request.segment_id, seed=seed, params=self.params)
        except KeyError:
            raise GeneratorError(f"oracle: segment {request.segment_id!r} is not in the synthetic corpus "
                                 f"{self.option('corpus')}") from None
        return GenerationResult(motion, {"switches": {k: getattr(self.params, k) for k in SWITCHES}})

    @property
    def stochastic(self) -> bool:
        return not self.bool_option("same_seed", False)
