"""Running a generator over many segments: seeds, the rules, parallel work, files, provenance, the cache.

``generate(entry, requests, out_dir, ...)`` writes ``OUT/<segment>.bvh`` (or ``.npz`` for positions; with
``samples > 1``, ``OUT/<segment>_<k>.*``) and ``OUT/generation.json``: the spec, package versions, config,
the model folder's sha256, the seed, every file's sha256, seed and runtime, and every fix the rules made.
A second run with the same generator, config, model, inputs, seed, fps and post-processing finds the same
cache key in ``generation.json`` and the files unchanged, and does nothing.

Per-segment work runs on the shared executor (:func:`evalsuite.parallel.run`: in process, local processes
or a dask.distributed cluster); each worker loads the generator once. Operators that need every segment
together (``batch_only``) run in this process.
"""
from __future__ import annotations

import hashlib
import json
import pathlib
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from evalsuite.errors import InputError
from evalsuite.generators.contract import GenerationRequest, Generator, GeneratorError
from evalsuite.generators.device import GPU_TOLERANCE, current_device
from evalsuite.generators.pose_repr import as_smplx_result
from evalsuite.generators.presets import model_preset
from evalsuite.generators.provenance import describe_inputs, model_sha256, package_versions
from evalsuite.generators.registry import GeneratorEntry, generator_class
from evalsuite.generators.rules import conform, conform_smplx, motion_digest
from evalsuite.hashing import file_sha256
from evalsuite.motion import Motion
from evalsuite.motion.filters import smooth
from evalsuite.motion.io import save_motion
from evalsuite.motion.smplx import write_smplx

__all__ = ["derive_seed", "expand_samples", "generate", "GenerationRun", "PostProcess", "apply_post",
           "GENERATION_FORMAT"]

GENERATION_FORMAT = "evalsuite-generation/1"


def derive_seed(seed: int, segment_id: str, sample: int) -> int:
    """The seed of one segment and sample: the first 4 bytes of sha256(seed, segment, sample), so that seeds
    do not depend on the order or number of segments in a run."""
    digest = hashlib.sha256(f"{seed}\0{segment_id}\0{sample}".encode()).digest()
    return int.from_bytes(digest[:4], "little")


def expand_samples(requests: Sequence[GenerationRequest], samples: int, seed: int) -> list[GenerationRequest]:
    """Each request ``samples`` times (``sample`` 0..k-1) with its derived seed."""
    if samples < 1:
        raise InputError(f"samples must be at least 1, got {samples}", field="--samples")
    return [replace(r, sample=k, seed=derive_seed(seed, r.segment_id, k)) for r in requests for k in range(samples)]


@dataclass(frozen=True)
class PostProcess:
    """A smoothing filter of :mod:`evalsuite.motion.filters` applied to every output (e.g. the moving-average,
    Savitzky-Golay and 1-euro filters studied in "Moving fast and slow")."""

    method: str
    params: tuple[tuple[str, Any], ...] = ()

    def as_dict(self) -> dict[str, Any]:
        return {"method": self.method, **dict(self.params)}


def apply_post(motion: Motion, post: Sequence[PostProcess]) -> Motion:
    for p in post:
        motion = smooth(motion, p.method, **dict(p.params))
    return motion


@dataclass(frozen=True)
class GenerationRun:
    """What one run wrote: ``files`` rows as in ``generation.json``; ``cached`` when nothing was redone."""

    out_dir: pathlib.Path
    files: list[dict[str, Any]]
    cached: bool
    record: dict[str, Any]


# -- the per-segment task (picklable: runs in workers) -----------------------------------------------------
_LOADED: dict[str, Generator] = {}


def _loaded(target: str, config: Mapping[str, Any], model_dir: str | None) -> Generator:
    key = json.dumps([target, dict(config), model_dir], sort_keys=True, default=str)
    if key not in _LOADED:
        gen = generator_class(target)()
        gen.load(config, pathlib.Path(model_dir) if model_dir else None)
        _LOADED[key] = gen
    return _LOADED[key]


def _file_name(req: GenerationRequest, samples: int, motion: Motion | None) -> str:
    """``<segment>[_<k>].bvh`` for rotations, ``.npz`` for positions and SMPL-X (``motion`` None)."""
    stem = req.segment_id if samples == 1 else f"{req.segment_id}_{req.sample}"
    return stem + (".bvh" if motion is not None and motion.is_hierarchical else ".npz")


@dataclass(frozen=True)
class _Task:
    target: str
    config: Mapping[str, Any]
    model_dir: str | None
    out_dir: str
    samples: int
    post: tuple[PostProcess, ...]

    def write(self, gen: Generator, req: GenerationRequest, result: Any, seconds: float) -> dict[str, Any]:
        notes: list[dict[str, Any]] = []
        result = as_smplx_result(result, req)           # a model of SMPL-X rotations writes SMPL-X .npz
        if getattr(result, "smplx", None) is not None:  # an SMPL-X source gives SMPL-X output
            data = conform_smplx(gen.spec, req, result.smplx, bool(self.post))
            path = pathlib.Path(self.out_dir) / (_file_name(req, self.samples, None))
            write_smplx(path, data)
            frames, fps = data.n_frames, data.fps
        else:
            motion, notes = conform(gen.spec, req, result)
            motion = apply_post(motion, self.post)
            path = pathlib.Path(self.out_dir) / _file_name(req, self.samples, motion)
            save_motion(motion, path)
            frames, fps = motion.n_frames, motion.fps
        meta = dict(getattr(result, "meta", {}) or {})
        return {"file": path.name, "segment": req.segment_id, "sample": req.sample, "seed": req.seed,
                "frames": frames, "fps": fps, "sha256": file_sha256(path),
                "runtime_s": round(seconds, 4), "notes": notes, "meta": meta}

    def describe(self, req: GenerationRequest) -> str:
        return f"generator {self.target!r}, segment {req.segment_id!r}"

    def __call__(self, req: GenerationRequest) -> dict[str, Any]:
        gen = _loaded(self.target, self.config, self.model_dir)
        t0 = time.perf_counter()
        result = gen.generate(req)
        return self.write(gen, req, result, time.perf_counter() - t0)


def _cache_key(entry: GeneratorEntry, config: Mapping[str, Any], model_hash: str | None, seed: int, fps: float,
               samples: int, post: Sequence[PostProcess], inputs: list[dict[str, Any]]) -> str:
    assert entry.spec is not None
    payload = {"spec": entry.spec.as_dict(), "target": entry.target, "config": dict(config), "model": model_hash,
               "seed": seed, "fps": fps, "samples": samples, "post": [p.as_dict() for p in post],
               "inputs": inputs, "packages": package_versions()}
    return hashlib.sha256(json.dumps(payload, sort_keys=True, default=str).encode()).hexdigest()


def _cached(out_dir: pathlib.Path, key: str) -> dict[str, Any] | None:
    try:
        record = json.loads((out_dir / "generation.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(record, dict) or record.get("cache_key") != key:
        return None
    for row in record.get("files", []):
        path = out_dir / str(row.get("file"))
        if not path.is_file() or file_sha256(path) != row.get("sha256"):
            return None
    return record


def generate(entry: GeneratorEntry, requests: Sequence[GenerationRequest], out_dir: str | pathlib.Path, *,
             config: Mapping[str, Any] | None = None, model_dir: str | pathlib.Path | None = None, seed: int = 0,
             samples: int = 1, post: Sequence[PostProcess] = (), jobs: int = 1, dask_address: str | None = None,
             check_determinism: bool = True, progress: bool = True, extra_record: Mapping[str, Any] | None = None,
             echo: Callable[[str], None] | None = None) -> GenerationRun:
    """Generate every request (``samples`` times each) into ``out_dir`` under the rules; see the module doc."""
    from evalsuite.parallel import run

    assert entry.spec is not None
    spec, config = entry.spec, dict(config or {})
    if not requests:
        raise InputError("nothing to generate: no segments", field="segments")
    fps_values = {r.fps for r in requests}
    out = pathlib.Path(out_dir)
    model_path = pathlib.Path(model_dir) if model_dir is not None else None
    model_hash = model_sha256(model_path) if model_path is not None else None
    inputs = describe_inputs(requests)
    key = _cache_key(entry, config, model_hash, seed, min(fps_values), samples, post, inputs)
    cached = _cached(out, key)
    if cached is not None:
        return GenerationRun(out, cached["files"], True, cached)
    out.mkdir(parents=True, exist_ok=True)
    all_reqs = expand_samples(requests, samples, seed)
    task = _Task(entry.target, config, str(model_path) if model_path else None, str(out), samples, tuple(post))
    t0 = time.perf_counter()
    gen = _loaded(entry.target, config, task.model_dir)
    if samples > 1 and not gen.stochastic:
        raise InputError(f"{spec.name} is deterministic as configured: --samples {samples} would give {samples} "
                         "identical copies", field="--samples")
    if type(gen).batch_only:
        rows = []
        for k in range(samples):
            reqs = [r for r in all_reqs if r.sample == k]
            t1 = time.perf_counter()
            results = gen.generate_batch(reqs)
            if check_determinism and k == 0:
                for r, a, b in zip(reqs, results, gen.generate_batch(reqs)):
                    _check_determinism_pair(gen, r, a, b)
            each = (time.perf_counter() - t1) / max(1, len(reqs))
            rows += [task.write(gen, r, res, each) for r, res in zip(reqs, results)]
    else:
        rows = []
        if check_determinism:  # the first segment twice, in this process; its first result is kept
            t1 = time.perf_counter()
            first = gen.generate(all_reqs[0])
            seconds = time.perf_counter() - t1
            _check_determinism_pair(gen, all_reqs[0], first, gen.generate(all_reqs[0]))
            rows.append(task.write(gen, all_reqs[0], first, seconds))
        rows += run(task, all_reqs[len(rows):], jobs=jobs, dask_address=dask_address, progress=progress,
                    describe=task.describe, desc=f"generate {spec.name}")
    record = {"format": GENERATION_FORMAT, "generator": spec.as_dict(), "target": entry.target,
              "origin": entry.origin, "distribution": entry.distribution, "config": config,
              "model": {"path": str(model_path), "sha256": model_hash} if model_path else None,
              "preset": model_preset(model_path), "device": current_device(),
              "determinism_check": _determinism_rule() if check_determinism else "off",
              "seed": seed, "fps": sorted(fps_values), "samples": samples, "post": [p.as_dict() for p in post],
              "packages": package_versions(), "cache_key": key, "inputs": inputs, **dict(extra_record or {}),
              "runtime_s": round(time.perf_counter() - t0, 3), "files": rows}
    tmp = out / "generation.json.tmp"
    tmp.write_text(json.dumps(record, indent=1, default=str), encoding="utf-8")
    tmp.replace(out / "generation.json")
    if echo:
        fixed = sum(1 for r in rows if r["notes"])
        echo(f"{spec.name}: {len(rows)} files in {out}" + (f" ({fixed} adjusted by the rules, see generation.json)"
                                                           if fixed else ""))
    return GenerationRun(out, rows, False, record)


def _determinism_rule() -> str:
    """How two runs of the first segment are compared: bitwise on the CPU; on a GPU, whose kernels are not
    bitwise deterministic, within :data:`~evalsuite.generators.device.GPU_TOLERANCE` of the values' range."""
    device = current_device()
    return "bitwise" if device == "cpu" else f"within {GPU_TOLERANCE:g} x the value range ({device})"


def _close(x: np.ndarray, y: np.ndarray) -> bool:
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    if x.shape != y.shape:
        return False
    scale = float(np.ptp(x)) if x.size else 0.0
    return bool(np.all(np.abs(x - y) <= GPU_TOLERANCE * max(scale, 1e-12)))


def _same_output(a: Any, b: Any) -> bool:
    sa, sb = getattr(a, "smplx", None), getattr(b, "smplx", None)
    exact = current_device() == "cpu"
    if sa is not None or sb is not None:
        same = np.array_equal if exact else _close
        return (sa is not None and sb is not None and same(sa.poses, sb.poses) and same(sa.trans, sb.trans))
    ma, mb = getattr(a, "motion", None), getattr(b, "motion", None)
    if not (isinstance(ma, Motion) and isinstance(mb, Motion)):
        return True
    if exact:
        return motion_digest(ma) == motion_digest(mb)
    return ma.joint_names == mb.joint_names and _close(ma.positions(), mb.positions())


def _check_determinism_pair(gen: Generator, req: GenerationRequest, a: Any, b: Any) -> None:
    if not _same_output(a, b):
        raise GeneratorError(f"generator {gen.spec.name!r}, segment {req.segment_id!r}: two runs with the same "
                             f"inputs, config, model and seed ({req.seed}) gave different output (compared "
                             f"{_determinism_rule()}); a plug-in must draw all randomness from the request's seed")
