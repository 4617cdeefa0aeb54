"""``aud2pose``, ``aud2motion``, ``aud2repr2pose``: re-implementations of "Moving fast and slow" (Kucherenko et
al., IVA 2019 / IJHCI 2021) as trainable plug-ins.

26 MFCC at 20 fps (``mfcc_kucherenko``) -> three dense layers -> a GRU -> the pose (Aud2Pose, with the velocity
as a second target), the pose sequence (Aud2Motion, causal GRU over 100-frame chunks), or the bottleneck code
of a denoising motion autoencoder learned first and decoded by its decoder (Aud2Repr2Pose). The paper's
post-processing (moving average, 1-euro) applies to the output with ``evalsuite generate --post``.
"""
from __future__ import annotations

import pathlib
from collections.abc import Callable, Mapping
from typing import Any, ClassVar

import numpy as np

from evalsuite.corpus.types import Corpus
from evalsuite.generators.aud2repr2pose.options import OPTIONS, WINDOWED_BATCH
from evalsuite.generators.aud2repr2pose.systems import SYSTEMS
from evalsuite.generators.contract import (
    GenerationRequest,
    GenerationResult,
    Generator,
    GeneratorError,
    GeneratorSpec,
    TrainingResult,
)
from evalsuite.generators.datastream import stream_arrays, training_folder
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
from evalsuite.generators.scaling import FLOOR_DEVIATION
from evalsuite.generators.weight_averaging import EMA_DEVIATION

__all__ = ["Aud2Pose", "Aud2Motion", "Aud2Repr2Pose"]

CITATION = ("Kucherenko, Hasegawa, Kaneko, Henter, Kjellström (2021). Moving fast and slow: analysis of "
            "representations and post-processing in speech-driven automatic gesture generation. IJHCI 37(14); "
            "and Kucherenko et al. (2019). Analyzing input and output representations for speech-driven gesture "
            "generation. IVA 2019.")
DEVIATIONS = ("The speech network runs in the sequence-level form by default (one bidirectional GRU pass per "
              "100-frame chunk instead of one 61-frame window per output frame: ~60x less computation on a CPU); "
              "form=windowed is the paper's.",
              "Layers are 64 units wide by default (paper: 256); the best validation epoch's weights are kept "
              "(early stopping), where the paper trained a fixed number of epochs; validation is the pose error "
              "over whole held-out segments (validate_on=poses), the representation decoded for Aud2Repr2Pose.",
              "Motion: joint rotations (exponential maps) of the GENEA 2020 upper body of the corpus's skeleton by "
              "default, or hip-centred joint positions; the paper used 64 joint positions + velocities of a "
              "Japanese corpus.", FLOOR_DEVIATION, EMA_DEVIATION,
              "Aud2Motion reads each frame's speech features together with those of the 4 frames before it "
              "(past_frames=5: a causal 0.25 s context at the input), where the paper feeds one frame per GRU step; "
              "it lowered the held-out pose error on two synthetic corpora (past_frames=1 is the paper's).")


class _Aud2(Generator):
    system: ClassVar[str]

    def _settings(self) -> dict[str, Any]:
        """The options (:data:`evalsuite.generators.aud2repr2pose.options.OPTIONS`), parsed and checked; the
        windowed form's batches default to the paper's 2056 windows."""
        options = OPTIONS[self.system]
        windowed = options.value(self, "form") == "windowed"
        if windowed and self.system == "aud2motion":
            raise GeneratorError("aud2motion is sequence-level by definition (a causal GRU returning one pose per "
                                 "frame of a chunk); form=windowed would make it a centred-window model that sees "
                                 "the future", field="form")
        st = options.parse(self, {"batch_size": WINDOWED_BATCH} if windowed else None)
        self._check_past_frames(st["past_frames"], windowed)
        return st

    def _check_past_frames(self, k: int, windowed: bool) -> None:
        if k < 1:
            raise GeneratorError(f"{self.spec.name}: option past_frames must be at least 1, got {k}",
                                 field="past_frames")
        if windowed and k > 1:
            raise GeneratorError(f"{self.spec.name}: past_frames applies to the sequence form; the windowed form "
                                 "already reads 30 frames either side", field="past_frames")

    def fit(self, corpus: Corpus, out_dir: pathlib.Path, *, seed: int, budget_minutes: float | None = None,
            progress: Callable[[dict[str, Any]], None] | None = None) -> TrainingResult:
        st = self._settings()
        torch_setup(seed, st["threads"])  # first: a clear message when torch is missing
        from evalsuite.generators.aud2repr2pose.training import train_system

        train, val = splits_for_training(corpus)
        rep = PoseRepresentation.from_motion(train[0].load_motion(), st["representation"])
        recipe = "mfcc_kucherenko"
        prosody = st["features"] == "mfcc+prosody"
        data = training_folder(self.system)  # features memory-mapped, not in memory
        speech, poses, _ = stream_arrays(train, rep, pathlib.Path(data.name), audio_recipe=recipe, words=None,
                                         speech=(lambda a, seg: self._prosody(a.speech, seg.audio, rep.fps))
                                         if prosody else None)
        va = corpus_arrays(val, rep, audio_recipe=recipe, words=None) if val else []
        vspeech = [self._prosody(a.speech, seg.audio, rep.fps) if prosody else a.speech for a, seg in zip(va, val)]
        _, overrides = SYSTEMS[self.system]
        model = train_system(self.system, speech, poses, data_dir=pathlib.Path(data.name),
                             config={**overrides, "form": st["form"], "width": st["width"],
                                     "velocity_target": st["velocity_target"], "past_frames": st["past_frames"]},
                             code_dim=st["code_dim"], dae_epochs=st["dae_epochs"], epochs=st["epochs"],
                             batch_size=st["batch_size"], learning_rate=st["learning_rate"], seed=seed,
                             val_speech=vspeech, val_poses=[a.poses for a in va],
                             budget_seconds=budget_seconds(budget_minutes), patience=st["patience"],
                             scale_floor=st["scale_floor"], lr_schedule=st["lr_schedule"], ema=st["ema"],
                             validate_on=st["validate_on"], dae_velocities=st["dae_inputs"] == "poses+velocities",
                             on_epoch=progress)
        data.cleanup()
        rep.save(out_dir)
        sha = save_state(out_dir, "speech_net.pt", model.speech_net)
        if model.dae is not None:
            save_state(out_dir, "motion_dae.pt", model.dae)
        np.savez(out_dir / "normalisers.npz", speech_mean=model.speech_norm.mean, speech_std=model.speech_norm.std,
                 pose_scale=model.pose_norm.scale, pose_mean=model.pose_norm.mean)
        write_json(out_dir / "settings.json", {**st, "system": self.system, "audio_recipe": recipe,
                                               "net": model.speech_net.config.to_dict(),
                                               "pose_dim": rep.dim})
        return TrainingResult(out_dir, model.history, {"weights_sha256": sha, "train_segments": len(train)})

    @staticmethod
    def _prosody(mfcc: np.ndarray, audio: Any, fps: float) -> np.ndarray:
        from evalsuite.features import extract

        n = len(mfcc)
        extra = np.concatenate([extract("pitch", audio, fps=fps, n_frames=n),
                                extract("energy", audio, fps=fps, n_frames=n)], axis=1)
        return np.concatenate([mfcc, extra], axis=1).astype(np.float32)

    def load(self, config: Mapping[str, Any], model_dir: pathlib.Path | None = None) -> None:
        super().load(config, model_dir)
        torch_setup(0, 1)  # a clear message when torch is missing
        from evalsuite.generators.aud2repr2pose.net import MotionDAE, SpeechNet, SpeechNetConfig
        from evalsuite.generators.aud2repr2pose.training import MaxAbsScaler, Standardiser, TrainedSystem

        saved, rep = open_model_folder(model_dir)
        assert model_dir is not None
        if saved.get("system") != self.system:
            raise GeneratorError(f"this model folder holds a {saved.get('system')} model, not {self.system}",
                                 field="--model")
        self.saved, self.rep = saved, rep
        net = SpeechNet(SpeechNetConfig(**saved["net"]))
        load_state(model_dir, "speech_net.pt", net)
        dae = None
        if (model_dir / "motion_dae.pt").is_file():
            dae = MotionDAE(saved["pose_dim"], saved["code_dim"],
                            velocities=saved.get("dae_inputs") == "poses+velocities")
            load_state(model_dir, "motion_dae.pt", dae)
        norms = np.load(model_dir / "normalisers.npz")
        self.model = TrainedSystem(self.system, net, Standardiser(norms["speech_mean"], norms["speech_std"]),
                                   MaxAbsScaler(norms["pose_mean"], norms["pose_scale"]), dae)

    def generate(self, request: GenerationRequest) -> GenerationResult:
        from evalsuite.generators.aud2repr2pose.training import generate

        arrays = request_arrays(request, self.rep.fps, audio_recipe=self.saved["audio_recipe"], words=None,
                                name=self.spec.name)
        speech = arrays.speech
        if self.saved["features"] == "mfcc+prosody":
            speech = self._prosody(speech, request.audio, self.rep.fps)
        return GenerationResult(self.rep.decode(generate(self.model, speech)))



def _spec(name: str, summary: str) -> GeneratorSpec:
    return GeneratorSpec(name=name, version="1", kind="re-implementation", summary=summary, citation=CITATION,
                         license="MIT (this re-implementation; the original code is Apache-2.0 and is not used)",
                         audio="required", native_fps=20.0, output="any", units="cm", trainable=True,
                         needs_model=True, extra="learned",
                         skeleton="the training corpus's skeleton (GENEA 2020 upper-body joints modelled)",
                         config=OPTIONS[name].config_help(), deviations=DEVIATIONS)


class Aud2Pose(_Aud2):
    system = "aud2pose"
    spec = _spec("aud2pose", "Re-implementation of Aud2Pose (Hasegawa et al. 2018 as in 'Moving fast and slow'; "
                             "not the published system): MFCC windows -> dense x3 -> bidirectional GRU -> pose "
                             "(+ velocity target).")


class Aud2Motion(_Aud2):
    system = "aud2motion"
    spec = _spec("aud2motion", "Re-implementation of Aud2Motion ('Moving fast and slow'; not the published "
                               "system): MFCC sequence -> dense x3 -> causal GRU -> pose per frame.")


class Aud2Repr2Pose(_Aud2):
    system = "aud2repr2pose"
    spec = _spec("aud2repr2pose", "Re-implementation of Aud2Repr2Pose ('Moving fast and slow'; not the published "
                                  "system): a denoising motion autoencoder learned first, MFCC -> its code -> "
                                  "its decoder.")
