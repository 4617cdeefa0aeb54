"""``gesture2vec``: the re-implementation of Yazdian, Chen and Lim (IROS 2022) as a trainable plug-in.

Text only, as the paper: the word vectors of the transcript with their timings -> a translation model (BiGRU
encoder, attention GRU decoder) -> one code of a K-vector codebook per 30-frame chunk -> the VQ-DVAE decoder ->
the frame autoencoder's decoder -> joint rotations (3x3 matrices of the GENEA 2020 upper-body joints of the
corpus's skeleton) at 20 fps, written as BVH. ``decoding=retrieval`` is the original repository's decoding
(a random training clip of each predicted code, seeded); every output file's ``meta`` in ``generation.json``
says which decoding made it (``retrieval: true|false``) and lists its codes.

Codebook statistics: the model folder keeps ``code_counts.npy`` (codes of the training chunks) and
:func:`code_usage` reads a generation folder's codes back and compares their histogram with it
(``evalsuite.learned.latent.hellinger`` / ``perplexity``, the NSD / codebook-diversity metrics' formulas).
"""
from __future__ import annotations

import json
import pathlib
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from evalsuite.corpus.types import Corpus, Transcript
from evalsuite.generators.contract import (
    GenerationRequest,
    GenerationResult,
    Generator,
    GeneratorError,
    GeneratorSpec,
    TrainingResult,
)
from evalsuite.generators.datastream import SegmentStore, training_folder
from evalsuite.generators.gesture2vec.info import DEVIATIONS as CORE_DEVIATIONS
from evalsuite.generators.gesture2vec.options import OPTIONS, SIZES
from evalsuite.generators.pose_repr import PoseRepresentation
from evalsuite.generators.reimpl import (
    budget_seconds,
    load_state,
    open_model_folder,
    save_state,
    splits_for_training,
    torch_setup,
    weights_sha256,
    write_json,
)
from evalsuite.generators.scaling import FLOOR_DEVIATION

__all__ = ["Gesture2Vec", "code_usage", "SIZES"]

MY_DEVIATIONS = (
    "Sizes: the cpu preset (default) has 96 recurrent units and one layer in the VQ-DVAE and the translation "
    "model (paper: 200 units, 2 layers); size=paper restores them. Stage epochs are compressed (defaults "
    "DAE 10, VQ-DVAE 15 + decoder 10, translation 60; paper's repository: 20-30, 3000, 250) and a time budget "
    "stops the stages in order.",
    "Codes unused in a VQ-DVAE epoch restart at the encoding of a random training chunk (dead-code reset; "
    "the paper reports no collapse handling), so that small corpora use the codebook.",
    "Translation windows are 4 chunks (120 frames at 20 fps, the repository's sentence_frame_length) cut from "
    "the transcript's word timings (the paper aligned its words with Gentle); in training one starts every "
    "'stride' frames (10), so windows overlap: three times the pairs of non-overlapping windows, which small "
    "corpora need (lexical contrast 0.26 -> 0.62 x natural's on the 30-minute synthetic corpus).",
)


def _word_track(transcript: Transcript | None, embedder: Any) -> list[tuple[np.ndarray, float]]:
    words = list(transcript.words) if transcript is not None else []
    if not words:
        return []
    vectors = embedder.embed([w.text for w in words])
    return [(np.asarray(v, np.float32), float(w.start)) for v, w in zip(vectors, words)]


class Gesture2Vec(Generator):
    spec = GeneratorSpec(
        name="gesture2vec", version="1", kind="re-implementation",
        summary="Re-implementation of Gesture2Vec (not the published system): text -> translation model -> codes "
                "of a VQ-DVAE codebook per 30-frame chunk -> VQ-DVAE decoder -> frame autoencoder decoder -> "
                "joint rotations at 20 fps; text only, as the paper (audio is not read).",
        citation="Yazdian, Chen, Lim (2022). Gesture2Vec: Clustering gestures using representation learning "
                 "methods for co-speech gesture generation. IROS 2022.",
        license="MIT (this re-implementation, written from the paper; the original repository is MIT and is not "
                "used)",
        audio="none", transcript="required", word_timings="required", native_fps=20.0, output="bvh",
        skeleton="the training corpus's skeleton (GENEA 2020 upper-body joints as 3x3 rotation matrices)",
        units="cm", trainable=True, needs_model=True, extra="learned, text",
        config=OPTIONS.config_help(),
        deviations=CORE_DEVIATIONS + MY_DEVIATIONS + (FLOOR_DEVIATION,))

    # -- options -------------------------------------------------------------------------------------------
    def _settings(self) -> dict[str, Any]:
        """The options (:data:`evalsuite.generators.gesture2vec.options.OPTIONS`), parsed and checked."""
        return OPTIONS.parse(self)

    @property
    def stochastic(self) -> bool:
        """Retrieval decoding, or sampling at a positive temperature, as configured (unparsed: never raises)."""
        st = self.config
        return (str(st.get("decoding", OPTIONS["decoding"].default)) == "retrieval"
                or float(st.get("temperature", OPTIONS["temperature"].default)) > 0)

    # -- training ------------------------------------------------------------------------------------------
    def fit(self, corpus: Corpus, out_dir: pathlib.Path, *, seed: int, budget_minutes: float | None = None,
            progress: Callable[[dict[str, Any]], None] | None = None) -> TrainingResult:
        from evalsuite.features.embeddings import get_embedder
        from evalsuite.generators.gesture2vec.data import save_pool, word_rows, word_tracks
        from evalsuite.generators.gesture2vec.net import G2VConfig
        from evalsuite.generators.gesture2vec.training import G2VStages, code_perplexity, train_gesture2vec

        st = self._settings()
        torch_setup(seed, st["threads"])
        train, val = splits_for_training(corpus)
        rep = PoseRepresentation.from_motion(train[0].load_motion(), "rotmat")
        embedder = get_embedder(st["words"])
        data = training_folder("gesture2vec")  # the training split memory-mapped
        folder = pathlib.Path(data.name)
        poses = SegmentStore(folder / "corpus_poses.npy", (rep.encode(s.load_motion()) for s in train))
        words = word_tracks(SegmentStore(folder / "word_tracks.npy", (
            word_rows(_word_track(s.transcript, embedder), embedder.dim) for s in train), np.float64))
        vposes = [rep.encode(s.load_motion()) for s in val]
        vwords = [_word_track(s.transcript, embedder) for s in val]
        config = G2VConfig(pose_dim=rep.dim, text_dim=embedder.dim, chunk=st["chunk"], stride=st["stride"],
                           codebook=st["codebook"], aligned=st["aligned"],
                           conditioned_decoder=st["conditioned_decoder"], **SIZES[st["size"]])
        stages = G2VStages(dae_epochs=st["dae_epochs"], vq_epochs=st["vq_epochs"],
                           vq_decoder_epochs=st["vq_decoder_epochs"], translation_epochs=st["translation_epochs"],
                           learning_rate=st["learning_rate"], translation_learning_rate=st["learning_rate"],
                           batch_size=st["batch_size"], reset_dead_codes=st["reset_dead_codes"],
                           scale_floor=st["scale_floor"], weakened_decoder=st["weakened_decoder"])
        model = train_gesture2vec(poses, words, config, rep.fps, stages, seed=seed, val_poses=vposes,
                                  val_words=vwords, budget_seconds=budget_seconds(budget_minutes), on_epoch=progress,
                                  data_dir=folder)
        rep.save(out_dir)
        shas = {name: save_state(out_dir, f"{name}.pt", net)
                for name, net in (("dae", model.dae), ("vqdvae", model.vq), ("translator", model.translator))}
        np.savez(out_dir / "normalisers.npz", pose_mean=model.pose_mean, pose_scale=model.pose_scale)
        np.save(out_dir / "code_counts.npy", model.code_counts)
        save_pool(out_dir / "retrieval_pool.npz", model.train_chunks)
        model.data.cleanup()
        data.cleanup()
        write_json(out_dir / "settings.json", {**st, "net": config.to_dict(), "fps": rep.fps,
                                               "text_dim": embedder.dim})
        states = {f"{name}.{k}": v for name, net in (("dae", model.dae), ("vqdvae", model.vq),
                                                     ("translator", model.translator))
                  for k, v in net.state_dict().items()}
        meta = {"weights_sha256": weights_sha256(states), "weights_sha256_parts": shas,
                "train_segments": len(train), "val_segments": len(val),
                "code_perplexity": code_perplexity(model.code_counts), "codes_used": int((model.code_counts > 0).sum()),
                "codebook": st["codebook"], "stopped_by_budget": model.stopped}
        return TrainingResult(out_dir, model.history, meta)

    # -- generation ----------------------------------------------------------------------------------------
    def load(self, config: Mapping[str, Any], model_dir: pathlib.Path | None = None) -> None:
        super().load(config, model_dir)
        from evalsuite.features.embeddings import get_embedder
        from evalsuite.generators.gesture2vec.data import open_pool
        from evalsuite.generators.gesture2vec.net import VQDVAE, FrameDAE, G2VConfig, Translator
        from evalsuite.generators.gesture2vec.training import TrainedG2V

        self.saved, self.rep = open_model_folder(model_dir)
        saved = self.saved
        assert model_dir is not None
        c = G2VConfig(**saved["net"])
        nets = {"dae": FrameDAE(c), "vqdvae": VQDVAE(c), "translator": Translator(c)}
        for name, net in nets.items():
            load_state(model_dir, f"{name}.pt", net)
        norms = np.load(model_dir / "normalisers.npz")
        pool = open_pool(model_dir / "retrieval_pool.npz")  # memory-mapped: clips are read when retrieved
        self.model = TrainedG2V(c, float(saved["fps"]), nets["dae"], nets["vqdvae"],  # type: ignore[arg-type]
                                nets["translator"], norms["pose_mean"], norms["pose_scale"],  # type: ignore[arg-type]
                                np.load(model_dir / "code_counts.npy"), [], pool)
        self.embedder = get_embedder(saved["words"])
        # generation options may differ from training's; the model's own settings are the defaults
        self.decoding = OPTIONS.value(self, "decoding")
        self.temperature = OPTIONS.value(self, "temperature")

    def generate(self, request: GenerationRequest) -> GenerationResult:
        from evalsuite.generators.gesture2vec.training import generate_gesture2vec

        if request.transcript is None or not len(request.transcript):
            raise GeneratorError(f"{self.spec.name}, segment {request.segment_id!r}: needs a transcript with word "
                                 f"timings (it reads text only)")
        n = int(round(request.duration * self.rep.fps))
        poses, codes = generate_gesture2vec(self.model, _word_track(request.transcript, self.embedder), n,
                                            seed=request.seed, temperature=self.temperature,
                                            retrieval=self.decoding == "retrieval")
        meta = {"decoding": self.decoding, "retrieval": self.decoding == "retrieval",
                "codes": [int(k) for k in codes], "chunk_frames": self.model.config.chunk}
        return GenerationResult(self.rep.decode(poses), meta)



def code_usage(generation_dir: str | pathlib.Path, model_dir: str | pathlib.Path) -> dict[str, float]:
    """Codebook statistics of a ``gesture2vec`` run: the codes listed in ``generation.json`` (per file meta)
    against the model's training code counts (``code_counts.npy``): ``codebook_hellinger`` (0 = the same
    usage as training), ``codebook_perplexity`` (generated), ``training_perplexity``, ``codes_used``."""
    from evalsuite.learned.latent import hellinger, perplexity

    record = json.loads((pathlib.Path(generation_dir) / "generation.json").read_text(encoding="utf-8"))
    train_counts = np.load(pathlib.Path(model_dir) / "code_counts.npy").astype(np.float64)
    codes = [k for f in record["files"] for k in (f.get("meta") or {}).get("codes", [])]
    if not codes:
        raise GeneratorError("generation.json lists no codes: not a gesture2vec run", field="generation_dir")
    counts = np.bincount(codes, minlength=len(train_counts)).astype(np.float64)
    return {"codebook_hellinger": hellinger(train_counts, counts), "codebook_perplexity": perplexity(counts),
            "training_perplexity": perplexity(train_counts), "codes_used": float((counts > 0).sum())}
