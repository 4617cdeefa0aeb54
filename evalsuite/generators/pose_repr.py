"""The pose representations the re-implemented generators learn, and the way back to a motion on the corpus's
skeleton.

* ``expmap`` (Gesticulator, GENEA 2020 BA, Gesture2Vec): exponential maps (rotation vectors, radians) of the
  modelled joints' local rotations, ``(T, 3J)``. Decoding writes them into a template: the corpus's skeleton
  with every other channel held at the first training frame (as the original PyMO pipelines hold the joints
  they do not model) and the root at the template's position (hip-centric, as the originals).
* ``rotmat`` (Gesture2Vec): the same rotations as flattened 3x3 matrices ``(T, 9J)``; decoding projects each
  onto the nearest rotation (scipy's ``Rotation.from_matrix``) first.
* ``positions`` (Aud2Repr2Pose IVA'19, Ferstl et al.): world positions of the modelled joints relative to the
  root joint, ``(T, 3J)``, in the corpus's units; decoded as a positions motion on the corpus's **whole**
  skeleton (every joint of the template, root included, with its parents), so that it scores against the
  corpus's natural motion with no joint filter: the modelled joints at their generated positions plus the
  template's root position (hip-centric, as the paper's second study), the root at the template's, and every
  other joint carried rigidly by its nearest modelled ancestor (the template's offset from that ancestor).

The representation resamples to its own frame rate (20 fps, as all four papers) on the way in. A model folder
keeps it as ``representation.json`` plus ``template.bvh`` (one frame).

Which joints are modelled: the ``joints`` argument, else the ones :func:`modelled_joints` set for the training
in progress (``evalsuite train --joints``), else the first preset of :mod:`evalsuite.generators.joint_presets`
that the skeleton has. Names given explicitly must all be in the skeleton; a preset's absent members are left out.
"""
from __future__ import annotations

import contextlib
import contextvars
import json
import pathlib
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from evalsuite.errors import InputError
from evalsuite.motion import Motion
from evalsuite.motion.io import load_motion, save_motion
from evalsuite.motion.joint_rotations import rotation_joints, with_rotation_vectors
from evalsuite.motion.ops import resample

__all__ = ["PoseRepresentation", "KINDS", "MODEL_FPS", "modelled_joints", "as_smplx_result"]

KINDS = ("expmap", "rotmat", "positions")
MODEL_FPS = 20.0   # the frame rate of all four seed papers' models

# (names, given explicitly) of the joints to model in the training in progress; None: the default preset
_JOINTS: contextvars.ContextVar[tuple[list[str], bool] | None] = contextvars.ContextVar("modelled_joints",
                                                                                        default=None)


@contextlib.contextmanager
def modelled_joints(value: str | Sequence[str] | None) -> Iterator[list[str] | None]:
    """Within the block, representations made by :meth:`PoseRepresentation.from_motion` without ``joints``
    model these (a preset of :mod:`evalsuite.generators.joint_presets` or joint names); None: the default."""
    from evalsuite.generators.joint_presets import JOINT_PRESETS, resolve_joint_option

    names = resolve_joint_option(value)
    token = _JOINTS.set(None if names is None else (names, not (isinstance(value, str) and value in JOINT_PRESETS)))
    try:
        yield names
    finally:
        _JOINTS.reset(token)


@dataclass
class PoseRepresentation:
    kind: str
    joints: list[str]
    fps: float
    template: Motion      # one frame of the corpus's skeleton (hierarchical)

    @classmethod
    def from_motion(cls, motion: Motion, kind: str = "expmap", joints: list[str] | None = None,
                    fps: float = MODEL_FPS) -> PoseRepresentation:
        """A representation of the joints (default: the module doc's) of the motion's skeleton; its first frame
        is the template."""
        if kind not in KINDS:
            raise InputError(f"unknown pose representation {kind!r}; expected one of {', '.join(KINDS)}")
        if not motion.is_hierarchical:
            raise InputError("the re-implemented generators learn from BVH motion (joint rotations); this motion "
                             "holds positions only", path=motion.source)
        from evalsuite.generators.joint_presets import default_joints

        rotating = [motion.joint_names[j] for j, _, _ in rotation_joints(motion)]
        explicit = joints is not None
        if joints is None and _JOINTS.get() is not None:
            joints, explicit = _JOINTS.get()  # type: ignore[misc]
        wanted = list(joints) if joints is not None else default_joints(rotating)
        if explicit:
            missing = [j for j in wanted if j not in rotating]
            if missing:
                raise InputError(f"--joints: the skeleton has no joint(s) {', '.join(missing)} with rotation "
                                 f"channels", path=motion.source, field="--joints")
        chosen = [j for j in wanted if j in rotating]
        if len(chosen) < 3:
            raise InputError(f"the skeleton has too few of the joints {', '.join(wanted[:6])}… with rotation "
                             f"channels ({len(chosen)}); name the joints to model with --joints PRESET|names "
                             f"(docs/generators.md)", path=motion.source, field="--joints")
        return cls(kind, chosen, float(fps), motion.with_values(motion.values[:1].copy()))

    # -- encoding ----------------------------------------------------------------------------------------
    @property
    def dim(self) -> int:
        return (9 if self.kind == "rotmat" else 3) * len(self.joints)

    def _rows(self, motion: Motion) -> list[list[int]]:
        cols = {motion.joint_names[j]: c for j, c, _ in rotation_joints(motion)}
        missing = [j for j in self.joints if j not in cols]
        if missing:
            raise InputError(f"the motion lacks the modelled joint(s) {', '.join(missing)}", path=motion.source)
        return [cols[j] for j in self.joints]

    def encode(self, motion: Motion) -> np.ndarray:
        """``(T, 3J)`` float32 at :attr:`fps` (the motion is resampled first when its rate differs)."""
        m = resample(motion, self.fps)
        if self.kind == "positions":
            idx = [m.joint_index(j) for j in self.joints]
            root = m.skeleton.roots[0]
            pos = m.positions()
            rel = pos[:, idx] - pos[:, root:root + 1]
            return rel.reshape(len(rel), -1).astype(np.float32)
        from scipy.spatial.transform import Rotation

        axes = {m.joint_names[j]: a for j, _, a in rotation_joints(m)}
        rots = [Rotation.from_euler(axes[j].upper(), m.values[:, cols], degrees=True)
                for j, cols in zip(self.joints, self._rows(m))]
        out = [r.as_matrix().reshape(len(m.values), 9) if self.kind == "rotmat" else r.as_rotvec() for r in rots]
        return np.concatenate(out, axis=1).astype(np.float32)

    def decode(self, data: np.ndarray) -> Motion:
        """``(T, 3J)`` at :attr:`fps` -> a motion (BVH on the template for ``expmap``, positions otherwise)."""
        x = np.asarray(data, dtype=np.float64)
        if x.ndim != 2 or x.shape[1] != self.dim:
            raise InputError(f"poses of shape {x.shape} do not fit this representation ({self.dim} values per frame)")
        t = self.template
        if self.kind == "positions":
            return self._decode_positions(x)
        if self.kind == "rotmat":
            from scipy.spatial.transform import Rotation

            x = Rotation.from_matrix(x.reshape(-1, 3, 3)).as_rotvec().reshape(len(x), -1)
        base = np.repeat(t.values[:1], len(x), axis=0)
        full = t.with_values(base, fps=self.fps)
        from evalsuite.motion.joint_rotations import rotation_vectors

        rv = rotation_vectors(full)
        order = [t.joint_names[j] for j, _, _ in rotation_joints(t)]
        for k, j in enumerate(self.joints):
            rv[:, order.index(j)] = x[:, 3 * k:3 * k + 3]
        return with_rotation_vectors(full, rv)

    def _decode_positions(self, x: np.ndarray) -> Motion:
        """``(T, 3J)`` root-relative positions -> a positions motion of every joint of the template."""
        t = self.template
        rest = t.positions()[0]                                  # (J_all, 3)
        root = int(t.skeleton.roots[0])
        parents = [int(p) for p in t.skeleton.parents]
        out = np.empty((len(x), len(t.joint_names), 3))
        modelled = {t.joint_index(j): k for k, j in enumerate(self.joints)}
        gen = x.reshape(len(x), -1, 3) + rest[root]
        for j in range(len(t.joint_names)):                      # parents come before their children
            if j in modelled:
                out[:, j] = gen[:, modelled[j]]
                continue
            a = parents[j]
            while a >= 0 and a not in modelled and a != root:
                a = parents[a]
            out[:, j] = rest[j] if a < 0 or a == root and root not in modelled else out[:, a] + (rest[j] - rest[a])
        return Motion.from_positions(out, list(t.joint_names), self.fps, parents)

    # -- files ---------------------------------------------------------------------------------------------
    def save(self, folder: pathlib.Path) -> None:
        """``representation.json`` and the template: ``template.bvh``, or ``template.npz`` for an SMPL-X corpus
        (its rotations; no body model is needed)."""
        smplx = getattr(self.template, "smplx", None)
        name = "template.npz" if smplx is not None else "template.bvh"
        (folder / "representation.json").write_text(json.dumps(
            {"kind": self.kind, "joints": self.joints, "fps": self.fps, "template": name}, indent=1),
            encoding="utf-8")
        if smplx is not None:
            from evalsuite.motion.smplx import write_smplx

            write_smplx(folder / name, smplx)
        else:
            save_motion(self.template, folder / name)

    @classmethod
    def load(cls, folder: pathlib.Path) -> PoseRepresentation:
        try:
            meta = json.loads((folder / "representation.json").read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise InputError(f"not a model folder of a re-implemented generator ({exc})", path=folder,
                             field="--model") from None
        return cls(meta["kind"], list(meta["joints"]), float(meta["fps"]),
                   load_motion(folder / str(meta.get("template", "template.bvh"))))


def as_smplx_result(result: Any, req: Any) -> Any:
    """A result whose motion is SMPL-X rotations (a model trained on an SMPL-X corpus) as SMPL-X output
    (:attr:`GenerationResult.smplx`): resampled to the request's rate and fitted to its frames (the last frame
    held, or the tail cut); any other result unchanged."""
    from evalsuite.generators.contract import GenerationResult
    from evalsuite.motion.smplx_motion import SmplxMotion

    motion = getattr(result, "motion", None)
    if not isinstance(motion, SmplxMotion):
        return result
    m = resample(motion, req.fps) if abs(motion.fps - req.fps) > 1e-9 else motion
    values = np.asarray(m.values)[:req.n_frames]
    if len(values) < req.n_frames:
        values = np.concatenate([values, np.repeat(values[-1:], req.n_frames - len(values), axis=0)])
    fitted = m.with_values(values, fps=req.fps)
    assert isinstance(fitted, SmplxMotion)
    return GenerationResult(None, dict(result.meta), smplx=fitted.smplx)
