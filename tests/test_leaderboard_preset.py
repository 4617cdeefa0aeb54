"""Tests for evalsuite.leaderboard.score and ``evalsuite score --preset genea-leaderboard``: naming, both sampling
rules, both FGD pairings, the script's quirks, and end-to-end runs (CLI and Python API) on a synthetic BEAT2
folder made here (fake SMPL-X model with random numbers, click-track speech, sem files)."""
from __future__ import annotations

import shutil

import numpy as np
import pandas as pd
import pytest
import soundfile as sf
from click.testing import CliRunner
from smplx_helpers import fake_smplx_model, write_fake_beat2_recording
from test_leaderboard_metrics import click_track

from evalsuite.cli import main
from evalsuite.errors import InputError
from evalsuite.leaderboard import beats as bc
from evalsuite.leaderboard import evaluate_leaderboard, score_leaderboard
from evalsuite.leaderboard import metrics as lm
from evalsuite.leaderboard.score import METRICS
from evalsuite.motion.smplx import SmplxData, read_smplx
from evalsuite.motion.smplx_body import smplx_positions

IDS = ["2_scott_0_1_1", "2_scott_0_2_2", "4_lawrence_0_3_3"]
SAMPLES = (2, 10, 3)          # text order: _10, _2, _3 -> "fixed" takes _10
REL = 1e-6


def rel(a, b):
    return abs(a - b) / max(abs(b), 1e-12)


@pytest.fixture(scope="module")
def beat2(tmp_path_factory):
    root = tmp_path_factory.mktemp("lb")
    lang = root / "beat_english_v2.0.0"
    for sub in ("smplxflame_30", "wave16k", "sem"):
        (lang / sub).mkdir(parents=True)
    rows = ["id,type"] + [f"{v},test" for v in IDS] + ["2_scott_0_9_9,train"]
    (lang / "train_test_split.csv").write_text("\n".join(rows) + "\n")
    write_fake_beat2_recording(lang / "smplxflame_30" / "2_scott_0_9_9.npz", n_frames=150, seed=99)  # train: unused
    for i, vid in enumerate(IDS):
        n = 200 + 25 * i
        write_fake_beat2_recording(lang / "smplxflame_30" / f"{vid}.npz", n_frames=n, seed=i)
        sf.write(lang / "wave16k" / f"{vid}.wav", click_track(n / 30, np.arange(0.3, n / 30, 0.45), seed=i), 16000)
        (lang / "sem" / f"{vid}.txt").write_text(f"a\t0.5\t2.5\t2.0\t0.4\tx\nb\t2.1\t{n / 60:.2f}\t1\t0.9\ty\n")
    system = root / "sys"
    system.mkdir()
    for i, vid in enumerate(IDS):
        base = np.load(lang / "smplxflame_30" / f"{vid}.npz")["poses"]
        for k in SAMPLES:
            p = base + np.random.default_rng(10 * i + k).normal(0, 0.04 * k, base.shape)
            write_fake_beat2_recording(system / f"{vid}_{k}.npz", poses=p[: len(p) - 3 * k], seed=k)
    model = fake_smplx_model(root / "SMPLX_FAKE.npz", n_betas=300)
    np.save(root / "mean_vel.npy", np.linspace(0.3, 0.6, 55).astype(np.float32))
    return {"root": root, "lang": lang, "sys": system, "model": model, "mean_vel": root / "mean_vel.npy"}


@pytest.fixture(scope="module")
def fgd_model(tmp_path_factory):
    import torch

    from evalsuite.learned import emage_aeskconv as ea

    root = tmp_path_factory.mktemp("fgd")
    torch.manual_seed(0)
    torch.save({"model_state": ea.AESKConv().state_dict()}, root / "ck.bin")
    ea.import_emage(root / "ck.bin", root / "m.pt")
    model, _ = ea.load_emage_model(root / "m.pt")
    return root / "m.pt", lambda poses: ea.aeskconv_latents(model, ea.axis_angle_to_rot6d(poses))


def gt_poses(beat2):
    return {v: read_smplx(beat2["lang"] / "smplxflame_30" / f"{v}.npz") for v in IDS}


def sample_poses(beat2, order):
    return {v: [read_smplx(beat2["sys"] / f"{v}_{k}.npz").poses for k in order] for v in IDS}


def value(frame, metric, condition="sys"):
    return float(frame[(frame.condition == condition) & (frame.metric == metric)].value.iloc[0])


def test_fixed_takes_the_first_sample_in_text_order(beat2):
    frame = score_leaderboard(beat2["lang"], [beat2["sys"]], metrics=["fid_g", "fid_k", "var_k"])
    gt = [d.poses for d in gt_poses(beat2).values()]
    first = [s[0] for s in sample_poses(beat2, [10]).values()]     # _10 before _2 in text order
    lowest = [s[0] for s in sample_poses(beat2, [2]).values()]
    assert rel(value(frame, "fid_g"), lm.fid_g(gt, first)) < REL
    assert rel(value(frame, "fid_g"), lm.fid_g(gt, lowest)) > 1e-3
    assert rel(value(frame, "fid_k"), lm.fid_k(gt, first)) < REL
    assert rel(value(frame, "var_k"), lm.var_k(first)) < REL
    assert set(frame.samples) == {"first"}


def test_all_pools_every_sample(beat2):
    frame = score_leaderboard(beat2["lang"], {"sys": beat2["sys"]}, sampling="all",
                              metrics=["fid_g", "var_k", "sample_div"])
    gt = [d.poses for d in gt_poses(beat2).values()]
    every = [p for s in sample_poses(beat2, [10, 2, 3]).values() for p in s]
    assert rel(value(frame, "fid_g"), lm.fid_g(gt, every)) < REL
    assert rel(value(frame, "var_k"), lm.var_k(every)) < REL
    assert rel(value(frame, "sample_div"), lm.sample_div(sample_poses(beat2, [10, 2, 3]))) < REL
    assert dict(zip(frame.metric, frame.samples)) == {"fid_g": "all", "var_k": "each", "sample_div": "all"}


@pytest.mark.parametrize("pairing", ["published", "corrected"])
def test_fgd_pairings(beat2, fgd_model, pairing):
    path, encode = fgd_model
    gt = gt_poses(beat2)
    a, b = [], []
    for vid, samples in sample_poses(beat2, [10, 2, 3]).items():
        g = gt[vid].poses
        for i, p in enumerate(samples):
            t = min(len(g), len(p))
            if i == 0:
                a.append(encode(g[:t]))
                b.append(encode(p[:t]))
            elif pairing == "published":
                a.append(encode(p[:t]))     # samples 2..k join the ground truth's side
            else:
                b.append(encode(p[:t]))
    expect = lm.frechet_fgd(np.concatenate(a), np.concatenate(b))
    frame = score_leaderboard(beat2["lang"], [beat2["sys"]], sampling="all", fgd_pairing=pairing, fgd_model=path,
                              metrics=["fgd"])
    assert rel(value(frame, "fgd"), expect) < REL
    fixed = score_leaderboard(beat2["lang"], [beat2["sys"]], fgd_pairing=pairing, fgd_model=path, metrics=["fgd"])
    g0 = {v: gt[v].poses for v in IDS}
    firsts = sample_poses(beat2, [10])
    a0 = [encode(g0[v][:min(len(g0[v]), len(firsts[v][0]))]) for v in IDS]
    b0 = [encode(firsts[v][0][:len(g0[v])]) for v in IDS]
    assert rel(value(fixed, "fgd"), lm.frechet_fgd(np.concatenate(a0), np.concatenate(b0))) < REL


def positions(poses, betas, model):
    return smplx_positions(SmplxData(poses, np.zeros((len(poses), 3)), betas), model, mode="leaderboard", betas=betas)


def test_position_metrics_use_gt_betas_and_the_overlap(beat2):
    res = evaluate_leaderboard(beat2["lang"], [beat2["sys"]], sampling="all", smplx_model=beat2["model"],
                               mean_vel=beat2["mean_vel"], metrics=["div", "srgr", "bc_a2m", "bc_m2a"])
    gt = gt_poses(beat2)
    mean_vel = np.load(beat2["mean_vel"]).astype(np.float64)
    pos_list, srgr_seqs, bcs = [], [], []
    for vid, samples in sample_poses(beat2, [10, 2, 3]).items():
        g, betas = gt[vid].poses, gt[vid].betas
        weights = lm.read_sem(beat2["lang"] / "sem" / f"{vid}.txt")
        wave = bc.load_wave(beat2["lang"] / "wave16k" / f"{vid}.wav")
        for p in samples:
            t = min(len(g), len(p))
            pos = positions(p[:t], betas, beat2["model"])
            pos_list.append(pos)
            srgr_seqs.append((pos, positions(g[:t], betas, beat2["model"]), lm.semantic_weights(weights, t)))
            bcs.append(bc.sequence_bc(pos, wave, mean_vel))
    s = res.summary
    assert rel(value(s, "div"), lm.div(pos_list)) < REL
    assert rel(value(s, "srgr"), lm.srgr(srgr_seqs)) < REL
    w = sum(x[2] for x in bcs)
    assert rel(value(s, "bc_a2m"), sum(x[0] * x[2] for x in bcs) / w) < REL
    assert rel(value(s, "bc_m2a"), sum(x[1] * x[2] for x in bcs) / w) < REL
    assert len(res.per_sequence[res.per_sequence.metric == "div"]) == len(IDS) * len(SAMPLES)


def test_without_a_model_rotation_metrics_run_and_position_metrics_say_why(beat2, monkeypatch):
    monkeypatch.delenv("EVALSUITE_SMPLX_MODEL", raising=False)
    res = evaluate_leaderboard(beat2["lang"], [beat2["sys"]], mean_vel=beat2["mean_vel"])
    assert set(res.summary.metric) == {"fid_g", "fid_k", "var_k", "sample_div"}
    assert any(i.startswith("div left out") and "--smplx-model" in i and "smpl-x.is.tue.mpg.de" in i
               for i in res.issues)
    assert any(i.startswith("fgd left out") and "--fgd" in i for i in res.issues)
    with pytest.raises(InputError, match="--smplx-model"):
        evaluate_leaderboard(beat2["lang"], [beat2["sys"]], metrics=["srgr"])


def make_system(beat2, tmp_path, name, edit):
    out = tmp_path / name
    shutil.copytree(beat2["sys"], out)
    edit(out)
    return out


def test_missing_and_extra_predictions_are_clear_errors(beat2, tmp_path):
    missing = make_system(beat2, tmp_path, "missing", lambda d: [f.unlink() for f in d.glob(f"{IDS[1]}_*.npz")])
    with pytest.raises(InputError, match=rf"no prediction for 1 ground-truth recording\(s\), e.g. {IDS[1]}"):
        score_leaderboard(beat2["lang"], [missing], metrics=["fid_g"])
    extra = make_system(beat2, tmp_path, "extra", lambda d: shutil.copy(d / f"{IDS[0]}_2.npz", d / "2_x_0_7_7_1.npz"))
    with pytest.raises(InputError, match="not in the ground truth, e.g. 2_x_0_7_7"):
        score_leaderboard(beat2["lang"], [extra], metrics=["fid_g"])


def test_nan_poses_read_as_zero_and_short_names_skipped(beat2, tmp_path):
    def edit(d):
        with np.load(d / f"{IDS[0]}_10.npz") as z:
            arrays = dict(z)
        arrays["poses"][5:9, 30:40] = np.nan
        np.savez(d / f"{IDS[0]}_10.npz", **arrays)
        arrays["poses"] = np.nan_to_num(arrays["poses"], nan=0.0)
        np.savez(tmp_path / "zeroed.npz", **arrays)
        shutil.copy(d / f"{IDS[1]}_2.npz", d / "short_name.npz")

    nan_sys = make_system(beat2, tmp_path, "nan", edit)
    zero_sys = make_system(beat2, tmp_path, "zero", lambda d: shutil.copy(tmp_path / "zeroed.npz",
                                                                         d / f"{IDS[0]}_10.npz"))
    res = evaluate_leaderboard(beat2["lang"], {"nan": nan_sys, "zero": zero_sys}, metrics=["fid_g", "var_k"])
    s = res.summary
    assert value(s, "fid_g", "nan") == value(s, "fid_g", "zero")
    assert any("fewer than five '_' tokens skipped" in i and "short_name.npz" in i for i in res.issues)


def test_length_warning_single_sample_and_sample_div_error(beat2, tmp_path):
    def edit(d):
        for f in d.glob("*.npz"):
            if not f.stem.endswith("_10"):
                f.unlink()
        with np.load(d / f"{IDS[2]}_10.npz") as z:
            arrays = dict(z)
        np.savez(d / f"{IDS[2]}_10.npz", **{k: (v[:120] if k in ("poses", "trans", "expressions") else v)
                                             for k, v in arrays.items()})

    single = make_system(beat2, tmp_path, "single", edit)
    res = evaluate_leaderboard(beat2["lang"], [single])
    assert "sample_div" not in set(res.summary.metric) and "fid_g" in set(res.summary.metric)
    assert any("sample_div left out" in i and "at least 2 samples" in i for i in res.issues)
    assert any(f"{IDS[2]}_10.npz: 120 frames against 250" in i and "more than 20%" in i for i in res.issues)
    with pytest.raises(InputError, match="at least 2 samples per recording"):
        evaluate_leaderboard(beat2["lang"], [single], metrics=["sample_div"])


def test_cli_preset_end_to_end_matches_python_api(beat2, fgd_model, tmp_path, monkeypatch):
    monkeypatch.delenv("EVALSUITE_SMPLX_MODEL", raising=False)   # --smplx-model sets it; restored afterwards
    out = tmp_path / "out"
    args = ["score", "--preset", "genea-leaderboard", "-r", str(beat2["lang"]), f"mine={beat2['sys']}", "-o", str(out),
            "--smplx-model", str(beat2["model"]), "--bc-mean-vel", str(beat2["mean_vel"]), "--fgd",
            str(fgd_model[0]), "--sampling", "all", "--fgd-pairing", "corrected", "--bootstrap", "5", "--quiet"]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 0, result.output
    summary = pd.read_csv(out / "summary.csv")
    assert list(summary.columns[:3]) == ["condition", "metric", "value"]
    assert list(summary.metric) == list(METRICS)
    assert dict(zip(summary.metric, summary.samples)) == {
        "fgd": "all", "fid_g": "all", "fid_k": "all", "var_k": "each", "sample_div": "all", "bc_a2m": "each",
        "bc_m2a": "each", "div": "each", "srgr": "each"}
    assert summary.ci_low.notna().all() and (summary.ci_low <= summary.ci_high).all()
    assert summary.set_index("metric").loc[["fgd", "fid_g", "fid_k"], "lb_ci_low"].notna().all()
    api = score_leaderboard(beat2["lang"], {"mine": beat2["sys"]}, smplx_model=beat2["model"],
                            mean_vel=beat2["mean_vel"], fgd_model=fgd_model[0], sampling="all",
                            fgd_pairing="corrected")
    for m in METRICS:
        assert rel(value(summary, m, "mine"), value(api, m, "mine")) < 1e-9
    for name in ("per_sequence.csv", "results.json", "summary.md", "summary.tex"):
        assert (out / name).is_file()


def test_cli_preset_errors_are_one_line(beat2, tmp_path):
    r = CliRunner().invoke(main, ["score", "--preset", "genea-leaderboard", "-r", str(beat2["lang"]),
                                  str(tmp_path / "nowhere"), "-o", str(tmp_path / "o")])
    assert r.exit_code != 0
    assert "no such folder of predictions" in r.output and "Traceback" not in r.output


def test_mean_velocity_of_a_training_split(beat2):
    from test_leaderboard_metrics import ref_speed

    from evalsuite.leaderboard.meanvel import mean_velocity_of_split

    got = mean_velocity_of_split(beat2["lang"], beat2["model"], split="train")
    data = read_smplx(beat2["lang"] / "smplxflame_30" / "2_scott_0_9_9.npz")
    expect = ref_speed(smplx_positions(data, beat2["model"], mode="full")).mean(axis=0)  # the one train file
    assert got.shape == (55,)
    np.testing.assert_allclose(got, expect, rtol=REL)
    every = mean_velocity_of_split(beat2["lang"], beat2["model"], split=None)
    assert not np.allclose(every, got)
    with pytest.raises(InputError, match="no recordings of the 'val' split"):
        mean_velocity_of_split(beat2["lang"], beat2["model"], split="val")


def test_a_156_wide_prediction_is_refused(beat2, tmp_path):
    def edit(d):
        with np.load(d / f"{IDS[0]}_10.npz") as z:
            arrays = dict(z)
        arrays["poses"] = arrays["poses"][:, :156]
        np.savez(d / f"{IDS[0]}_10.npz", **arrays)

    narrow = make_system(beat2, tmp_path, "narrow", edit)
    with pytest.raises(InputError, match=r"poses: poses are 156 wide; .* \(T, 165\)"):
        score_leaderboard(beat2["lang"], [narrow], metrics=["fid_g"])
