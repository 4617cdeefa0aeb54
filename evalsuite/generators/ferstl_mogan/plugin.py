"""``ferstl-mogan``: the multi-objective adversarial model of Ferstl, Neff and McDonnell (MIG 2019),
re-implemented from the paper (no code was published), as a trainable plug-in.

26 MFCC + F0 at 20 fps (``mfcc_f0_ferstl``) and seeded noise -> GRU generator -> hip-centred positions of the
GENEA 2020 upper-body joints of the corpus's skeleton (a positions motion, ``.npz``). Pre-trained with MSE, then
trained against the paper's four discriminators (phase structure, motion realism, minibatch, displacement;
weights 2:4:4:1, RMSprop). The phase classifier learns from the corpus's per-frame phase labels (the synthetic
speaker writes them) or, without labels, from :func:`evalsuite.generators.ferstl_mogan.phases.heuristic_phases`;
its weighted F1 on the validation split is in ``model.json`` (``phase_classifier_f1``). Ablations as the
paper's Figure 1: ``ablation=no_phase|no_realism|no_minibatch|no_displacement|mse_only``.
"""
from __future__ import annotations

import pathlib
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from evalsuite.corpus.types import Corpus, Segment
from evalsuite.generators.contract import (
    GenerationRequest,
    GenerationResult,
    Generator,
    GeneratorError,
    GeneratorSpec,
    TrainingResult,
)
from evalsuite.generators.datastream import SegmentStore, training_folder
from evalsuite.generators.ferstl_mogan.options import ABLATIONS, OPTIONS
from evalsuite.generators.joint_presets import ARM_JOINTS, WRIST_JOINTS
from evalsuite.generators.pose_repr import PoseRepresentation
from evalsuite.generators.reimpl import (
    budget_seconds,
    load_state,
    open_model_folder,
    request_arrays,
    save_state,
    speech_features,
    splits_for_training,
    torch_setup,
    write_json,
)
from evalsuite.generators.scaling import FLOOR_DEVIATION

__all__ = ["FerstlMogan", "ABLATIONS"]

AUDIO_RECIPE = "mfcc_f0_ferstl"
CORE_DEVIATIONS = (  # the core's (net.DEVIATIONS imports torch; a test checks they agree)
    "Seeded noise channels are appended to the generator's speech input so that one model gives k different "
    "samples per segment (the paper's generator reads speech only).",
    "The phase-structure discriminator reads the phase classifier's class probabilities rather than hard labels, "
    "so that its gradient reaches the generator.",
    "Phase labels for training the classifier come from the synthetic speaker's per-frame labels or a documented "
    "heuristic labeller (wrist speed and acceleration), not from the authors' 3.8 h of hand annotation.",
    "Positions of the corpus skeleton's upper-body joints instead of the paper's 21 mocap joints; the MFCC/F0 "
    "come from evalsuite's ferstl_mfcc26_f0 recipe instead of openSMILE; sizes are options.",
)
MY_DEVIATIONS = (
    "Sizes: width 128 and discriminators of 64 units by default (paper: 256); stages compressed (classifier 30 "
    "epochs, MSE pre-training 30 epochs, 400 adversarial steps by default) and a time budget stops them in order.",
    "The MSE-only ablation is the MSE pre-trained generator (no adversarial stage), as the paper's baseline. Its "
    "30 epochs stop before the held-out MSE has converged (on a 30-minute synthetic corpus 0.207, against 0.17-0.19 "
    "from epoch 50 on; the training history logs it as val_mse).",
    "No finger-distance penalty (the paper's eq. 5): the modelled joints, the GENEA 2020 upper body, have no "
    "finger markers.",
)


class FerstlMogan(Generator):
    spec = GeneratorSpec(
        name="ferstl-mogan", version="1", kind="re-implementation",
        summary="Re-implementation of Ferstl, Neff, McDonnell's multi-objective adversarial gesture model (no code "
                "was published): 26 MFCC + F0 and seeded noise -> GRU -> hip-centred joint positions at 20 fps, "
                "MSE pre-training then phase / realism / minibatch / displacement discriminators.",
        citation="Ferstl, Neff, McDonnell (2019). Multi-objective adversarial gesture generation. MIG 2019.",
        license="MIT (this re-implementation, written from the paper)",
        audio="required", transcript="none", word_timings="none", native_fps=20.0, output="positions",
        skeleton="the training corpus's skeleton (GENEA 2020 upper-body joints, hip-centred positions)",
        units="cm", stochastic=True, trainable=True, needs_model=True, extra="learned",
        config=OPTIONS.config_help(),
        deviations=CORE_DEVIATIONS + MY_DEVIATIONS + (FLOOR_DEVIATION,))

    def _settings(self) -> dict[str, Any]:
        """The options (:data:`evalsuite.generators.ferstl_mogan.options.OPTIONS`), parsed."""
        return OPTIONS.parse(self)

    # -- training ------------------------------------------------------------------------------------------
    def _arrays(self, segs: Sequence[Segment], rep: PoseRepresentation, use_corpus_labels: bool,
                folder: pathlib.Path | None = None):
        """Speech features, positions and phase classes per segment: lists, or with ``folder`` three
        memory-mapped stores written one segment at a time (phases as one column)."""
        from evalsuite.generators.ferstl_mogan.phases import corpus_phases, heuristic_phases, to_classes

        speech: Any = [] if folder is None else SegmentStore(folder / "speech.npy")
        poses: Any = [] if folder is None else SegmentStore(folder / "positions.npy")
        phases: Any = [] if folder is None else SegmentStore(folder / "phases.npy", dtype=np.int64)
        wrists = [rep.joints.index(j) for j in WRIST_JOINTS if j in rep.joints]
        for s in segs:
            motion = s.load_motion()
            pos = rep.encode(motion)
            n = len(pos)
            speech.append(speech_features(s.audio, AUDIO_RECIPE, rep.fps, n))
            poses.append(pos)
            if use_corpus_labels:
                assert s.labels is not None
                labels = corpus_phases(s.labels, motion.fps, rep.fps, n)
            else:
                labels = heuristic_phases(pos.reshape(n, -1, 3)[:, wrists], rep.fps)
            classes = to_classes(labels)
            phases.append(classes if folder is None else np.asarray(classes, np.int64).reshape(n, 1))
        if folder is not None:
            return speech.finish(), poses.finish(), phases.finish()
        return speech, poses, phases

    def fit(self, corpus: Corpus, out_dir: pathlib.Path, *, seed: int, budget_minutes: float | None = None,
            progress: Callable[[dict[str, Any]], None] | None = None) -> TrainingResult:
        from evalsuite.generators.ferstl_mogan.net import MoganConfig
        from evalsuite.generators.ferstl_mogan.training import MoganStages, train_mogan

        st = self._settings()
        torch_setup(seed, st["threads"])
        train, val = splits_for_training(corpus)
        rep = PoseRepresentation.from_motion(train[0].load_motion(), "positions")
        if not any(j in rep.joints for j in WRIST_JOINTS):
            raise GeneratorError(f"ferstl-mogan needs a wrist ({'/'.join(WRIST_JOINTS)}) among the modelled joints")
        source = "corpus" if st["phase_labels"] == "corpus" and all(s.labels for s in (*train, *val)) else "heuristic"
        data = training_folder("ferstl-mogan")  # features memory-mapped, not in memory
        speech, poses, phases = self._arrays(train, rep, source == "corpus", pathlib.Path(data.name))
        held = val if val else train
        vspeech, vposes, vphases = self._arrays(held, rep, source == "corpus")
        arm = [3 * rep.joints.index(j) + k for j in ARM_JOINTS if j in rep.joints for k in range(3)]
        config = MoganConfig(speech_dim=speech.width, pose_dim=rep.dim, arm_dim=len(arm),
                             noise_dim=st["noise_dim"], width=st["width"],
                             classifier_width=st["discriminator_width"],
                             discriminator_width=st["discriminator_width"])
        stages = MoganStages(classifier_epochs=st["classifier_epochs"], pretrain_epochs=st["pretrain_epochs"],
                             adversarial_steps=st["adversarial_steps"], batch_size=st["batch_size"],
                             realism_pretrain_steps=st["realism_pretrain_steps"],
                             phase_pretrain_tries=st["phase_pretrain_tries"],
                             learning_rate=st["learning_rate"],
                             adversarial_learning_rate=st["adversarial_learning_rate"],
                             discriminator_learning_rate=st["discriminator_learning_rate"],
                             discriminators=ABLATIONS[st["ablation"]], scale_floor=st["scale_floor"])
        model = train_mogan(speech, poses, phases, arm, config, stages, seed=seed, val=(vspeech, vposes, vphases),
                            budget_seconds=budget_seconds(budget_minutes), on_step=progress,
                            data_dir=pathlib.Path(data.name))
        data.cleanup()
        rep.save(out_dir)
        sha = save_state(out_dir, "generator.pt", model.generator)
        save_state(out_dir, "phase_classifier.pt", model.classifier)
        np.savez(out_dir / "normalisers.npz", speech_mean=model.speech_mean, speech_std=model.speech_std,
                 pose_mean=model.pose_mean, pose_std=model.pose_std, arm_columns=model.arm_columns)
        write_json(out_dir / "settings.json", {**st, "net": config.to_dict(), "audio_recipe": AUDIO_RECIPE})
        meta = {"weights_sha256": sha, "phase_classifier_f1": model.classifier_f1,
                "phase_classifier_f1_on": "val" if val else "train (no val split)", "phase_labels_source": source,
                "train_segments": len(train), "val_segments": len(val), "stopped_by_budget": model.stopped}
        return TrainingResult(out_dir, model.history, meta)

    # -- generation ----------------------------------------------------------------------------------------
    def load(self, config: Mapping[str, Any], model_dir: pathlib.Path | None = None) -> None:
        super().load(config, model_dir)
        from evalsuite.generators.ferstl_mogan.net import Generator as GeneratorNet
        from evalsuite.generators.ferstl_mogan.net import MoganConfig, PhaseClassifier
        from evalsuite.generators.ferstl_mogan.training import TrainedMogan

        self.saved, self.rep = open_model_folder(model_dir)
        saved = self.saved
        assert model_dir is not None
        c = MoganConfig(**saved["net"])
        gen, clf = GeneratorNet(c), PhaseClassifier(c)
        load_state(model_dir, "generator.pt", gen)
        load_state(model_dir, "phase_classifier.pt", clf)
        n = np.load(model_dir / "normalisers.npz")
        self.model = TrainedMogan(c, gen, clf, n["speech_mean"], n["speech_std"], n["pose_mean"], n["pose_std"],
                                  n["arm_columns"], float("nan"))

    def generate(self, request: GenerationRequest) -> GenerationResult:
        from evalsuite.generators.ferstl_mogan.training import generate_mogan

        speech = request_arrays(request, self.rep.fps, audio_recipe=AUDIO_RECIPE, words=None,
                                name=self.spec.name).speech
        poses = generate_mogan(self.model, speech, seed=request.seed)
        return GenerationResult(self.rep.decode(poses), {"ablation": self.saved["ablation"]})
