"""Benchmark: ``evalsuite score --preset genea-leaderboard`` on 100 recordings x 5 samples x 60 s, and the FK of
one hour of SMPL-X motion.

Makes a synthetic BEAT2 folder once (``--cache``, default ``$TMPDIR/evalsuite-bench-leaderboard``): 100 ground-truth
recordings of 60 s at 30 fps (``smplxflame_30/``, click-track speech in ``wave16k/``, ``sem/`` files,
``train_test_split.csv``), a system folder with 5 samples per recording (``<id>_<k>.npz``, 500 files), a fake SMPL-X
model with the real shapes (10,475 vertices, 300+100 shape columns; random numbers, nothing licensed), a mean
velocity file, and an AESKConv FGD model with random weights (the published checkpoint is not needed for timing).

Then, each in a fresh process (wall time and peak RSS of that process):

* **evalsuite**: the whole preset (all nine metrics) with ``--sampling fixed`` and with ``--sampling all`` (every
  one of the 500 samples enters every metric);
* **per-file reference**: the organisers' script cannot run here (it needs their repository, the ``smplx``
  package, whose licence evalsuite avoids, and their downloads), so the peer is a plain numpy pipeline with the
  same structure: for every file it runs SMPL-X's full forward pass as the ``smplx`` package does before it returns
  joints (shape and pose blend shapes, skinning of all vertices), detects the speech's onsets again, and computes
  the same formulas. It runs on ``--reference-recordings`` recordings (fixed sampling) and is scaled to 100; its
  numbers are checked against evalsuite's on the same recordings (positions to 1e-6 m, metrics to 1e-6 relative);
* **FK of one hour** (108,000 frames) with :func:`evalsuite.motion.smplx_body.smplx_positions`.

Goal (issue 35): the whole preset on 500 one-minute files in under 2 minutes on 2 cores, faster than the
organisers' code on the same CPU.

Run: python benchmarks/bench_leaderboard.py [--cache DIR] [--recordings 100] [--samples 5] [--reference-recordings 5]
"""
from __future__ import annotations

import argparse
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parent.parent
FPS = 30
SR = 16000
N_VERTS = 10475


def generate(cache: pathlib.Path, n_rec: int, n_samples: int, seconds: float) -> dict[str, pathlib.Path]:
    """The synthetic BEAT2 folder, system folder, model files (made once per size)."""
    sys.path.insert(0, str(ROOT))
    sys.path.insert(0, str(ROOT / "tests"))
    import soundfile as sf
    import torch
    from smplx_helpers import fake_poses, fake_smplx_model, write_fake_beat2_recording

    from evalsuite.learned import emage_aeskconv as ea

    lang = cache / "beat_english_v2.0.0"
    paths = {"gt": lang, "sys": cache / "system", "model": cache / "SMPLX_FAKE.npz", "fgd": cache / "fgd.pt",
             "mean_vel": cache / "mean_vel.npy"}
    if (cache / ".complete").exists():
        return paths
    t0 = time.perf_counter()
    for sub in ("smplxflame_30", "wave16k", "sem"):
        (lang / sub).mkdir(parents=True, exist_ok=True)
    paths["sys"].mkdir(parents=True, exist_ok=True)
    n = int(seconds * FPS)
    ids = [f"{2 + r % 4}_speaker{r % 4}_0_{r + 1}_{r + 1}" for r in range(n_rec)]
    (lang / "train_test_split.csv").write_text("id,type\n" + "".join(f"{v},test\n" for v in ids))
    rng = np.random.default_rng(0)
    t = np.arange(int(seconds * SR)) / SR
    for r, vid in enumerate(ids):
        write_fake_beat2_recording(lang / "smplxflame_30" / f"{vid}.npz", n_frames=n, seed=r)
        clicks = np.zeros_like(t)
        for c in np.arange(0.3, seconds, 0.45) + rng.uniform(0, 0.1):
            i = int(c * SR)
            clicks[i:i + 200] += np.hanning(200) * np.sin(2 * np.pi * 900 * t[:200])
        sf.write(lang / "wave16k" / f"{vid}.wav", (0.5 * clicks + rng.normal(0, 0.003, len(t))).astype(np.float32), SR)
        (lang / "sem" / f"{vid}.txt").write_text("".join(f"w\t{s:.2f}\t{s + 1.5:.2f}\t{1 + s % 3:.1f}\t0.5\tx\n"
                                                         for s in np.arange(1.0, seconds - 2, 4.0)))
        base = fake_poses(n, seed=r)
        for k in range(1, n_samples + 1):
            p = base + np.random.default_rng(1000 * r + k).normal(0, 0.03 * k, base.shape)
            write_fake_beat2_recording(paths["sys"] / f"{vid}_{k}.npz", poses=p, seed=k)
    fake_smplx_model(paths["model"], n_betas=300, n_verts=N_VERTS)
    np.save(paths["mean_vel"], np.linspace(0.3, 0.6, 55).astype(np.float32))
    torch.manual_seed(0)
    torch.save({"model_state": ea.AESKConv().state_dict()}, cache / "ck.bin")
    ea.import_emage(cache / "ck.bin", paths["fgd"])
    (cache / ".complete").write_text("ok\n")
    print(f"made the synthetic BEAT2 folder in {time.perf_counter() - t0:.0f} s ({cache})", flush=True)
    return paths


# --- the per-file reference pipeline (runs in a child process) ------------------------------------------------

def _rodrigues(rotvecs: np.ndarray) -> np.ndarray:
    """(..., 3) axis-angle -> (..., 3, 3), written out (Rodrigues' formula)."""
    angle = np.linalg.norm(rotvecs, axis=-1, keepdims=True)
    axis = rotvecs / np.maximum(angle, 1e-12)
    x, y, z = axis[..., 0], axis[..., 1], axis[..., 2]
    zero = np.zeros_like(x)
    k = np.stack([zero, -z, y, z, zero, -x, -y, x, zero], axis=-1).reshape(rotvecs.shape[:-1] + (3, 3))
    s, c = np.sin(angle)[..., None], np.cos(angle)[..., None]
    return np.eye(3) + s * k + (1 - c) * (k @ k)


def full_forward(poses: np.ndarray, betas: np.ndarray, model: dict[str, np.ndarray], parents: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray]:
    """SMPL-X's forward pass as the ``smplx`` package computes it (written from the model's definition): shaped
    template, rest joints, pose blend shapes, rigid transforms down the chain, skinning of every vertex; global
    orientation and translation zeroed as the Leaderboard does. Returns joints (T, 55, 3) and vertices (T, V, 3)."""
    nb = len(betas)
    v_shaped = model["v_template"] + model["shapedirs"][:, :, :nb] @ betas
    rest = model["J_regressor"] @ v_shaped
    rot = _rodrigues(poses.reshape(len(poses), 55, 3))
    rot[:, 0] = np.eye(3)
    feat = (rot[:, 1:] - np.eye(3)).reshape(len(poses), -1)
    v_posed = v_shaped + (feat @ model["posedirs"].reshape(-1, 486).T).reshape(len(poses), -1, 3)
    world = np.zeros((len(poses), 55, 4, 4))
    for j in range(55):
        local = np.zeros((len(poses), 4, 4))
        local[:, :3, :3] = rot[:, j]
        local[:, :3, 3] = rest[j] - (rest[parents[j]] if j else 0.0)
        local[:, 3, 3] = 1.0
        world[:, j] = local if j == 0 else world[:, parents[j]] @ local
    joints = world[:, :, :3, 3].copy()
    world[:, :, :3, 3] -= np.einsum("tjab,jb->tja", world[:, :, :3, :3], rest)
    verts = np.empty_like(v_posed)
    for a in range(0, len(poses), 100):   # (frames, vertices, 3, 4) blended transforms, a block at a time
        blend = np.einsum("vj,tjab->tvab", model["weights"], world[a:a + 100, :, :3, :])
        verts[a:a + 100] = np.einsum("tvab,tvb->tva", blend[..., :3], v_posed[a:a + 100]) + blend[..., 3]
    return joints, verts


def reference_run(paths: dict[str, str], n_rec: int) -> dict[str, float]:
    """Fixed sampling on the first ``n_rec`` recordings, file by file, no caching across files."""
    from evalsuite.leaderboard import beats as bc
    from evalsuite.leaderboard import metrics as lm
    from evalsuite.leaderboard.score import _encoder
    from evalsuite.motion.smplx_layout import SMPLX_PARENTS

    gt_dir = pathlib.Path(paths["gt"])
    ids = sorted(p.stem for p in (gt_dir / "smplxflame_30").glob("*.npz"))[:n_rec]
    with np.load(paths["model"]) as z:
        model = {k: z[k] for k in ("v_template", "shapedirs", "J_regressor", "posedirs", "weights")}
    parents = np.asarray(SMPLX_PARENTS)
    mean_vel = np.load(paths["mean_vel"])
    enc = _encoder(paths["fgd"])
    gts, preds, lat_g, lat_p, l1, srgr, bcs = [], [], [], [], [0.0, 0], [0.0, 0], [0.0, 0.0, 0.0]
    for vid in ids:
        with np.load(gt_dir / "smplxflame_30" / f"{vid}.npz") as z:
            g, betas = z["poses"], z["betas"]
        with np.load(pathlib.Path(paths["sys"]) / f"{vid}_1.npz") as z:
            p = z["poses"]
        t = min(len(g), len(p))
        gts.append(g)
        preds.append(p)
        lat_g.append(enc(g[:t]))
        lat_p.append(enc(p[:t]))
        g_pos, _ = full_forward(g[:t], betas, model, parents)
        p_pos, _ = full_forward(p[:t], betas, model, parents)
        s, n = lm.l1_div_terms(p_pos)
        l1 = [l1[0] + s, l1[1] + n]
        rate = lm.srgr_rate(p_pos, g_pos, lm.semantic_weights(lm.read_sem(gt_dir / "sem" / f"{vid}.txt"), t))
        srgr = [srgr[0] + rate * t, srgr[1] + t]
        wave = bc.load_wave(gt_dir / "wave16k" / f"{vid}.wav")
        a2m, m2a, w = bc.sequence_bc(p_pos, wave, mean_vel, onsets=bc.sequence_onsets(wave, t))
        bcs = [bcs[0] + a2m * w, bcs[1] + m2a * w, bcs[2] + w]
    return {"fid_g": lm.fid_g(gts, preds), "fid_k": lm.fid_k(gts, preds), "var_k": lm.var_k(preds),
            "fgd": lm.frechet_fgd(np.concatenate(lat_g), np.concatenate(lat_p)), "div": l1[0] / l1[1],
            "srgr": srgr[0] / srgr[1], "bc_a2m": bcs[0] / bcs[2], "bc_m2a": bcs[1] / bcs[2]}


def evalsuite_run(paths: dict[str, str], sampling: str, n_rec: int | None = None) -> dict[str, float]:
    from evalsuite.leaderboard import evaluate_leaderboard

    gt, system = paths["gt"], paths["sys"]
    if n_rec is not None:   # a subset: link the first n_rec recordings into a smaller folder
        sub = pathlib.Path(tempfile.mkdtemp(prefix="lb-subset-"))
        ids = sorted(p.stem for p in (pathlib.Path(gt) / "smplxflame_30").glob("*.npz"))[:n_rec]
        for d in ("smplxflame_30", "wave16k", "sem"):
            (sub / "gt" / d).mkdir(parents=True)
        (sub / "sys").mkdir()
        ext = {"smplxflame_30": "npz", "wave16k": "wav", "sem": "txt"}
        for vid in ids:
            for d, e in ext.items():
                os.symlink(pathlib.Path(gt) / d / f"{vid}.{e}", sub / "gt" / d / f"{vid}.{e}")
            for f in pathlib.Path(system).glob(f"{vid}_*.npz"):
                os.symlink(f, sub / "sys" / f.name)
        (sub / "gt" / "train_test_split.csv").write_text("id,type\n" + "".join(f"{v},test\n" for v in ids))
        gt, system = str(sub / "gt"), str(sub / "sys")
    res = evaluate_leaderboard(gt, {"system": system}, sampling=sampling, fgd_model=paths["fgd"],
                               smplx_model=paths["model"], mean_vel=paths["mean_vel"])
    return {r.metric: float(r.value) for r in res.summary.itertuples()}


def child(kind: str, paths: dict[str, str], arg: str) -> None:
    import resource

    t0 = time.perf_counter()
    if kind == "reference":
        values = reference_run(paths, int(arg))
    elif kind == "evalsuite-subset":
        values = evalsuite_run(paths, "fixed", int(arg))
    elif kind == "evalsuite":
        values = evalsuite_run(paths, arg)
    else:   # fk of one hour
        from evalsuite.motion.smplx import SmplxData
        from evalsuite.motion.smplx_body import smplx_positions

        rng = np.random.default_rng(0)
        n = 3600 * FPS
        data = SmplxData(rng.normal(0, 0.3, (n, 165)), np.zeros((n, 3)), rng.normal(0, 1, 300))
        pos = smplx_positions(data, paths["model"], mode="full")
        values = {"frames": float(len(pos))}
    wall = time.perf_counter() - t0
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(json.dumps({"wall_s": wall, "peak_mb": peak_mb, "values": values}))


def measure(kind: str, paths: dict[str, pathlib.Path], arg: str = "") -> dict:
    out = subprocess.run([sys.executable, __file__, "--child", kind, "--child-arg", arg, "--child-paths",
                          json.dumps({k: str(v) for k, v in paths.items()})], capture_output=True, text=True,
                         check=False, env={**os.environ, "PYTHONPATH": str(ROOT)})
    if out.returncode != 0:
        raise SystemExit(f"{kind} failed:\n{out.stderr[-3000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cache", type=pathlib.Path,
                    default=pathlib.Path(tempfile.gettempdir()) / "evalsuite-bench-leaderboard")
    ap.add_argument("--recordings", type=int, default=100)
    ap.add_argument("--samples", type=int, default=5)
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--reference-recordings", type=int, default=5, help="Recordings the per-file reference runs on.")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    ap.add_argument("--child-arg", default="", help=argparse.SUPPRESS)
    ap.add_argument("--child-paths", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(args.child, json.loads(args.child_paths), args.child_arg)
        return
    cache = args.cache / f"r{args.recordings}_s{args.samples}_t{args.seconds:g}"
    paths = generate(cache, args.recordings, args.samples, args.seconds)
    n_files = args.recordings * args.samples
    print(f"machine: {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f}; {args.recordings} recordings x "
          f"{args.samples} samples x {args.seconds:g} s ({n_files} prediction files)", flush=True)
    rows = []
    for sampling in ("fixed", "all"):
        r = measure("evalsuite", paths, sampling)
        rows.append((f"evalsuite preset, sampling={sampling}", r))
        print(f"  evalsuite --preset genea-leaderboard --sampling {sampling}: {r['wall_s']:.1f} s, "
              f"peak {r['peak_mb']:.0f} MB", flush=True)
    k = args.reference_recordings
    ref = measure("reference", paths, str(k))
    sub = measure("evalsuite-subset", paths, str(k))
    worst = max(abs(ref["values"][m] - sub["values"][m]) / max(abs(sub["values"][m]), 1e-12) for m in ref["values"])
    scaled = ref["wall_s"] * args.recordings / k
    fixed = rows[0][1]["wall_s"]
    print(f"  per-file reference (full SMPL-X forward per file, onsets per file) on {k} recordings: "
          f"{ref['wall_s']:.1f} s, peak {ref['peak_mb']:.0f} MB -> {scaled:.0f} s scaled to {args.recordings}; "
          f"evalsuite on the same {k}: {sub['wall_s']:.1f} s; largest relative difference of the 8 metrics "
          f"{worst:.1e}", flush=True)
    fk = measure("fk", paths)
    print(f"  FK of one hour (108,000 frames, 55 joints): {fk['wall_s']:.2f} s, peak {fk['peak_mb']:.0f} MB")
    goal = "met" if rows[1][1]["wall_s"] < 120 else "NOT met"
    print(f"\nwhole preset on {n_files} files (sampling=all): {rows[1][1]['wall_s']:.0f} s (goal < 120 s: {goal}); "
          f"sampling=fixed {fixed:.0f} s, {scaled / fixed:.1f}x faster than the per-file reference")


if __name__ == "__main__":
    main()
