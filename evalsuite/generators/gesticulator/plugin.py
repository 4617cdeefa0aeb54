"""``gesticulator``: the re-implementation of Kucherenko et al. (ICMI 2020) as a trainable plug-in.

Speech per 20-fps frame: Gesticulator's 64-band log-mel (``logmel_gesticulator``) and text (the word vector of
the word spoken, plus the five timing features); a window of 10 past and 20 future frames; FiLM conditioning on
the 3 previous poses; exponential maps of the GENEA 2020 upper-body joints, written as BVH on the corpus's
skeleton. The paper's loss (with a heavier velocity term by default) and teacher-forcing schedule (compressed to
the epochs given); the text features dropped at the input in training (``text_dropout``). Ablations as the
paper's Table 2: ``inputs=audio`` / ``inputs=text``, ``autoregressive=false``, ``film=false``.
"""
from __future__ import annotations

import pathlib
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from evalsuite.corpus.types import Corpus
from evalsuite.generators.contract import (
    GenerationRequest,
    GenerationResult,
    Generator,
    GeneratorSpec,
    TrainingResult,
)
from evalsuite.generators.datastream import stream_arrays, training_folder
from evalsuite.generators.gesticulator.options import OPTIONS, SIZES
from evalsuite.generators.pose_repr import PoseRepresentation
from evalsuite.generators.reimpl import (
    budget_seconds,
    corpus_arrays,
    load_state,
    open_model_folder,
    request_arrays,
    save_state,
    splits_for_training,
    torch_setup,
    write_json,
)

__all__ = ["Gesticulator"]

AUDIO_RECIPE = "logmel_gesticulator"


class Gesticulator(Generator):
    spec = GeneratorSpec(
        name="gesticulator", version="1", kind="re-implementation",
        summary="Re-implementation of Gesticulator (not the published system): log-mel + word vectors and timing "
                "features -> FiLM autoregressive network -> joint rotations at 20 fps, trained on CPU.",
        citation="Kucherenko, Jonell, van Waveren, Henter, Alexanderson, Leite, Kjellström (2020). Gesticulator: "
                 "A framework for semantically-aware speech-driven gesture generation. ICMI 2020.",
        license="MIT (this re-implementation; the original code is GPL-3 and is not used)",
        audio="required", transcript="required", word_timings="estimated", native_fps=20.0, output="bvh",
        skeleton="the training corpus's skeleton (GENEA 2020 upper-body joints modelled)", units="cm",
        trainable=True, needs_model=True, extra="learned, text",
        config=OPTIONS.config_help(),
        deviations=(
            "Text: word vectors from all-MiniLM-L6-v2 (384-d, offline from the text extra) or another local model "
            "instead of BERT-base-cased (768-d) fetched from a hub; by default its context-free vectors (on a "
            "30-minute corpus the contextual ones overfit: pose error 0.75 against 0.70 x mean pose); the five "
            "timing features as the original.",
            "Loss and regularisation for a 30-minute corpus: velocity weight alpha 7 (paper 0.6), the text features "
            "dropped at the input with probability 0.8 in training (not in the paper), dropout 0.1 (paper 0.2), "
            "Adam weight decay 1e-3 (paper none). With the paper's alpha the motion is a low-pass of the speaker's "
            "(wrist velocity power at 2-6 Hz a quarter of natural's) and its wrist speed follows the speech energy "
            "with r 0.34-0.39; with these r 0.53-0.54 at a pose error of 0.54-0.60 x mean pose's (four seeds).",
            "Sizes: the CPU preset has 32-unit frame encodings and 256/128 hidden units (paper: 124, 612/256).",
            "Schedule: the paper's stages (pretraining without autoregression, teacher forcing every 16/8/4 "
            "frames, then free) compressed into the given epochs (90 by default); Adam 1e-3 instead of 1e-4 for short "
            "budgets, decayed to 1e-5 by a cosine over the epochs (the paper: constant); with a constant rate, "
            "trainings of equal validation loss scattered from 0.55 to 0.71 x mean pose's held-out error.",
            "No mirroring augmentation; motion hip-centric with the non-modelled joints held at the first "
            "training frame (as the original's PyMO pipeline)."))

    # -- training ------------------------------------------------------------------------------------------
    def _settings(self) -> dict[str, Any]:
        """The training options (:data:`evalsuite.generators.gesticulator.options.OPTIONS`), parsed."""
        return OPTIONS.parse(self)

    def fit(self, corpus: Corpus, out_dir: pathlib.Path, *, seed: int, budget_minutes: float | None = None,
            progress: Callable[[dict[str, Any]], None] | None = None) -> TrainingResult:
        from dataclasses import replace

        st = self._settings()
        torch = torch_setup(seed, st["threads"])  # first: a clear message when torch is missing
        from evalsuite.generators.gesticulator.net import GesticulatorConfig
        from evalsuite.generators.gesticulator.training import PREDICTED_FRAMES, budgeted_schedule, train_gesticulator

        train, val = splits_for_training(corpus)
        rep = PoseRepresentation.from_motion(train[0].load_motion(), "expmap")
        data = training_folder("gesticulator")  # features memory-mapped, not in memory
        tr_speech, tr_poses, first = stream_arrays(train, rep, pathlib.Path(data.name), audio_recipe=AUDIO_RECIPE,
                                                   words=st["words"])
        va = corpus_arrays(val, rep, audio_recipe=AUDIO_RECIPE, words=st["words"]) if val else []
        audio_dim, text_dim = first.audio.shape[1], first.text.shape[1]  # type: ignore[union-attr]
        config = GesticulatorConfig(audio_dim=audio_dim, text_dim=text_dim, pose_dim=rep.dim,
                                    use_audio="audio" in st["inputs"], use_text="text" in st["inputs"],
                                    autoregressive=st["autoregressive"], film=st["film"], past=st["past"],
                                    future=st["future"], dropout=st["dropout"],
                                    prev_pose_dropout=st["prev_pose_dropout"], film_identity=st["film_identity"],
                                    frame_layers=st["frame_layers"], text_dropout=st["text_dropout"],
                                    **SIZES[st["size"]])
        schedule = replace(budgeted_schedule(st["epochs"]), batch_size=st["batch_size"],
                           learning_rate=st["learning_rate"], lr_schedule=st["lr_schedule"],
                           sequence=st["past"] + PREDICTED_FRAMES + st["future"])
        model = train_gesticulator(tr_speech, tr_poses, config, schedule, data_dir=pathlib.Path(data.name),
                                   seed=seed, val_speech=[a.speech for a in va],
                                   val_poses=[a.poses for a in va], budget_seconds=budget_seconds(budget_minutes),
                                   patience=st["patience"], weight_decay=st["weight_decay"],
                                   scale_floor=st["scale_floor"], velocity_weight=st["velocity_weight"],
                                   ema=st["ema"], on_epoch=progress)
        data.cleanup()
        rep.save(out_dir)
        sha = save_state(out_dir, "gesticulator.pt", model.net)
        np.savez(out_dir / "normalisers.npz", speech_mean=model.speech_norm.mean, speech_std=model.speech_norm.std,
                 pose_mean=model.pose_norm.mean, pose_std=model.pose_norm.std)
        write_json(out_dir / "settings.json", {**st, "net": config.to_dict(), "audio_recipe": AUDIO_RECIPE})
        del torch
        return TrainingResult(out_dir, model.history, {"weights_sha256": sha, "train_segments": len(train),
                                                        "val_segments": len(va)})

    # -- generation ----------------------------------------------------------------------------------------
    def load(self, config: Mapping[str, Any], model_dir: pathlib.Path | None = None) -> None:
        super().load(config, model_dir)
        self.saved, self.rep = open_model_folder(model_dir)
        saved = self.saved
        assert model_dir is not None
        from evalsuite.generators.gesticulator.net import GesticulatorConfig, GesticulatorNet
        from evalsuite.generators.gesticulator.training import Normaliser, TrainedGesticulator

        net = GesticulatorNet(GesticulatorConfig.from_dict(saved["net"]))
        load_state(model_dir, "gesticulator.pt", net)
        norms = np.load(model_dir / "normalisers.npz")
        self.model = TrainedGesticulator(net, Normaliser(norms["speech_mean"], norms["speech_std"]),
                                         Normaliser(norms["pose_mean"], norms["pose_std"]), [])

    def _speech(self, req: GenerationRequest) -> np.ndarray:
        speech = request_arrays(req, self.rep.fps, audio_recipe=self.saved["audio_recipe"], words=self.saved["words"],
                                name=self.spec.name).speech
        if OPTIONS.value(self, "zero_audio"):  # the training mean: zero after standardisation
            a = int(self.saved["net"]["audio_dim"])
            speech[:, :a] = self.model.speech_norm.mean[:a]
        return speech

    def generate_batch(self, requests: Sequence[GenerationRequest]) -> list[GenerationResult]:
        from evalsuite.generators.gesticulator.training import generate_poses

        poses = generate_poses(self.model, [self._speech(r) for r in requests], initial_pose=self.model.pose_norm.mean)
        return [GenerationResult(self.rep.decode(p)) for p in poses]

    def generate(self, request: GenerationRequest) -> GenerationResult:
        return self.generate_batch([request])[0]
