"""The scoring engine behind ``evalsuite score``: folders in, per-file work, ordered aggregation.

1. :func:`plan_scoring` lists the motion files of the natural (reference) folder and of each
   condition folder, pairs them by file name (stem) and decides the joint set.
2. Work is split into one task per sequence name (the natural file and every condition's file
   of that name), so the natural motion is loaded once per name. :func:`score_sequence` runs in
   the parent, in local processes (``jobs``) or on a dask cluster; it loads and measures each
   file and returns plain numpy summaries (never the raw motion). A file that fails is reported
   in its record and the others go on.
3. Results are consumed in task order whatever order they finish in: :class:`MomentReducer`
   folds the bulky covariance summaries (FD, CCA) into running sums as they come, and
   :func:`aggregate` combines the rest in a fixed order (conditions as given, sequence names
   sorted), so the numbers are identical however the per-file work was run.
"""
from __future__ import annotations

import os
import pathlib
import warnings
from dataclasses import dataclass, field

import numpy as np

from evalsuite.errors import InputError
from evalsuite.hashing import file_sha256
from evalsuite.metrics import beats as beats_mod
from evalsuite.metrics.cca import cca_fit_moments, cca_score_moments
from evalsuite.metrics.conventions import Convention, get_convention, reference_edges
from evalsuite.metrics.distribution import combine_moments, frechet_from_moments
from evalsuite.metrics.frechet import FrechetWarning
from evalsuite.metrics.histograms import automatic_edges, clipped_fraction, hellinger_rows, joint_histograms

__all__ = ["METRICS", "FAMILIES", "ScoreSetup", "Plan", "resolve_metrics", "plan_scoring", "score_sequence",
           "probe_ranges", "run_tasks", "aggregate", "score_folders"]

MOTION_SUFFIXES = (".bvh", ".npy", ".npz", ".csv")

# metric -> (family, order or None, better)
METRICS = {
    "speed": ("kinematics", 1, "closer to natural"),
    "acceleration": ("kinematics", 2, "closer to natural"),
    "jerk": ("kinematics", 3, "closer to natural"),
    "hellinger_speed": ("histograms", 1, "lower"),
    "hellinger_acceleration": ("histograms", 2, "lower"),
    "hellinger_speed_seq": ("histograms", 1, "lower"),
    "hellinger_acceleration_seq": ("histograms", 2, "lower"),
    "clipped_speed": ("histograms", 1, "closer to natural"),
    "clipped_acceleration": ("histograms", 2, "closer to natural"),
    "ape": ("errors", None, "lower"),
    "mae": ("errors", None, "lower"),
    "fd_g": ("distribution", None, "lower"),
    "fd_k": ("distribution", None, "lower"),
    "l1div": ("distribution", None, "closer to natural"),
    "div_k": ("distribution", None, "closer to natural"),
    "cca": ("cca", None, "higher"),
    "beat_a2m": ("beats", None, "higher"),
    "beat_m2a": ("beats", None, "higher"),
}
FAMILIES = {}
for _m, (_fam, _o, _b) in METRICS.items():
    FAMILIES.setdefault(_fam, []).append(_m)
DEFAULT_FAMILIES = ("kinematics", "histograms", "errors", "distribution", "cca")
DEFAULT_GROUPS = ("wrists", "forearms")


def resolve_metrics(spec, audio: bool) -> list[str]:
    """Metric names from families/metric names (comma-separated string or list); default all but beats
    (plus beats when audio is given)."""
    if spec is None or spec == "" or spec == ():
        items = list(DEFAULT_FAMILIES) + (["beats"] if audio else [])
    else:
        if isinstance(spec, str):
            spec = [spec]
        items = [s.strip() for part in spec for s in str(part).split(",") if s.strip()]
    out = []
    for item in items:
        if item == "all":
            names = [m for f in DEFAULT_FAMILIES for m in FAMILIES[f]] + (FAMILIES["beats"] if audio else [])
        elif item in FAMILIES:
            names = FAMILIES[item]
        elif item in METRICS:
            names = [item]
        else:
            raise InputError(f"unknown metric {item!r}; expected families {', '.join(FAMILIES)} or metrics "
                             f"{', '.join(METRICS)}", field="metrics")
        out.extend(n for n in names if n not in out)
    if any(METRICS[m][0] == "beats" for m in out) and not audio:
        raise InputError("beat alignment needs speech audio: pass --audio AUDIO_DIR with <sequence>.wav files",
                         field="metrics")
    return out


@dataclass
class ScoreSetup:
    """Everything a worker needs besides the file paths (picklable, sent with every task)."""

    joints: list[str]
    metrics: list[str]
    convention: str = "default"
    fps: float | None = None          # for positions files without a frame rate
    resample: float | None = None     # resample every file to this rate first
    edges: dict = field(default_factory=dict)  # quantity -> bin edges
    groups: dict = field(default_factory=dict)  # group name -> joint names (subset of joints)
    sigma: float = 0.1
    length_tolerance_s: float = 1.0
    figures: bool = True

    @property
    def families(self) -> set[str]:
        return {METRICS[m][0] for m in self.metrics}


@dataclass
class Plan:
    """Which files are scored: ``files[condition][sequence] = path``; the reference comes first."""

    reference: str
    conditions: list[str]
    folders: dict
    files: dict
    names: list[str]
    audio: dict
    issues: list[str]
    joints: list[str]


def _list_motion_files(name: str, folder: pathlib.Path) -> dict:
    if not folder.exists():
        raise InputError(f"folder of condition {name!r} does not exist", path=folder)
    if not folder.is_dir():
        raise InputError(f"expected a folder of motion files for condition {name!r}", path=folder)
    found: dict[str, pathlib.Path] = {}
    for path in sorted(folder.iterdir()):
        if path.is_file() and path.suffix.lower() in MOTION_SUFFIXES:
            if path.stem in found:
                raise InputError(f"two files for sequence {path.stem!r}: {found[path.stem].name} and {path.name}; "
                                 "keep one per sequence", path=folder)
            found[path.stem] = path
    if not found:
        raise InputError(f"no motion files ({', '.join(MOTION_SUFFIXES)}) in the folder of condition {name!r}",
                         path=folder)
    return found


def parse_condition(item, default_name=None) -> tuple[str, pathlib.Path]:
    """``"name=path"`` or ``"path"`` (the name is the folder name)."""
    text = str(item)
    if "=" in text and not pathlib.Path(text).exists():
        name, _, path = text.partition("=")
        if not name or not path:
            raise InputError(f"expected NAME=FOLDER or FOLDER, got {text!r}", field="condition")
        return name, pathlib.Path(path)
    path = pathlib.Path(text)
    return default_name or path.resolve().name, path


def plan_scoring(reference, conditions, joints=None, audio_dir=None, strict: bool = False,
                 fps: float | None = None) -> Plan:
    """Pair files by name, check folders, resolve the joint set (see module docstring)."""
    from evalsuite.motion.presets import resolve_joints

    ref_name, ref_path = parse_condition(reference)
    pairs = [(ref_name, ref_path)] + [parse_condition(c) for c in conditions]
    names = [n for n, _ in pairs]
    dupes = sorted({n for n in names if names.count(n) > 1})
    if dupes:
        raise InputError(f"condition names must be unique, {', '.join(dupes)} appears twice; "
                         "name them with NAME=FOLDER", field="condition")
    files = {n: _list_motion_files(n, p) for n, p in pairs}
    issues: list[str] = []
    ref_names = sorted(files[ref_name])
    for cond, _ in pairs[1:]:
        missing = [s for s in ref_names if s not in files[cond]]
        extra = sorted(s for s in files[cond] if s not in files[ref_name])
        if missing:
            msg = (f"condition {cond!r} has no file for {len(missing)} of {len(ref_names)} natural sequences: "
                   f"{', '.join(missing[:10])}{' ...' if len(missing) > 10 else ''}")
            if strict or len(missing) == len(ref_names):
                raise InputError(msg + ("" if strict else "; no pairs left to score"), field="pairs")
            issues.append(msg + "; scored on the sequences it has")
        if extra:
            msg = (f"condition {cond!r} has {len(extra)} files with no natural counterpart (ignored): "
                   f"{', '.join(extra[:10])}{' ...' if len(extra) > 10 else ''}")
            if strict:
                raise InputError(msg, field="pairs")
            issues.append(msg)
    audio = {}
    if audio_dir is not None:
        audio_dir = pathlib.Path(audio_dir)
        if not audio_dir.is_dir():
            raise InputError("audio folder does not exist or is not a folder", path=audio_dir)
        audio = {p.stem: p for p in sorted(audio_dir.glob("*.wav")) + sorted(audio_dir.glob("*.WAV"))}
        lacking = [s for s in ref_names if s not in audio]
        if len(lacking) == len(ref_names):
            raise InputError("no <sequence>.wav file matches any natural sequence name", path=audio_dir)
        if lacking:
            issues.append(f"no audio for {len(lacking)} sequences (beat alignment skipped there): "
                          f"{', '.join(lacking[:10])}")
    # The joint set comes from the first readable natural file.
    first = None
    errors = []
    for s in ref_names:
        try:
            first = _load(files[ref_name][s], fps)
            break
        except InputError as exc:
            errors.append(str(exc))
            if strict:
                raise
    if first is None:
        raise InputError("none of the natural files can be read: " + "; ".join(errors[:3]), field="reference")
    available = first.joint_names
    if joints:
        try:
            joint_list = resolve_joints(joints, available)
        except KeyError as exc:
            raise InputError(f"joints not in the natural motion ({first.source}): {exc.args[0]}; it has "
                             f"{', '.join(available)}", field="joints") from None
        order = {n: i for i, n in enumerate(available)}
        joint_list = sorted(dict.fromkeys(joint_list), key=order.__getitem__)
    else:
        joint_list = list(available)
    return Plan(ref_name, names, dict(pairs), files, ref_names, audio, issues, joint_list)


# Name patterns for skeletons whose joints the presets do not name (e.g. "LeftWrist", "l_elbow").
GROUP_PATTERNS = {"wrists": r"(wrist|hand)$", "forearms": r"(forearm|elbow|lowarm)$", "hands": r"(wrist|hand)$"}


def find_group(group: str, names: list[str]) -> list[str]:
    """Members of a preset group present in ``names``; if none, joints matching its name pattern."""
    import re

    from evalsuite.motion.presets import PRESETS

    present = [j for j in PRESETS.get(group, []) if j in names]
    if not present and group in GROUP_PATTERNS:
        present = [j for j in names if re.search(GROUP_PATTERNS[group], j, flags=re.IGNORECASE)]
    return present


def resolve_groups(group_names, joints: list[str]) -> dict:
    """Named joint groups (presets or ``name:A,B``) restricted to the scored joints; empty ones dropped.

    Preset groups fall back to name patterns (``wrists``: names ending in wrist/hand, ``forearms``:
    forearm/elbow/lowarm) when the skeleton uses other names than the presets.
    """
    from evalsuite.motion.presets import PRESETS

    groups = {"all": list(joints)}
    for g in group_names or ():
        if ":" in g:
            name, _, members = g.partition(":")
            wanted = [m.strip() for m in members.split(",") if m.strip()]
        elif g in PRESETS or g in GROUP_PATTERNS:
            name, wanted = g, find_group(g, joints)
        else:
            raise InputError(f"unknown joint group {g!r}; use a preset ({', '.join(PRESETS)}) or "
                             "NAME:J1;J2 (NAME:J1,J2 in Python)", field="groups")
        present = [j for j in wanted if j in joints]
        if present:
            groups[name] = present
    return groups


# --- per-file work (runs in workers) -----------------------------------------------------------
def _load(path, fps=None, resample_fps=None):
    from evalsuite.motion.io import load_motion
    from evalsuite.motion.ops import resample

    path = pathlib.Path(path)
    suffix = path.suffix.lower()
    give_fps = fps if suffix in (".npy", ".csv") else None
    if suffix == ".npz" and fps is not None:
        try:
            with np.load(path, allow_pickle=False) as data:
                if "fps" not in data.files:
                    give_fps = fps
        except Exception:  # the loader below reports unreadable archives
            pass
    motion = load_motion(path, fps=give_fps)
    if resample_fps is not None and abs(motion.fps - resample_fps) > 1e-9 * resample_fps:
        motion = resample(motion, resample_fps)
    return motion


def _selected_positions(motion, joints: list[str]) -> np.ndarray:
    index = {n: i for i, n in enumerate(motion.joint_names)}
    missing = [j for j in joints if j not in index]
    if missing:
        raise InputError(f"skeleton differs from the natural motion: missing joints {', '.join(missing[:8])}"
                         f"{' ...' if len(missing) > 8 else ''}; score a common subset with --joints",
                         path=motion.source)
    return motion.positions()[:, [index[j] for j in joints]]


def _norms(pos, order, scale):
    d = np.diff(pos, n=order, axis=0)
    return np.sqrt(np.einsum("tjk,tjk->tj", d, d)) * scale


def _moments(x):
    mean = x.mean(axis=0)
    c = x - mean
    return (len(x), mean, c.T @ c)


def _wrist_track(motion, fps):
    """Wrist positions relative to the root's ground-plane position, about 10 per second (for figures)."""
    wrists = find_group("wrists", motion.joint_names)
    if not wrists:
        return None
    pos = motion.positions()
    roots = np.flatnonzero(motion.parents < 0)
    root = pos[:, roots[0] if roots.size else 0].copy()
    root[:, 1] = 0.0  # keep height; remove travel on the ground plane (Y-up BVH)
    idx = [motion.joint_names.index(w) for w in wrists]
    step = max(1, int(round(fps / 10.0)))
    return (pos[::step, idx] - root[::step, None, :]).astype(np.float32), fps / step


def _centred_halves(x: np.ndarray) -> list:
    """``[(n, mean, x - mean)]`` of the first and second half of ``(N, D)`` frames."""
    half = len(x) // 2
    return [(len(p), p.mean(axis=0), p - p.mean(axis=0)) for p in (x[:half], x[half:])]


def _cca_halves(x_flat, natural_cache, natural_flat):
    """Moments of stacked ``[x; y]`` frames in two halves, from blocks: ``Sxx``, ``Sxy`` per file and
    the natural ``Syy`` computed once per sequence (the costly part is 3 of the 4 blocks otherwise).
    Also returns the ``Sxx`` halves, from which the pose moments follow without another product."""
    n_common = len(x_flat)
    if n_common not in natural_cache:
        hy = _centred_halves(natural_flat[:n_common])
        natural_cache[n_common] = (hy, [cy.T @ cy for _, _, cy in hy])
    hy, syy = natural_cache[n_common]
    out, xx = [], []
    for (n, mx, cx), (_, my, cy), s_yy in zip(_centred_halves(x_flat), hy, syy):
        s_xx, s_xy = cx.T @ cx, cx.T @ cy
        out.append((n, np.concatenate([mx, my]), np.block([[s_xx, s_xy], [s_xy.T, s_yy]])))
        xx.append((n, mx, s_xx))
    return tuple(out), xx


def _measure(motion, pos, setup: ScoreSetup, conv: Convention, natural_pos, audio_onsets, names,
             natural_cache=None):
    fam = setup.families
    natural_cache = {} if natural_cache is None else natural_cache
    fps = motion.fps
    rec: dict = {"fps": fps, "n_frames": int(len(pos))}
    if len(pos) < 4:
        raise InputError(f"only {len(pos)} frames; at least 4 are needed (jerk uses 3rd differences)",
                         path=motion.source)
    if "kinematics" in fam or "histograms" in fam:
        for q, order in (("speed", 1), ("acceleration", 2), ("jerk", 3)):
            if "kinematics" not in fam and q == "jerk":
                continue
            n = _norms(pos, order, conv.scale(fps, order))
            rec[f"{q}_joint"] = n.mean(axis=0)
            if "histograms" in fam and q in setup.edges:
                rec[f"hist_{q}"] = joint_histograms(n, setup.edges[q])
    flat = pos.reshape(len(pos), -1)
    pose_halves = None
    if natural_pos is not None and ("errors" in fam or "cca" in fam):
        n_common = min(len(pos), len(natural_pos))
        diff_s = abs(len(pos) - len(natural_pos)) / fps
        rec["length_diff_s"] = diff_s
        if diff_s > setup.length_tolerance_s:
            rec.setdefault("warnings", []).append(
                f"{len(pos)} frames vs {len(natural_pos)} natural ({diff_s:.2f} s apart, more than "
                f"{setup.length_tolerance_s:g} s); truncated to {n_common} frames")
        a, b = pos[:n_common], natural_pos[:n_common]
        if "errors" in fam:
            d = a - b
            rec["ape_joint"] = np.sqrt(np.einsum("tjk,tjk->tj", d, d)).mean(axis=0)
            rec["mae_joint"] = np.abs(d).mean(axis=(0, 2))
        if "cca" in fam:
            rec["cca_halves"], xx = _cca_halves(flat[:n_common], natural_cache,
                                                natural_pos.reshape(len(natural_pos), -1))
            if n_common == len(pos):
                pose_halves = xx
    if "distribution" in fam:
        rec["pose_moments"] = combine_moments(pose_halves) if pose_halves else _moments(flat)
        rec["diff_moments"] = _moments(np.diff(flat, axis=0))
        rec["l1_sum"] = float(np.abs(flat - flat.mean(axis=0)).sum())
        rec["div_k"] = float(np.var(flat, axis=0).mean())
    if "beats" in fam and audio_onsets is not None:
        wrist_idx = [i for i, j in enumerate(names) if j in setup.groups.get("wrists", [])]
        beat_pos = pos[:, wrist_idx] if wrist_idx else pos
        mb = beats_mod.motion_beats(beat_pos, fps)
        rec["beat_a2m"] = beats_mod.beat_alignment_score(audio_onsets, mb, setup.sigma)
        rec["beat_m2a"] = beats_mod.beat_alignment_score(mb, audio_onsets, setup.sigma)
    if setup.figures:
        rec["wrist_track"] = _wrist_track(motion, fps)
    return rec


def score_sequence(task) -> dict:
    """Measure one sequence in every condition: ``task = (name, [(condition, path), ...], audio, setup)``.

    The first entry is the natural file. Returns ``{"name", "records": {condition: record}}`` where
    a record holds numpy summaries, or ``{"error": message}`` for a file that could not be scored.
    """
    name, entries, audio_path, setup = task
    conv = get_convention(setup.convention)
    records: dict = {}
    onsets = None
    audio_error = None
    if audio_path is not None and "beats" in setup.families:
        try:
            signal, sr = beats_mod.read_wav(audio_path)
            onsets = beats_mod.audio_onsets(signal, sr)
        except InputError as exc:
            audio_error = str(exc)
    natural_pos = None
    natural_cache: dict = {}
    for k, (cond, path) in enumerate(entries):
        try:
            motion = _load(path, setup.fps, setup.resample)
            pos = _selected_positions(motion, setup.joints)
            if k == 0:
                natural_pos = pos
            rec = _measure(motion, pos, setup, conv, natural_pos, onsets, setup.joints, natural_cache)
            rec["sha256"] = file_sha256(path)
            rec["path"] = str(path)
            if audio_error:
                rec.setdefault("warnings", []).append(audio_error)
            records[cond] = rec
        except InputError as exc:
            records[cond] = {"error": str(exc), "path": str(path)}
        except Exception as exc:  # a broken file must not lose the other results
            records[cond] = {"error": f"{path}: cannot be scored ({type(exc).__name__}: {exc})", "path": str(path)}
    return {"name": name, "records": records}


def probe_ranges(task) -> dict:
    """99.5th percentiles of pooled speed and acceleration of one natural file (for automatic bins)."""
    path, setup = task
    conv = get_convention(setup.convention)
    try:
        motion = _load(path, setup.fps, setup.resample)
        pos = _selected_positions(motion, setup.joints)
        out = {"path": str(path), "fps": motion.fps}
        for q, order in (("speed", 1), ("acceleration", 2)):
            n = _norms(pos, order, conv.scale(motion.fps, order))
            out[q] = float(np.percentile(n, 99.5)) if n.size else float("nan")
        return out
    except Exception as exc:  # reported by the main pass
        return {"path": str(path), "error": str(exc)}


# --- running tasks --------------------------------------------------------------------------
_BLAS_THREAD_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def run_tasks(func, tasks, *, jobs: int = 1, dask_address: str | None = None, progress: bool = True,
              weights=None, desc: str = "files", consume=None) -> list:
    """``[func(t) for t in tasks]`` in task order, locally, in ``jobs`` processes or on a dask cluster.

    ``weights`` (files per task) drive the tqdm progress bar, which counts files. ``consume(i, result)``,
    if given, is called for every result **in task order** whatever order they finish in (results
    that arrive early wait in a buffer); what it returns replaces the result (e.g. with its bulky
    parts folded into running sums and dropped), so reductions are identical in every mode.
    """
    from tqdm import tqdm

    tasks = list(tasks)
    weights = list(weights) if weights is not None else [1] * len(tasks)
    results: list = [None] * len(tasks)
    waiting: dict = {}
    next_index = 0
    bar = tqdm(total=sum(weights), unit="file", desc=desc, disable=not progress, leave=False)

    def deliver(i, res):
        nonlocal next_index
        waiting[i] = res
        while next_index in waiting:
            r = waiting.pop(next_index)
            results[next_index] = consume(next_index, r) if consume is not None else r
            next_index += 1
        bar.update(weights[i])
    try:
        if dask_address:
            try:
                from distributed import Client, as_completed
            except ImportError:
                raise InputError("--dask needs dask.distributed: pip install 'evalsuite[dask]'") from None
            try:
                client = Client(dask_address, timeout="10s")
            except (OSError, TimeoutError) as exc:
                raise InputError(f"cannot connect to the dask scheduler at {dask_address} ({exc})",
                                 field="dask") from None
            try:
                futures = client.map(func, tasks, pure=False)
                index = {f.key: i for i, f in enumerate(futures)}
                for fut in as_completed(futures):
                    deliver(index[fut.key], fut.result())
            finally:
                client.close()
        elif jobs and jobs > 1 and len(tasks) > 1:
            import multiprocessing
            from concurrent.futures import ProcessPoolExecutor, as_completed as done

            ctx = multiprocessing.get_context("spawn")
            # One BLAS thread per worker process: N processes x N BLAS threads would oversubscribe
            # the cores. The variables are read when a spawned worker imports numpy.
            saved = {k: os.environ.get(k) for k in _BLAS_THREAD_VARS}
            os.environ.update({k: "1" for k in _BLAS_THREAD_VARS})
            try:
                with ProcessPoolExecutor(max_workers=min(jobs, len(tasks)), mp_context=ctx) as pool:
                    futs = {pool.submit(func, t): i for i, t in enumerate(tasks)}
                    for fut in done(futs):
                        deliver(futs[fut], fut.result())
            finally:
                for k, v in saved.items():
                    if v is None:
                        os.environ.pop(k, None)
                    else:
                        os.environ[k] = v
        else:
            for i, t in enumerate(tasks):
                deliver(i, func(t))
    finally:
        bar.close()
    return results


# --- aggregation (parent, fixed order) -------------------------------------------------------
class MomentReducer:
    """Folds the bulky moment summaries of each sequence into running sums, in task order.

    Per condition: pooled pose and frame-difference moments of the condition and of the natural
    sequences it is paired with (FD_g, FD_k), and CCA moments of stacked ``[generated; natural]``
    frames in two folds (sequences at even/odd positions of the sorted natural names) and in two
    halves in time. The per-file matrices are then dropped (kept for FD only when bootstrapping,
    which resamples sequences), so memory does not grow with the number of files.
    """

    def __init__(self, reference: str, keep_fd_moments: bool):
        self.reference = reference
        self.keep = keep_fd_moments
        self.acc: dict = {}

    def _add(self, cond, key, m):
        slot = self.acc.setdefault(cond, {})
        slot[key] = m if key not in slot else combine_moments([slot[key], m])

    def __call__(self, index: int, result: dict) -> dict:
        records = result["records"]
        nat = records.get(self.reference, {})
        for cond, rec in records.items():
            if "error" in rec or "error" in nat or not nat:
                continue
            for key in ("pose_moments", "diff_moments"):
                if key in rec:
                    self._add(cond, key, rec[key])
                    self._add(cond, "natural_" + key, nat[key])
            halves = rec.pop("cca_halves", None)
            if halves is not None:
                fold = combine_moments(list(halves))
                self._add(cond, f"cca_fold{index % 2}", fold)
                self._add(cond, "cca_first_half", halves[0])
                self._add(cond, "cca_second_half", halves[1])
        if not self.keep:  # every condition of this sequence has used them now
            for rec in records.values():
                rec.pop("pose_moments", None)
                rec.pop("diff_moments", None)
        return result


def _bootstrap_weights(n: int, n_boot: int, seed: int, cond_index: int) -> np.ndarray:
    rng = np.random.default_rng([int(seed), int(cond_index)])
    idx = rng.integers(0, n, size=(n_boot, n))
    w = np.zeros((n_boot, n))
    np.add.at(w, (np.arange(n_boot)[:, None], idx), 1.0)
    return w


def _ci(samples) -> tuple[float, float]:
    s = np.asarray(samples, dtype=np.float64)
    s = s[np.isfinite(s)]
    if s.size == 0:
        return float("nan"), float("nan")
    return float(np.percentile(s, 2.5)), float(np.percentile(s, 97.5))


def _weighted_mean_boot(w, values):
    v = np.asarray(values, dtype=np.float64)
    ok = np.isfinite(v)
    with np.errstate(invalid="ignore", divide="ignore"):
        return (w @ np.where(ok, v, 0.0)) / (w @ ok.astype(float))


def aggregate(plan: Plan, setup: ScoreSetup, results: list, *, bootstrap: int = 0, seed: int = 0,
              strict: bool = False, reduced: dict | None = None) -> dict:
    """Summary, per-sequence and per-joint rows, pooled histograms and issues from task results.

    ``reduced`` holds the :class:`MomentReducer` sums (computed here from ``results`` if not given).
    """
    if reduced is None:
        reducer = MomentReducer(plan.reference, keep_fd_moments=True)
        for i, res in enumerate(results):
            reducer(i, res)
        reduced = reducer.acc
    conv = get_convention(setup.convention)
    records = {c: {} for c in plan.conditions}
    issues = list(plan.issues)
    errors = []
    for res in results:
        for cond, rec in res["records"].items():
            if "error" in rec:
                errors.append(rec["error"])
                continue
            for w in rec.get("warnings", []):
                issues.append(f"{cond}/{res['name']}: {w}")
            records[cond][res["name"]] = rec
    if errors and strict:
        raise InputError(f"{len(errors)} file(s) could not be scored (--strict): " + "; ".join(errors[:5]))
    issues.extend(f"skipped: {e}" for e in errors)
    fps_by_cond = {c: sorted({r["fps"] for r in recs.values()}) for c, recs in records.items() if recs}
    all_fps = sorted({f for v in fps_by_cond.values() for f in v})
    if not records[plan.reference]:
        raise InputError("no natural file could be scored: " + "; ".join(errors[:5]), field="reference")
    if len(all_fps) > 1:
        detail = "; ".join(f"{c}: {', '.join(f'{f:g}' for f in v)} fps" for c, v in fps_by_cond.items())
        raise InputError(f"frame rates differ ({detail}); evalsuite does not mix rates: pass --resample FPS "
                         "to resample every file to one rate", field="fps")
    fps = all_fps[0]
    fam = setup.families
    ref = records[plan.reference]
    summary, per_seq, per_joint, pooled_hists = [], [], [], []
    units = {
        "speed": conv.unit(1), "acceleration": conv.unit(2), "jerk": conv.unit(3),
        "ape": "units", "mae": "units", "fd_g": "units^2", "fd_k": "units^2", "l1div": "units",
        "div_k": "units^2", "cca": "r", "beat_a2m": "score", "beat_m2a": "score",
    }

    def add(cond, metric, value, std=float("nan"), n=0, ci=(float("nan"), float("nan")), unit=None, better=None):
        base = metric.split("[")[0]
        summary.append({"condition": cond, "metric": metric, "value": float(value),
                        "unit": unit or units.get(base, ""), "ci_low": ci[0], "ci_high": ci[1],
                        "std": float(std), "n": int(n), "better": better or METRICS.get(base, ("", "", ""))[2],
                        "convention": conv.name})

    for ci_, cond in enumerate(plan.conditions):
        recs = records[cond]
        names = sorted(s for s in recs if s in ref)
        if not names:
            issues.append(f"condition {cond!r}: no sequence could be scored together with its natural one")
            continue
        n = len(names)
        w = _bootstrap_weights(n, bootstrap, seed, ci_) if bootstrap else None

        def mean_metric(metric, values, unit=None):
            values = np.asarray(values, dtype=np.float64)
            for s, v in zip(names, values):
                per_seq.append({"condition": cond, "sequence": s, "metric": metric, "value": float(v),
                                "unit": unit or units.get(metric, "")})
            finite = values[np.isfinite(values)]
            mean = float(finite.mean()) if finite.size else float("nan")
            std = float(np.std(finite, ddof=conv.std_ddof)) if finite.size > conv.std_ddof else float("nan")
            ci = _ci(_weighted_mean_boot(w, values)) if w is not None else (float("nan"), float("nan"))
            add(cond, metric, mean, std, finite.size, ci, unit)

        # kinematics
        for q in ("speed", "acceleration", "jerk"):
            if q in setup.metrics:
                table = np.stack([recs[s][f"{q}_joint"] for s in names])
                mean_metric(q, table.mean(axis=1))
                for j, v in zip(setup.joints, table.mean(axis=0)):
                    per_joint.append({"condition": cond, "joint": j, "metric": q, "value": float(v),
                                      "unit": units[q]})
        # histograms
        if "histograms" in fam:
            for q in ("speed", "acceleration"):
                key = f"hist_{q}"
                if q not in setup.edges:
                    continue
                hc = np.stack([recs[s][key] for s in names]).astype(np.float64)   # (n, J, B+1)
                hr = np.stack([ref[s][key] for s in names]).astype(np.float64)
                use = slice(None) if conv.overflow else slice(0, -1)
                for gname, members in setup.groups.items():
                    gi = [setup.joints.index(m) for m in members]
                    gc, gr = hc[:, gi].sum(axis=1), hr[:, gi].sum(axis=1)       # (n, B+1)
                    metric = f"hellinger_{q}" + ("" if gname == "all" else f"[{gname}]")
                    if metric.split("[")[0] in setup.metrics:
                        value = hellinger_rows(gc.sum(0)[use], gr.sum(0)[use])
                        ci = (_ci(hellinger_rows((w @ gc)[:, use], (w @ gr)[:, use])) if w is not None
                              else (float("nan"), float("nan")))
                        add(cond, metric, value, n=n, ci=ci, unit="H")
                    pooled_hists.append({"condition": cond, "quantity": q, "group": gname,
                                         "counts": gc.sum(0)})
                if f"hellinger_{q}_seq" in setup.metrics:
                    mean_metric(f"hellinger_{q}_seq", hellinger_rows(hc.sum(1)[:, use], hr.sum(1)[:, use]),
                                unit="H")
                if f"clipped_{q}" in setup.metrics:
                    tot = hc.sum(axis=1)   # (n, B+1)
                    value = float(clipped_fraction(tot.sum(0)))
                    ci = _ci(clipped_fraction(w @ tot)) if w is not None else (float("nan"), float("nan"))
                    add(cond, f"clipped_{q}", value, n=n, ci=ci, unit="fraction")
                if f"hellinger_{q}" in setup.metrics:
                    for j, jname in enumerate(setup.joints):
                        per_joint.append({"condition": cond, "joint": jname, "metric": f"hellinger_{q}",
                                          "value": float(hellinger_rows(hc[:, j].sum(0)[use], hr[:, j].sum(0)[use])),
                                          "unit": "H"})
        # errors against ground truth
        for q in ("ape", "mae"):
            if q in setup.metrics:
                table = np.stack([recs[s][f"{q}_joint"] for s in names])
                mean_metric(q, table.mean(axis=1))
                for j, v in zip(setup.joints, table.mean(axis=0)):
                    per_joint.append({"condition": cond, "joint": j, "metric": q, "value": float(v), "unit": "units"})
        # distribution distances
        if "distribution" in fam:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always", FrechetWarning)
                for q, key in (("fd_g", "pose_moments"), ("fd_k", "diff_moments")):
                    if q not in setup.metrics:
                        continue
                    acc = reduced.get(cond, {})
                    value = frechet_from_moments(acc["natural_" + key], acc[key])
                    ci = (float("nan"), float("nan"))
                    if w is not None:
                        pc = [recs[s][key] for s in names]
                        pr = [ref[s][key] for s in names]
                        with warnings.catch_warnings():
                            warnings.simplefilter("ignore", FrechetWarning)
                            ci = _ci([frechet_from_moments(combine_moments(pr, wb), combine_moments(pc, wb))
                                      for wb in w])
                    add(cond, q, value, n=n, ci=ci)
            for c in caught:
                issues.append(f"{cond}: {c.message}")
            if "l1div" in setup.metrics:
                sums = np.array([recs[s]["l1_sum"] for s in names])
                frames = np.array([recs[s]["n_frames"] for s in names], dtype=np.float64)
                for s, v in zip(names, sums / frames):
                    per_seq.append({"condition": cond, "sequence": s, "metric": "l1div", "value": float(v),
                                    "unit": "units"})
                ci = _ci((w @ sums) / (w @ frames)) if w is not None else (float("nan"), float("nan"))
                add(cond, "l1div", sums.sum() / frames.sum(), n=n, ci=ci)
            if "div_k" in setup.metrics:
                mean_metric("div_k", [recs[s]["div_k"] for s in names])
        if "cca" in setup.metrics:
            add(cond, "cca", *_cca_value(reduced.get(cond, {}), len(names), len(setup.joints) * 3,
                                         conv.cca_in_sample, issues, cond))
        for q in ("beat_a2m", "beat_m2a"):
            if q in setup.metrics:
                mean_metric(q, [recs[s].get(q, float("nan")) for s in names])
    files = {c: {s: {"path": r["path"], "sha256": r["sha256"], "n_frames": r["n_frames"]}
                 for s, r in sorted(records[c].items())} for c in plan.conditions}
    tracks = {c: [records[c][s]["wrist_track"] for s in sorted(records[c])
                  if records[c][s].get("wrist_track") is not None] for c in plan.conditions}
    return {"summary": summary, "per_sequence": per_seq, "per_joint": per_joint, "histograms": pooled_hists,
            "issues": issues, "errors": errors, "fps": fps, "files": files, "wrist_tracks": tracks}


def _cca_value(acc: dict, n_names: int, dx: int, in_sample: bool, issues: list, cond: str):
    """(value, std, n): in-sample, or cross-fitted over two folds of sequences (both ways, averaged);
    when a fold is empty (a single sequence), over the first and second halves in time."""
    try:
        folds = [acc.get("cca_fold0"), acc.get("cca_fold1")]
        if in_sample:
            whole = combine_moments([f for f in folds if f is not None])
            return cca_fit_moments(*whole, dx).correlation, float("nan"), n_names
        if folds[0] is None or folds[1] is None:
            folds = [acc["cca_first_half"], acc["cca_second_half"]]
        ma, mb = folds
        scores = [cca_score_moments(cca_fit_moments(*ma, dx), *mb, dx),
                  cca_score_moments(cca_fit_moments(*mb, dx), *ma, dx)]
        return float(np.mean(scores)), float("nan"), n_names
    except InputError as exc:
        issues.append(f"{cond}: CCA not computed ({exc.reason})")
        return float("nan"), float("nan"), n_names


# --- the whole run ----------------------------------------------------------------------------
def score_folders(reference, conditions, *, joints=None, metrics=None, convention="default", audio_dir=None,
                  fps=None, resample=None, speed_bins=None, acceleration_bins=None, groups=DEFAULT_GROUPS,
                  sigma: float = 0.1, bootstrap: int = 0, seed: int = 0, jobs: int = 1, dask_address=None,
                  strict: bool = False, progress: bool = True, figures: bool = True) -> dict:
    """Score condition folders against a natural folder; returns the :func:`aggregate` dict plus the
    plan and setup (what ``evalsuite score`` writes out)."""
    conv = get_convention(convention)
    metric_list = resolve_metrics(metrics, audio_dir is not None)
    plan = plan_scoring(reference, conditions, joints, audio_dir, strict, fps)
    setup = ScoreSetup(joints=plan.joints, metrics=metric_list, convention=conv.name, fps=fps, resample=resample,
                       groups=resolve_groups(groups, plan.joints), sigma=sigma, figures=figures)
    if "histograms" in setup.families:
        setup.edges = _edges(plan, setup, conv, speed_bins, acceleration_bins, jobs, dask_address, progress)
    tasks, weights = [], []
    for s in plan.names:
        entries = [(c, plan.files[c][s]) for c in plan.conditions if s in plan.files[c]]
        tasks.append((s, entries, plan.audio.get(s), setup))
        weights.append(len(entries))
    reducer = MomentReducer(plan.reference, keep_fd_moments=bool(bootstrap))
    results = run_tasks(score_sequence, tasks, jobs=jobs, dask_address=dask_address, progress=progress,
                        weights=weights, desc="scoring", consume=reducer)
    out = aggregate(plan, setup, results, bootstrap=bootstrap, seed=seed, strict=strict, reduced=reducer.acc)
    out.update(plan=plan, setup=setup, convention=conv, bootstrap=bootstrap, seed=seed)
    return out


def _parse_bins(spec):
    if spec is None or isinstance(spec, tuple):
        return spec
    try:
        top, width = (float(v) for v in str(spec).split(":"))
    except ValueError:
        raise InputError(f"expected bins as MAX:WIDTH (e.g. 250:2.5), got {spec!r}", field="bins") from None
    return top, width


def _edges(plan, setup, conv, speed_bins, acceleration_bins, jobs, dask_address, progress) -> dict:
    given = {"speed": _parse_bins(speed_bins) or conv.bins("speed"),
             "acceleration": _parse_bins(acceleration_bins) or conv.bins("acceleration")}
    edges = {q: reference_edges(*b) for q, b in given.items() if b is not None}
    auto = [q for q, b in given.items() if b is None]
    if auto:
        ref_files = [plan.files[plan.reference][s] for s in plan.names]
        probes = run_tasks(probe_ranges, [(p, setup) for p in ref_files], jobs=jobs, dask_address=dask_address,
                           progress=progress, desc="bin ranges")
        for q in auto:
            vals = [p[q] for p in probes if "error" not in p and np.isfinite(p[q])]
            edges[q] = automatic_edges(max(vals) if vals else 1.0)
    return edges
