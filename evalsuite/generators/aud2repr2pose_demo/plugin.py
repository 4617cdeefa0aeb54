"""``aud2repr2pose-demo``: the published Aud2Repr2Pose English demo model as a generator plug-in.

The user names the folder of the demo repository's ``models/`` files with ``--model`` (nothing of them is
shipped or downloaded). Per segment: the demo's features (26 MFCC + 4 Praat prosody at 20 fps,
:mod:`evalsuite.features.aud2repr2pose_demo`), the 61-frame windows, the speech encoder, the decoder, the
original's Savitzky-Golay (9, 3) smoothing: 46 named points in centimetres at 20 fps.
"""
from __future__ import annotations

import pathlib
from collections.abc import Mapping
from typing import Any

import numpy as np

from evalsuite.generators.contract import (
    GenerationRequest,
    GenerationResult,
    Generator,
    GeneratorError,
    GeneratorSpec,
)

__all__ = ["Aud2Repr2PoseDemoGenerator"]

# The 46 point names of the demo's visualiser, in its order (kept here as well so that listing and describing
# the plug-in never import the model module).
_FINGERS = ("Thumb", "Index", "Middle", "Ring", "Pinky")
_POINTS = ("Hips", "Spine", "Spine1", "Spine2", "Spine3", "Neck", "Neck1", "Head",
           "RightShoulder", "RightArm", "RightForeArm", "RightHand",
           *(f"RightHand{f}{i}" for f in _FINGERS for i in (1, 2, 3)),
           "LeftShoulder", "LeftArm", "LeftForeArm", "LeftHand",
           *(f"LeftHand{f}{i}" for f in _FINGERS for i in (1, 2, 3)))


class Aud2Repr2PoseDemoGenerator(Generator):
    spec = GeneratorSpec(
        name="aud2repr2pose-demo", version="1", kind="published model",
        summary="The published Aud2Repr2Pose English demo model (trained on Trinity by the authors), run with "
                "numpy from the original files (Keras HDF5 speech encoder, TensorFlow 1 decoder checkpoint, "
                "max_val.npy, mean_pose.npy): 46 points at 20 fps.",
        citation="Kucherenko, Hasegawa, Kaneko, Henter, Kjellström (2021). Moving fast and slow: analysis of "
                 "representations and post-processing in speech-driven automatic gesture generation. IJHCI.",
        license="Apache-2.0 (the demo repository's code and model files)",
        audio="required", native_fps=20.0, output="positions", joints=_POINTS, units="cm",
        needs_model=True, extra="published, praat",
        config={"dropout_keep_prob": "1.0 (default): the deterministic reference; < 1 leaves the decoder's "
                                     "dropout on as the original does, seeded by the request's seed",
                "drop_tail": "true (default): drop the last N mod 8 frames as the original does (then held)",
                "smooth": "true (default): the original's Savitzky-Golay (9, 3) smoothing"},
        deviations=("Runs in numpy instead of TensorFlow/Keras, with TensorFlow's CPU tanh and batch-norm rsqrt "
                    "(the CPU's rsqrtps estimate + a Newton step): on a CPU of the golden run's family the codes "
                    "equal Keras's bit for bit and the points agree to 3.4e-6 cm; elsewhere float32 rounding "
                    "moves points by up to ~2.5e-4 cm (see tests/test_generators_aud2repr2pose_demo.py).",
                    "Dropout at inference is off by default (the original leaves it on, unseeded); "
                    "dropout_keep_prob=0.8 reproduces the original's behaviour with a seed.",
                    "The frames the original drops at the end (N mod 8) are held from the last decoded frame so "
                    "the output covers the whole speech (noted in generation.json)."))

    def load(self, config: Mapping[str, Any], model_dir: pathlib.Path | None = None) -> None:
        super().load(config, model_dir)
        from evalsuite.generators.aud2repr2pose_demo.model import Aud2Repr2PoseDemo

        assert model_dir is not None
        keep = self.float_option("dropout_keep_prob", 1.0)
        if not 0.0 < keep <= 1.0:
            raise GeneratorError(f"dropout_keep_prob must be in (0, 1], got {keep}", field="dropout_keep_prob")
        self.keep_prob = keep
        self.model = Aud2Repr2PoseDemo.from_folder(model_dir)

    @property
    def stochastic(self) -> bool:
        return bool(getattr(self, "keep_prob", 1.0) < 1.0)

    def generate(self, request: GenerationRequest) -> GenerationResult:
        from evalsuite.features.aud2repr2pose_demo import demo_features, demo_windows
        from evalsuite.generators.aud2repr2pose_demo.model import POINT_NAMES, POINT_PARENTS
        from evalsuite.generators.aud2repr2pose_demo.tf_arithmetic import rsqrt_source
        from evalsuite.motion import Motion

        if request.audio is None:
            raise GeneratorError(f"aud2repr2pose-demo, segment {request.segment_id!r}: needs audio")
        windows = demo_windows(demo_features(request.audio))
        points = self.model(windows, keep_prob=self.keep_prob, seed=request.seed if self.stochastic else None,
                            drop_tail=self.bool_option("drop_tail", True), smooth=self.bool_option("smooth", True))
        n = int(round(request.duration * 20.0))
        held = max(0, n - len(points))
        if held:
            points = np.concatenate([points, np.repeat(points[-1:], held, axis=0)])
        motion = Motion.from_positions(points[:n], POINT_NAMES, 20.0, POINT_PARENTS)
        return GenerationResult(motion, {"feature_frames": len(windows), "held_last_frames": held,
                                         "batch_norm_rsqrt": rsqrt_source()})
