"""Conditions built from a synthetic-speaker corpus for the coupling tests: natural, the oracle (another
performance), mean pose, mismatched natural motion, and the oracle with time offsets."""
from __future__ import annotations

import pathlib

import numpy as np

from evalsuite.motion.bvh_writer import write_bvh
from evalsuite.synth import Layout, MotionParams, read_synth_corpus, segment_oracle, synthesize_corpus


def build_corpus(root: pathlib.Path, minutes: float = 1.0, seed: int = 0, segment_s: float = 10.0) -> pathlib.Path:
    synthesize_corpus(root, minutes, seed, layout=Layout(segment_s=segment_s), progress=False)
    return root


def _write(folder: pathlib.Path, name: str, motion) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    write_bvh(folder / f"{name}.bvh", motion.skeleton, motion.values, 1.0 / motion.fps)


def build_conditions(corpus_dir: pathlib.Path, out: pathlib.Path, offsets=(0.3, 0.6, 1.2)) -> dict[str, pathlib.Path]:
    """Folders of one BVH per segment (file stem = segment id) for each condition."""
    corpus = read_synth_corpus(corpus_dir)
    params = MotionParams.from_dict(corpus.meta["model"]["params"])
    segs = list(corpus)
    natural = {s.id: s.load_motion() for s in segs}
    mean_values = np.concatenate([m.values for m in natural.values()]).mean(axis=0)
    folders = {name: out / name for name in ("natural", "oracle", "mean_pose", "mismatched")}
    folders.update({f"offset_{o:g}": out / f"offset_{o:g}" for o in offsets})
    for k, seg in enumerate(segs):
        nat = natural[seg.id]
        _write(folders["natural"], seg.id, nat)
        oracle, labels = segment_oracle(corpus, seg.id, seed=1000 + k)
        _write(folders["oracle"], seg.id, oracle)
        for name, text in (("natural", seg.labels.read_text()), ("oracle", labels.to_csv())):
            (folders[name] / "labels").mkdir(exist_ok=True)
            (folders[name] / "labels" / f"{seg.id}.csv").write_text(text)
        _write(folders["mean_pose"], seg.id, nat.with_values(np.tile(mean_values, (nat.n_frames, 1))))
        # the other segments' motion, one after another, cropped to this segment's length
        others = [natural[s.id].values for s in segs[k + 1:] + segs[:k]]
        vals = np.concatenate(others)
        while len(vals) < nat.n_frames:
            vals = np.concatenate([vals, vals])
        _write(folders["mismatched"], seg.id, nat.with_values(vals[: nat.n_frames]))
        for o in offsets:
            _write(folders[f"offset_{o:g}"], seg.id, segment_oracle(corpus, seg.id, params=params.replace(offset_s=o))[0])
    return folders
