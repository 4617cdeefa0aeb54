"""Tests for evalsuite.leaderboard.metrics and evalsuite.leaderboard.beats: each GENEA Leaderboard metric against
an independent implementation written here from the definitions (loops, plain formulas), to 1e-6 relative."""
from __future__ import annotations

import math

import numpy as np
import pytest

from evalsuite.errors import InputError
from evalsuite.leaderboard import beats as bc
from evalsuite.leaderboard import metrics as lm

REL = 1e-6


def rel(a, b):
    return abs(a - b) / max(abs(b), 1e-12)


# ---------------------------------------------------------------- independent references
def ref_stats(x):
    x = np.asarray(x, dtype=np.float64)
    n = len(x)
    mu = np.array([sum(x[i, d] for i in range(n)) / n for d in range(x.shape[1])])
    c = x - mu
    return mu, (c.T @ c) / (n - 1)


def ref_fd(mu1, s1, mu2, s2, eps=0.0):
    """FD with tr sqrt(S1 S2) from the eigenvalues of the symmetric A^1/2 B A^1/2 (A = S1 + eps I, B = S2 + eps I)."""
    a = s1 + eps * np.eye(len(s1))
    b = s2 + eps * np.eye(len(s2))
    w, v = np.linalg.eigh(a)
    root = (v * np.sqrt(np.clip(w, 0, None))) @ v.T
    tr = np.sqrt(np.clip(np.linalg.eigvalsh(root @ b @ root), 0, None)).sum()
    return float(np.sum((mu1 - mu2) ** 2) + np.trace(s1) + np.trace(s2) - 2 * tr)


def seqs(rng, lengths, d=12, scale=1.0):
    return [rng.normal(0.3, scale, (n, d)) + np.sin(np.arange(n))[:, None] * 0.2 for n in lengths]


# ---------------------------------------------------------------- Fréchet distances
def test_frechet_published_equals_symmetric_form():
    rng = np.random.default_rng(0)
    x, y = rng.normal(0, 1, (400, 8)), rng.normal(0.5, 1.3, (300, 8)) @ rng.normal(0, 1, (8, 8))
    got = lm.frechet_published(*lm.gaussian(x), *lm.gaussian(y))
    assert rel(got, ref_fd(*ref_stats(x), *ref_stats(y))) < REL


def test_frechet_fgd_adds_eps_inside_the_root_only():
    rng = np.random.default_rng(1)
    x, y = rng.normal(0, 0.01, (50, 6)), rng.normal(0, 0.02, (60, 6))
    got = lm.frechet_fgd(x, y)
    assert rel(got, ref_fd(*ref_stats(x), *ref_stats(y), eps=1e-6)) < REL
    assert rel(got, ref_fd(*ref_stats(x), *ref_stats(y))) > 1e-6   # the eps matters at this scale


def test_fid_g_and_fid_k_pool_frames_without_truncation():
    rng = np.random.default_rng(2)
    gt = seqs(rng, [120, 90, 150])
    pred = seqs(rng, [100, 140, 150, 60], scale=1.2)  # other lengths and counts: nothing is cut or paired
    g, p = np.concatenate(gt), np.concatenate(pred)
    assert rel(lm.fid_g(gt, pred), ref_fd(*ref_stats(g), *ref_stats(p))) < REL
    dg = np.concatenate([[s[t + 1] - s[t] for t in range(len(s) - 1)] for s in gt])
    dp = np.concatenate([[s[t + 1] - s[t] for t in range(len(s) - 1)] for s in pred])
    assert rel(lm.fid_k(gt, pred), ref_fd(*ref_stats(dg), *ref_stats(dp))) < REL
    # frames past the ground truth's length count: a prediction longer than its ground truth, drifting at the end
    long_pred = [np.concatenate([s, s[-40:] + 3.0]) for s in pred]
    assert lm.fid_g(gt, long_pred) > lm.fid_g(gt, pred) + 1.0


def test_var_k_is_mean_of_temporal_variance():
    rng = np.random.default_rng(3)
    pred = seqs(rng, [40, 55], d=5)
    vals = []
    for s in pred:
        for d in range(s.shape[1]):
            m = sum(s[:, d]) / len(s)
            vals.append(sum((v - m) ** 2 for v in s[:, d]) / len(s))
    assert rel(lm.var_k(pred), sum(vals) / len(vals)) < REL


def test_sample_div_cuts_to_shortest_and_needs_two_samples():
    rng = np.random.default_rng(4)
    groups = {"a": seqs(rng, [30, 28, 33], d=4), "b": seqs(rng, [20, 20], d=4)}
    per = []
    for samples in groups.values():
        n = min(len(s) for s in samples)
        total, count = 0.0, 0
        for t in range(n):
            for d in range(4):
                vals = [s[t, d] for s in samples]
                m = sum(vals) / len(vals)
                total += sum((v - m) ** 2 for v in vals) / len(vals)
                count += 1
        per.append(total / count)
    assert rel(lm.sample_div(groups), sum(per) / len(per)) < REL
    with pytest.raises(InputError, match=r"at least 2 samples per recording; b has 1"):
        lm.sample_div({"a": groups["a"], "b": groups["b"][:1]})


def test_div_is_l1_around_the_mean_over_all_frames():
    rng = np.random.default_rng(5)
    pos = [rng.normal(0, 0.2, (n, 55, 3)) for n in (20, 31)]
    total, frames = 0.0, 0
    for p in pos:
        flat = p.reshape(len(p), -1)
        for d in range(flat.shape[1]):
            m = sum(flat[:, d]) / len(flat)
            total += sum(abs(v - m) for v in flat[:, d])
        frames += len(p)
    assert rel(lm.div(pos), total / frames) < REL


# ---------------------------------------------------------------- SRGR
def test_semantic_weights_floor_ceil_max_and_float32(tmp_path):
    sem = tmp_path / "x.txt"
    sem.write_text("a\t0.51\t1.0\t0.49\t0.3\tfoo\nb\t0.9\t1.52\t0.62\t0.7\t\nc\t2.0\t2.0\t0.0\t0.9\tzero length\n")
    rows = lm.read_sem(sem)
    assert rows == [(0.51, 1.0, 0.3), (0.9, 1.52, 0.7), (2.0, 2.0, 0.9)]
    w = lm.semantic_weights(rows, 80)
    expect = np.zeros(80)
    for f in range(80):
        for s, e, wt in rows:
            if e > s and math.floor(s * 30) <= f < math.ceil(e * 30):
                expect[f] = max(expect[f], np.float32(wt))
    assert w.dtype == np.float32
    np.testing.assert_array_equal(w, expect.astype(np.float32))
    assert w[15] == np.float32(0.3) and w[27] == np.float32(0.7) and w[45] == np.float32(0.7) and w[46] == 0


def test_read_sem_names_the_bad_line(tmp_path):
    sem = tmp_path / "bad.txt"
    sem.write_text("a\t0\t1\t1\t0.1\nb\tsoon\t2\t1\t0.2\n")
    with pytest.raises(InputError, match=r"bad.txt:2: expected numbers"):
        lm.read_sem(sem)
    with pytest.raises(InputError, match="no such semantic"):
        lm.read_sem(tmp_path / "none.txt")


def test_srgr_against_loops_and_it_can_exceed_one():
    rng = np.random.default_rng(6)
    gt = rng.normal(0, 0.3, (40, 55, 3))
    pred = gt + rng.normal(0, 0.07, gt.shape)
    w = np.float32(rng.uniform(0, 1, 40))
    hits = 0.0
    for t in range(40):
        for j in range(55):
            d = math.sqrt(sum((pred[t, j, c] - gt[t, j, c]) ** 2 for c in range(3)))
            if d < 0.1:
                hits += float(w[t]) / 0.1672
    assert rel(lm.srgr_rate(pred, gt, w), hits / (40 * 55)) < REL
    # every joint within 0.1 m and weights of 0.9: 0.9 / 0.1672 = 5.38, far above 1 (reproduced, not clipped)
    assert rel(lm.srgr_rate(gt, gt, np.full(40, 0.9, np.float32)), float(np.float32(0.9)) / 0.1672) < REL
    # over sequences: weighted by frames
    a, b = (pred[:10], gt[:10], w[:10]), (pred, gt, w)
    expect = (lm.srgr_rate(*a) * 10 + lm.srgr_rate(*b) * 40) / 50
    assert rel(lm.srgr([a, b]), expect) < REL


# ---------------------------------------------------------------- beat alignment
def ref_speed(x, fps=30.0):
    t = len(x)
    out = np.zeros((t, x.shape[1]))
    for i in range(t):
        if i == 0:
            v = (x[1] - x[0]) * fps
        elif i == t - 1:
            v = (x[t - 1] - x[t - 2]) * fps
        else:
            v = (x[i + 1] - x[i - 1]) * fps / 2
        out[i] = np.sqrt((v ** 2).sum(axis=1))
    return out


def ref_minima(v, order):
    n = len(v)
    return [i for i in range(n) if all(v[i] < v[min(max(i + k, 0), n - 1)] for k in range(-order, order + 1) if k)]


def test_joint_speed_and_mean_velocity():
    rng = np.random.default_rng(7)
    a, b = rng.normal(0, 0.1, (25, 55, 3)), rng.normal(0, 0.1, (18, 55, 3))
    np.testing.assert_allclose(bc.joint_speed(a), ref_speed(a), rtol=REL)
    expect = np.concatenate([ref_speed(a), ref_speed(b)]).mean(axis=0)
    np.testing.assert_allclose(bc.mean_velocity([a, b]), expect, rtol=REL)


def test_motion_beats_threshold_tested_two_seconds_before():
    t = 300
    i = np.arange(t)
    speed = 1.0 - 0.5 * np.exp(-((i - 150.25) ** 2) / 8)   # one clear minimum near absolute frame 150 ...
    speed[85:96] = 0.05                                     # ... while the frames 2 s before it are slow
    # joint 3 moves along x with these per-frame steps
    x = np.zeros((t, 55, 3))
    x[:, 3, 0] = np.cumsum(speed) / 30.0
    v = ref_speed(x)[:, 3]
    mean_vel = np.ones(55)
    published = bc.motion_beats(x, mean_vel, 60, t - 60)[3]
    cleaner = bc.motion_beats(x, mean_vel, 60, t - 60, published_threshold_frame=False)[3]
    minima = ref_minima(v[60:t - 60], 7)
    assert set(published) == {i for i in minima if v[i] > 0.1}
    assert set(cleaner) == {i for i in minima if v[i + 60] > 0.1}
    assert set(published) != set(cleaner)
    # the minimum at absolute frame 150 is dropped under the published rule (frame 90 is slow), kept otherwise
    assert not any(abs(i + 60 - 150) <= 1 for i in published) and any(abs(i + 60 - 150) <= 1 for i in cleaner)


def test_hit_rate_and_beat_alignment_against_loops():
    rng = np.random.default_rng(8)
    onsets = np.sort(rng.uniform(0, 8, 15))
    beats = [np.sort(rng.choice(240, 12, replace=False)) if j % 4 else np.array([], int) for j in range(55)]

    def h(a, b):
        return sum(math.exp(-min(abs(x - y) for x in a) ** 2 / (2 * 0.3 ** 2)) for y in b) / len(b)

    a2m = sum(h(beats[j] / 30, onsets) for j in bc.UPPER_BODY if len(beats[j])) / 13
    m2a = sum(h(onsets, beats[j] / 30) for j in bc.UPPER_BODY if len(beats[j])) / 13
    got = bc.beat_alignment(onsets, beats)
    assert rel(got[0], a2m) < REL and rel(got[1], m2a) < REL
    with pytest.raises(InputError, match="no onsets"):
        bc.beat_alignment(np.array([]), beats)


def click_track(seconds, times, sr=16000, seed=0):
    rng = np.random.default_rng(seed)
    y = np.zeros(int(seconds * sr), np.float32)
    for t in times:
        k = int(t * sr)
        y[k:k + 480] += (rng.normal(0, 0.6, 480) * np.exp(-np.arange(480) / 90)).astype(np.float32)
    return y


def test_audio_onsets_use_librosa_with_the_scripts_parameters():
    import librosa

    times = np.arange(0.5, 9.5, 0.6)
    y = click_track(10, times)
    got = bc.audio_onsets(y, 32000, 144000)
    direct = librosa.onset.onset_detect(y=y[32000:144000], sr=16000, hop_length=512, units="time")
    np.testing.assert_array_equal(got, direct)
    inside = times[(times >= 2) & (times < 9)] - 2
    assert len(got) >= len(inside) - 1
    assert max(min(abs(o - t) for o in got) for t in inside) < 0.07   # within ~2 hops of each click


def test_sequence_bc_cuts_two_seconds_and_weights(tmp_path):
    rng = np.random.default_rng(9)
    t = 330
    pos = np.cumsum(rng.normal(0, 0.01, (t, 55, 3)), axis=0)
    y = click_track(t / 30, np.arange(0.4, t / 30, 0.5))
    mean_vel = np.full(55, 0.2)
    a2m, m2a, w = bc.sequence_bc(pos, y, mean_vel)
    onsets = bc.audio_onsets(y, 32000, int((t - 60) / 30 * 16000))
    v = ref_speed(pos) / 0.2
    beats = []
    for j in range(55):
        beats.append(np.array([i for i in ref_minima(v[60:t - 60, j], 7) if v[i, j] > 0.1], int))
    ref = bc.beat_alignment(onsets, beats)
    assert w == t - 120 and rel(a2m, ref[0]) < REL and rel(m2a, ref[1]) < REL
    with pytest.raises(InputError, match="no onsets"):
        bc.sequence_bc(pos, np.zeros_like(y), mean_vel, source="silent.wav")
    with pytest.raises(InputError, match="more than 120 frames"):
        bc.sequence_bc(pos[:100], y, mean_vel)


def test_read_mean_velocity_checks_shape(tmp_path):
    np.save(tmp_path / "ok.npy", np.linspace(0.1, 1, 55).astype(np.float32))
    np.testing.assert_allclose(bc.read_mean_velocity(tmp_path / "ok.npy"), np.linspace(0.1, 1, 55), rtol=1e-6)
    np.save(tmp_path / "bad.npy", np.ones(52))
    with pytest.raises(InputError, match=r"bad.npy: bc-mean-vel: expected 55 positive"):
        bc.read_mean_velocity(tmp_path / "bad.npy")
