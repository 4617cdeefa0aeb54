"""`evalsuite score` end to end on real mocap fixtures, values checked against independent computations."""
import json
import shutil
import sys

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner
from scipy.io import wavfile

import evalsuite
from evalsuite.cli import main
from evalsuite.metrics.frechet import frechet_distance_samples
from evalsuite.motion.io import save_motion
from evalsuite.motion.ops import resample
from evalsuite.motion.samples import sample_path


@pytest.fixture(scope="module")
def folders(tmp_path_factory):
    """natural/jitter/smoothed/static/mismatched folders of 4 mocapbank segments (the demo's conditions)."""
    from evalsuite.metrics.demo import build_conditions

    root = tmp_path_factory.mktemp("score")
    return build_conditions(root, seed=3)


def run(args, ok=True):
    result = CliRunner().invoke(main, ["score", *map(str, args)])
    if ok:
        assert result.exit_code == 0, result.output + repr(result.exception)
    return result


def _positions(folder):
    return {p.stem: evalsuite.load_motion(p).positions() for p in sorted(folder.glob("*.bvh"))}


def _value(summary, cond, metric):
    row = summary[(summary.condition == cond) & (summary.metric == metric)]
    assert len(row) == 1, (cond, metric)
    return row.iloc[0]


def test_score_end_to_end_matches_independent_computation(folders, tmp_path):
    out = tmp_path / "out"
    res = run(["-r", f"natural={folders['natural']}", f"jitter={folders['jitter']}",
               f"smoothed={folders['smoothed']}", "--quiet", "-o", out])
    summary = pd.read_csv(out / "summary.csv")
    assert list(summary.columns[:6]) == ["condition", "metric", "value", "unit", "ci_low", "ci_high"]
    prov = json.loads((out / "results.json").read_text())["provenance"]
    edges = {q: np.asarray(e) for q, e in prov["histogram_edges"].items()}
    fps = 30.0
    nat = _positions(folders["natural"])
    for cond in ("natural", "jitter", "smoothed"):
        gen = _positions(folders[cond])
        names = sorted(gen)
        # kinematics: per-sequence mean over joints of mean_t ||Δ^n x|| fps^n; mean and sample std across sequences
        for metric, n in (("speed", 1), ("acceleration", 2), ("jerk", 3)):
            per_seq = [np.mean(np.linalg.norm(np.diff(gen[s], n=n, axis=0), axis=2), axis=0).mean() * fps ** n
                       for s in names]
            row = _value(summary, cond, metric)
            assert row.value == pytest.approx(np.mean(per_seq), rel=1e-9)
            assert row["std"] == pytest.approx(np.std(per_seq, ddof=1), rel=1e-9)
            assert row.unit == {1: "units/s", 2: "units/s^2", 3: "units/s^3"}[n]
        # pooled Hellinger with the overflow bin as an ordinary bin
        for metric, n in (("hellinger_speed", 1), ("hellinger_acceleration", 2)):
            def pooled(seqs):
                vals = np.concatenate([np.linalg.norm(np.diff(seqs[s], n=n, axis=0), axis=2).ravel() * fps ** n
                                       for s in names])
                h, _ = np.histogram(vals, bins=edges[metric.split("_")[1]])
                return np.append(h, np.sum(vals > edges[metric.split("_")[1]][-1]))
            p, q = pooled(gen), pooled(nat)
            expected = np.sqrt(1 - np.sum(np.sqrt(p / p.sum() * q / q.sum())))
            assert _value(summary, cond, metric).value == pytest.approx(expected, abs=1e-7)
        ape = [np.linalg.norm(gen[s] - nat[s], axis=2).mean() for s in names]
        assert _value(summary, cond, "ape").value == pytest.approx(np.mean(ape), rel=1e-9, abs=1e-12)
        mae = [np.abs(gen[s] - nat[s]).mean() for s in names]
        assert _value(summary, cond, "mae").value == pytest.approx(np.mean(mae), rel=1e-9, abs=1e-12)
        flat = lambda d: np.concatenate([d[s].reshape(len(d[s]), -1) for s in names])  # noqa: E731
        assert _value(summary, cond, "fd_g").value == pytest.approx(
            frechet_distance_samples(flat(nat), flat(gen)), rel=1e-4, abs=1e-4)  # near-singular covariances
        l1 = sum(np.abs(gen[s].reshape(len(gen[s]), -1) - gen[s].reshape(len(gen[s]), -1).mean(0)).sum()
                 for s in names) / sum(len(gen[s]) for s in names)
        assert _value(summary, cond, "l1div").value == pytest.approx(l1, rel=1e-9)
    assert _value(summary, "jitter", "jerk").value > 10 * _value(summary, "natural", "jerk").value
    assert _value(summary, "smoothed", "jerk").value < _value(summary, "natural", "jerk").value
    assert _value(summary, "natural", "hellinger_speed").value == 0.0
    assert _value(summary, "jitter", "clipped_speed").value > 0.0
    assert "hellinger_speed[wrists]" in set(summary.metric)
    # the other outputs
    for name in ("per_sequence.csv", "per_joint.csv", "histograms.csv", "summary.md", "summary.tex"):
        assert (out / name).stat().st_size > 0
    per_joint = pd.read_csv(out / "per_joint.csv")
    assert set(per_joint.joint) == set(evalsuite.load_motion(sample_path("mocapbank")).joint_names)
    for ext in ("png", "svg"):
        assert (out / "figures" / f"hist_speed_all.{ext}").exists()
        assert (out / "figures" / f"wrist_distribution.{ext}").exists()
    assert prov["fps"] == 30.0
    assert prov["convention"]["name"] == "default"
    f = next(iter(sorted(folders["jitter"].glob("*.bvh"))))
    import hashlib
    assert prov["files"]["jitter"][f.stem]["sha256"] == hashlib.sha256(f.read_bytes()).hexdigest()
    assert "\\toprule" in (out / "summary.tex").read_text()
    assert res.stdout == ""  # --quiet: no table, no progress bar
    # 4 sequences of 105 frames: every condition's Fréchet distances are flagged as too small a sample, in one
    # line per message that names the conditions it applies to
    line = next(x for x in res.stderr.splitlines() if "fd_g: 4 sequence(s) on a side (fewer than 10)" in x)
    assert "jitter" in line and "(conditions " in line
    assert all(line.startswith("warning: ") for line in res.stderr.splitlines())


def test_table_is_printed_with_units_and_direction(folders, tmp_path):
    res = run(["-r", folders["natural"], folders["static"], "-m", "kinematics", "-o", tmp_path / "o",
               "--no-figures"])
    assert "units/s^3" in res.output
    assert "≈nat" in res.output
    assert "static" in res.output
    assert "natural" in res.output


def _npy_folder(src, dst):
    dst.mkdir()
    for p in sorted(src.glob("*.bvh")):
        np.save(dst / f"{p.stem}.npy", evalsuite.load_motion(p).positions())


@pytest.mark.parametrize("convention,rate,top", [("genea2022", 30, 49), ("genea2020", 20, 59),
                                                  ("aud2repr2pose", None, 1)])
def test_reference_conventions_reproduce_the_reference_scripts(folders, tmp_path, convention, rate, top):
    nat_dir, gen_dir = tmp_path / "NA", tmp_path / "SA"
    _npy_folder(folders["natural"], nat_dir)
    _npy_folder(folders["smoothed"], gen_dir)
    out = tmp_path / "out"
    run(["-r", nat_dir, gen_dir, "--fps", 30, "--convention", convention, "-m", "kinematics,histograms",
         "--quiet", "--no-figures", "-o", out])
    summary = pd.read_csv(out / "summary.csv")
    scale = 1 if rate is None else rate

    def ref_velocity(data):  # calc_histogram.compute_velocity / calc_distance.compute_velocity, from their formula
        coords = data.reshape(data.shape[0], -1)
        vels = np.diff(coords, n=1, axis=0)
        norms = np.zeros((vels.shape[0], vels.shape[1] // 3))
        for i in range(vels.shape[0]):
            for j in range(vels.shape[1] // 3):
                norms[i, j] = np.linalg.norm(vels[i, 3 * j:3 * j + 3])
        return norms * scale

    def ref_total(folder, width=0.05):
        dists = np.concatenate([ref_velocity(np.load(f)) for f in sorted(folder.glob("*.npy"))])
        bins = np.arange(0, top + width, width)
        return np.sum([np.histogram(dists[:, i], bins=bins)[0] for i in range(dists.shape[1])], axis=0)

    h1, h2 = ref_total(nat_dir), ref_total(gen_dir)
    reference = np.sqrt(1.0 - np.sum(np.sqrt(h1 / np.sum(h1) * (h2 / np.sum(h2)))))
    assert _value(summary, "SA", "hellinger_speed").value == pytest.approx(reference, abs=1e-9)

    def ref_jerk(data):  # calk_jerk_or_acceleration.compute_jerks / calc_jerk.compute_jerks
        d = np.diff(data.reshape(data.shape[0], -1), n=3, axis=0)
        return np.mean(np.linalg.norm(d.reshape(len(d), -1, 3), axis=2), axis=0) * scale * scale * scale

    stats = [ref_jerk(np.load(f)) for f in sorted(gen_dir.glob("*.npy"))]
    row = _value(summary, "SA", "jerk")
    assert row.value == pytest.approx(np.mean(np.mean(stats, axis=1)), rel=1e-9)
    assert row["std"] == pytest.approx(np.std(np.mean(stats, axis=1)), rel=1e-9)   # np.std, ddof 0
    assert row.unit == ("units/frame^3" if rate is None else "units/s^3")
    clipped = _value(summary, "SA", "clipped_speed").value
    all_v = np.concatenate([ref_velocity(np.load(f)).ravel() for f in sorted(gen_dir.glob("*.npy"))])
    assert clipped == pytest.approx(np.mean(all_v > top), abs=1e-12)


@pytest.mark.slow
def test_local_jobs_and_dask_give_identical_numbers(folders, tmp_path):
    import distributed  # in the test extra
    args = ["-r", f"natural={folders['natural']}", f"jitter={folders['jitter']}", f"static={folders['static']}",
            "--bootstrap", 30, "--seed", 7, "--quiet", "--no-figures"]
    run(args + ["-o", tmp_path / "local"])
    run(args + ["--jobs", 2, "-o", tmp_path / "jobs"])
    # In-process workers behind a TCP scheduler: tasks still travel pickled from the CLI's client; the
    # --jobs run above covers separate worker processes.
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False, protocol="tcp",
                                  host="127.0.0.1", dashboard_address=None) as cluster:
        run(args + ["--dask", cluster.scheduler_address, "-o", tmp_path / "dask"])
    for name in ("summary.csv", "per_sequence.csv", "per_joint.csv", "histograms.csv"):
        local = (tmp_path / "local" / name).read_text()
        assert (tmp_path / "jobs" / name).read_text() == local, name
        assert (tmp_path / "dask" / name).read_text() == local, name
    summary = pd.read_csv(tmp_path / "local" / "summary.csv")
    row = _value(summary, "jitter", "speed")
    assert row.ci_low <= row.value <= row.ci_high


def test_beat_alignment_with_audio(folders, tmp_path):
    audio = tmp_path / "audio"
    audio.mkdir()
    rng = np.random.default_rng(0)
    for p in sorted(folders["natural"].glob("*.bvh")):
        sig = 0.001 * rng.normal(size=16000 * 4)
        for t in (0.5, 1.2, 2.0, 2.9):
            sig[int(t * 16000):int(t * 16000) + 200] += 0.8 * np.hanning(200)
        wavfile.write(audio / f"{p.stem}.wav", 16000, (sig * 32767).astype(np.int16))
    out = tmp_path / "out"
    run(["-r", folders["natural"], folders["jitter"], "--audio", audio, "-m", "beats", "--sigma", 0.2, "--quiet",
         "--no-figures", "-o", out])
    summary = pd.read_csv(out / "summary.csv")
    assert set(summary.metric) == {"beat_a2m", "beat_m2a"}
    assert summary.value.between(0, 1).all()


# --- bad input -------------------------------------------------------------------------------
def _copy(src, dst):
    shutil.copytree(src, dst)
    return dst


def test_missing_pair_is_reported_and_strict_refuses(folders, tmp_path):
    cond = _copy(folders["jitter"], tmp_path / "jitter")
    (cond / "seg01.bvh").unlink()
    res = run(["-r", folders["natural"], cond, "-m", "kinematics", "--no-figures", "-o", tmp_path / "o"])
    assert "no file for 1 of 4 natural sequences: seg01" in res.output
    summary = pd.read_csv(tmp_path / "o" / "summary.csv")
    assert _value(summary, "jitter", "speed").n == 3
    res = run(["-r", folders["natural"], cond, "--strict", "-o", tmp_path / "o2"], ok=False)
    assert res.exit_code == 1
    assert "seg01" in res.output
    assert "Traceback" not in res.output


def test_unreadable_file_does_not_lose_the_others(folders, tmp_path):
    cond = _copy(folders["jitter"], tmp_path / "jitter")
    (cond / "seg02.bvh").write_text("HIERARCHY\nROOT broken {\n")
    res = run(["-r", folders["natural"], cond, "-m", "kinematics,errors", "--no-figures", "-o", tmp_path / "o"])
    assert "skipped:" in res.output
    assert "seg02.bvh" in res.output
    summary = pd.read_csv(tmp_path / "o" / "summary.csv")
    assert _value(summary, "jitter", "ape").n == 3
    res = run(["-r", folders["natural"], cond, "--strict", "-o", tmp_path / "o2"], ok=False)
    assert res.exit_code == 1
    assert "seg02.bvh" in res.output


def test_mismatched_skeleton_is_a_clear_error(folders, tmp_path):
    other = tmp_path / "walkers"
    other.mkdir()
    walk = resample(evalsuite.load_motion(sample_path("walk01")), 30.0)
    for p in sorted(folders["natural"].glob("*.bvh")):
        save_motion(walk, other / p.name)
    res = run(["-r", folders["natural"], folders["jitter"], other, "-m", "kinematics", "--no-figures",
               "-o", tmp_path / "o"], ok=False)
    assert res.exit_code == 1
    assert "nothing could be scored for condition(s) walkers" in res.output
    assert "skeleton differs from the natural motion: missing joints" in res.output
    summary = pd.read_csv(tmp_path / "o" / "summary.csv")
    assert "walkers" not in set(summary.condition)
    assert "jitter" in set(summary.condition)
    res = run(["-r", folders["natural"], other, "--strict", "-o", tmp_path / "o2"], ok=False)
    assert res.exit_code == 1
    assert "missing joints" in res.output
    res = run(["-r", folders["natural"], folders["jitter"], "--joints", "NoSuchJoint", "-o", tmp_path / "o3"],
              ok=False)
    assert res.exit_code == 1
    assert "NoSuchJoint" in res.output


def test_fps_mismatch_is_refused_unless_resampled(folders, tmp_path):
    slow = tmp_path / "slow"
    slow.mkdir()
    for p in sorted(folders["smoothed"].glob("*.bvh")):
        save_motion(resample(evalsuite.load_motion(p), 20.0), slow / p.name)
    res = run(["-r", folders["natural"], slow, "-m", "kinematics", "-o", tmp_path / "o"], ok=False)
    assert res.exit_code == 1
    assert "frame rates differ" in res.output
    assert "--resample" in res.output
    assert "20" in res.output
    run(["-r", folders["natural"], slow, "-m", "kinematics", "--resample", 30, "--quiet", "--no-figures",
         "-o", tmp_path / "o2"])
    prov = json.loads((tmp_path / "o2" / "results.json").read_text())["provenance"]
    assert prov["fps"] == 30.0
    assert prov["resampled_to"] == 30.0


def test_empty_and_missing_folders_and_bad_options(folders, tmp_path):
    empty = tmp_path / "empty"
    empty.mkdir()
    res = run(["-r", folders["natural"], empty, "-o", tmp_path / "o"], ok=False)
    assert res.exit_code == 1
    assert "no motion files" in res.output
    res = run(["-r", tmp_path / "nope", folders["jitter"], "-o", tmp_path / "o"], ok=False)
    assert res.exit_code == 1
    assert "does not exist" in res.output
    res = run(["-r", folders["natural"], folders["jitter"], "-m", "nonsense", "-o", tmp_path / "o"], ok=False)
    assert res.exit_code == 1
    assert "unknown metric" in res.output
    res = run(["-r", folders["natural"], folders["jitter"], "-m", "beats", "-o", tmp_path / "o"], ok=False)
    assert res.exit_code == 1
    assert "--audio" in res.output
    res = run(["-r", folders["natural"], f"natural={folders['jitter']}", "-o", tmp_path / "o"], ok=False)
    assert res.exit_code == 1
    assert "unique" in res.output


def test_fgd_option_reports_missing_extra(folders, tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "evalsuite.learned.fgd", None)
    # an earlier test may have imported the family already: it must be re-imported (and fail) here
    monkeypatch.setitem(sys.modules, "evalsuite.learned.family", None)
    res = run(["-r", folders["natural"], folders["jitter"], "-m", "kinematics", "--no-figures", "--fgd",
               tmp_path / "model.pt", "-o", tmp_path / "o"], ok=False)
    assert res.exit_code == 1
    assert "learned" in res.output
    assert "Traceback" not in res.output


def test_fgd_option_scores_with_a_trained_model(folders, tmp_path):
    """A real (tiny) encoder trained by `evalsuite fgd train`, then `evalsuite score --fgd`."""
    model = tmp_path / "model.pt"
    res = CliRunner().invoke(main, ["fgd", "train", str(folders["natural"]), "-o", str(model), "--joints", "all", "--window", "20",
                                    "--epochs", "3", "--seed", "0", "--quiet"])
    assert res.exit_code == 0, res.output
    run(["-r", folders["natural"], folders["jitter"], folders["static"], "-m", "kinematics", "--no-figures",
         "--quiet", "--fgd", model, "--bootstrap", "20", "-o", tmp_path / "o2"])
    summary = pd.read_csv(tmp_path / "o2" / "summary.csv")
    static, jitter = _value(summary, "static", "fgd"), _value(summary, "jitter", "fgd")
    assert static.value > 0
    assert jitter.value >= 0
    assert static.ci_low <= static.ci_high
    assert not (summary.metric == "fgd_raw").any()  # raw-space FD only with --fgd-raw


@pytest.mark.slow
def test_demo_step_writes_condition_folders_and_scores_them(tmp_path):
    from evalsuite.metrics.demo import run as demo_run

    lines = []
    demo_run(tmp_path, lines.append)
    folders = sorted(p.name for p in (tmp_path / "conditions").iterdir())
    assert folders == ["jitter", "mismatched", "natural", "smoothed", "static"]
    names = {c: sorted(p.name for p in (tmp_path / "conditions" / c).glob("*.bvh")) for c in folders}
    assert all(v == names["natural"] for v in names.values())
    assert len(names["natural"]) == 4
    summary = pd.read_csv(tmp_path / "score" / "summary.csv")
    assert set(summary.condition) == set(folders)
    assert _value(summary, "static", "speed").value == 0.0
    assert _value(summary, "jitter", "jerk").value > _value(summary, "natural", "jerk").value
    assert _value(summary, "smoothed", "jerk").value < _value(summary, "natural", "jerk").value
    assert _value(summary, "mismatched", "ape").value > _value(summary, "smoothed", "ape").value
    assert any("jerk" in line for line in lines)
    assert (tmp_path / "score" / "figures" / "wrist_distribution.png").exists()


def test_condition_with_nothing_scored_fails_after_writing_the_rest(folders, tmp_path):
    """A condition whose only file is broken: the others are written, the exit code says it failed."""
    import shutil

    broken = tmp_path / "broken"
    broken.mkdir()
    for f in sorted(folders["natural"].glob("*.bvh")):
        (broken / f.name).write_text("HIERARCHY\nROOT Hips\n{\n")
    jitter = tmp_path / "jitter"
    shutil.copytree(folders["jitter"], jitter)
    res = run(["-r", folders["natural"], jitter, broken, "-m", "kinematics", "--no-figures", "--quiet",
               "-o", tmp_path / "o"], ok=False)
    assert res.exit_code == 1
    assert "nothing could be scored for condition(s) broken" in res.output
    assert "unexpected end of the hierarchy" in res.output  # the reason, per file
    summary = pd.read_csv(tmp_path / "o" / "summary.csv")
    assert set(summary.condition) == {"natural", "jitter"}


def test_fd_bootstrap_contains_its_estimate_reports_bias_progress_and_small_samples(folders, capsys):
    from evalsuite.metrics.engine import score_folders

    result = score_folders(f"natural={folders['natural']}", [f"jitter={folders['jitter']}",
                           f"smoothed={folders['smoothed']}", f"static={folders['static']}"],
                           metrics="distribution", bootstrap=100, seed=1, jobs=2, figures=False, progress=True)
    rows = [r for r in result.summary if r["metric"] in ("fd_g", "fd_k")]
    assert len(rows) == 8
    for r in rows:
        assert r["ci_low"] <= r["value"] <= r["ci_high"], r
        assert np.isfinite(r["bootstrap_bias"])
    natural = [r for r in rows if r["condition"] == "natural"]
    assert all((r["value"], r["ci_low"], r["ci_high"], r["bootstrap_bias"]) == (0, 0, 0, 0) for r in natural)
    # 4 sequences of 105 frames, 57 dimensions: both rules fire for every condition but the natural one
    for cond in ("jitter", "smoothed", "static"):
        for q, n in (("fd_g", 420), ("fd_k", 416)):
            assert any(i.startswith(f"{cond}: {q}: 4 sequence(s) on a side") for i in result.issues)
            assert any(i.startswith(f"{cond}: {q}: {n} reference and {n} condition") for i in result.issues)
    assert not any(i.startswith("natural:") for i in result.issues)
    err = capsys.readouterr().err
    assert "bootstrap" in err and "800/800" in err and "resample/s" in err   # 4 conditions x 2 metrics x 100
