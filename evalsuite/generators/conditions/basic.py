"""``natural``, ``mean_pose`` and ``precomputed``: the conditions every study has."""
from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from evalsuite.generators.conditions.smplx_ops import fit_smplx, mean_pose_smplx, smplx_source
from evalsuite.generators.conditions.source import OF_OPTION, fit_to_request, folder_files, source_motion, source_path
from evalsuite.generators.contract import (
    GenerationRequest,
    GenerationResult,
    Generator,
    GeneratorError,
    GeneratorSpec,
)
from evalsuite.hashing import file_sha256
from evalsuite.motion import Motion
from evalsuite.motion.io import list_motion_files, load_motion
from evalsuite.motion.joint_rotations import rotation_joints
from evalsuite.motion.smplx import SmplxData, is_smplx_npz, read_smplx

__all__ = ["Natural", "MeanPose", "Precomputed", "mean_pose_of"]


class Natural(Generator):
    """The ground truth: the corpus segment's own motion, at the requested fps and length."""

    spec = GeneratorSpec(
        name="natural", version="1", kind="condition", output="any",
        summary="Ground truth: each segment's recorded motion (resampled to the requested fps, cropped to the "
                "speech's duration; a motion shorter than the speech holds its last frame).")

    def generate(self, request: GenerationRequest) -> GenerationResult:
        data = smplx_source(source_path("natural", request))
        if data is not None:  # SMPL-X stays SMPL-X, every key as recorded
            return GenerationResult(None, smplx=fit_smplx(data, request))
        return GenerationResult(fit_to_request(source_motion("natural", request), request))


def mean_pose_of(motions: Sequence[Motion]) -> Motion:
    """One frame: the mean pose of ``motions`` (all on one skeleton). Joint rotations are averaged as
    rotations (scipy ``Rotation.mean``, the chordal L2 mean of the quaternions), position channels and
    positions arithmetically."""
    first = motions[0]
    if first.is_hierarchical:
        for m in motions[1:]:
            if not m.is_hierarchical or m.skeleton.channels != first.skeleton.channels:
                raise GeneratorError(f"mean_pose needs one skeleton; {m.source or m.name} differs from "
                                     f"{first.source or first.name}")
        values = np.concatenate([m.values for m in motions])
        mean = values.mean(axis=0)
        for _, cols, axes in rotation_joints(first):
            mean[cols] = Rotation.from_euler(axes.upper(), values[:, cols], degrees=True).mean().as_euler(
                axes.upper(), degrees=True)
        return first.with_values(mean[None, :])
    pos = np.concatenate([m.positions() for m in motions])
    return first.with_positions(pos.mean(axis=0)[None])


class MeanPose(Generator):
    """The mean pose, held still: the floor every generator must beat."""

    spec = GeneratorSpec(
        name="mean_pose", version="1", kind="condition", output="any",
        summary="The mean pose of the source motion held for the whole segment (zero velocity). The mean is over "
                "the folder given by 'from' (e.g. the training split's motion) or else over the segments being "
                "generated; on SMPL-X the per-joint rotation mean of the axis-angle, written as SMPL-X.",
        config={**OF_OPTION, "from": "a folder of motion files to average (default: the source motion of the "
                                     "segments being generated)"})
    batch_only = True

    def generate(self, request: GenerationRequest) -> GenerationResult:
        return self.generate_batch([request])[0]

    def generate_batch(self, requests: Sequence[GenerationRequest]) -> list[GenerationResult]:
        src = self.option("from")
        paths = list(folder_files(src).values()) if src else [source_path(self.option("of"), r) for r in requests]
        if not paths:
            raise GeneratorError(f"no motion files in {src}", field="from")
        if all(is_smplx_npz(p) for p in paths):
            return self._smplx(requests, [read_smplx(p) for p in paths])
        motions = [load_motion(p) for p in paths]
        mean = mean_pose_of(motions)
        out = []
        for r in requests:
            idx = np.zeros(r.n_frames, dtype=np.int64)
            m = mean.with_values(mean.values[idx], fps=r.fps) if mean.is_hierarchical else \
                mean.with_positions(mean.positions()[idx], fps=r.fps)
            out.append(GenerationResult(m, {"averaged_files": len(motions)}))
        return out

    def _smplx(self, requests: Sequence[GenerationRequest], items: list[SmplxData]) -> list[GenerationResult]:
        """SMPL-X: the per-joint rotation mean (and mean trans, expressions) held, with each segment's own keys."""
        pose, trans, expr = mean_pose_smplx(items)
        out = []
        for r in requests:
            try:
                own = smplx_source(source_path(self.option("of"), r)) or items[0]
            except GeneratorError:
                own = items[0]
            base = fit_smplx(own, r)
            n = base.n_frames
            keep = base.expressions is not None and expr is not None and base.expressions.shape[1] == expr.size
            data = dataclasses.replace(base, poses=np.repeat(pose[None], n, axis=0), trans=np.repeat(trans[None], n, 0),
                                       expressions=np.repeat(expr[None], n, 0) if keep and expr is not None
                                       else base.expressions)
            out.append(GenerationResult(None, {"averaged_files": len(items)}, smplx=data))
        return out


class Precomputed(Generator):
    """Motion someone else made: a folder of BVH/positions files keyed by segment (e.g. released challenge
    submissions), checked by the same rules as every generator and hashed in the provenance."""

    spec = GeneratorSpec(
        name="precomputed", version="1", kind="condition", stochastic=True, output="any",
        summary="A folder of motion files named <segment>.bvh|.npz (or <segment>_<k>.* for sample k), e.g. the "
                "released GENEA submissions; each file's sha256 is recorded.",
        config={"dir": "the folder of motion files (required)"})

    def load(self, config: Mapping[str, Any], model_dir: Any = None) -> None:
        super().load(config, model_dir)
        if not self.option("dir"):
            raise GeneratorError("precomputed needs the option dir (a folder of motion files)", field="dir")
        self.files = list_motion_files(self.option("dir"))

    def generate(self, request: GenerationRequest) -> GenerationResult:
        for stem in (f"{request.segment_id}_{request.sample}", request.segment_id):
            if stem in self.files:
                path = self.files[stem]
                return GenerationResult(load_motion(path), {"source_file": str(path),
                                                            "source_sha256": file_sha256(path)})
        raise GeneratorError(f"no file for segment {request.segment_id!r} in {self.option('dir')} "
                             f"(expected {request.segment_id}.bvh/.npz or {request.segment_id}_{request.sample}.*)")
