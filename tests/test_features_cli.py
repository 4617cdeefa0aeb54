"""``evalsuite features``: the arrays it writes and their shapes, --list, and precise errors."""
from __future__ import annotations

import pathlib

import numpy as np
import pytest
from click.testing import CliRunner
from scipy.io import wavfile

from evalsuite.cli import main

SHARED = pathlib.Path(__file__).resolve().parents[1].parent / "shared"
DEMO_WAV = SHARED / "weights" / "aud2repr2pose-demo" / "audio" / "audio3_20sec.wav"


@pytest.fixture()
def wav(tmp_path) -> pathlib.Path:
    rate = 16000
    t = np.arange(2 * rate) / rate
    path = tmp_path / "speech.wav"
    wavfile.write(path, rate, np.round(8000 * np.sin(2 * np.pi * 140 * t)).astype(np.int16))
    return path


def run(*args):
    return CliRunner().invoke(main, ["features", *map(str, args)])


def test_list_names_every_recipe_with_rate_and_dimension():
    r = run("--list")
    assert r.exit_code == 0
    assert "mfcc_kucherenko\n    26 per frame, 20 fps; needs audio" in r.output
    assert "aud2repr2pose_demo_windows\n    61x30 per frame, 20 fps; needs audio, extra [praat]" in r.output
    assert "words_minilm\n    384 per frame, any fps; needs transcript, extra [text]" in r.output


@pytest.mark.parametrize("recipe,fps,shape", [("mfcc_kucherenko", None, (39, 26)), ("logmel_gesticulator", None, (41, 64)),
                                             ("pitch", None, (200, 1)), ("energy", 30, (60, 1)),
                                             ("mfcc_f0_ferstl", 20, (39, 27))])
def test_writes_the_array(tmp_path, wav, recipe, fps, shape):
    out = tmp_path / "out" / "x.npy"
    args = [wav, "--recipe", recipe, "-o", out, "--cache-dir", tmp_path / "cache"] + (["--fps", fps] if fps else [])
    r = run(*args)
    assert r.exit_code == 0, r.output
    x = np.load(out)
    assert x.shape == shape and x.dtype == np.float32
    assert f"{recipe} {shape}" in r.output
    assert ("by linear interpolation" in r.output) == (fps is not None)


def test_text_recipe_from_a_tsv_transcript_and_options(tmp_path, wav):
    tsv = tmp_path / "speech.tsv"
    tsv.write_text("start\tend\tword\n0.1\t0.5\thello\n0.6\t1.2\tworld.\n", encoding="utf-8")
    r = run(wav, "-r", "text_timing", "-t", tsv, "-o", tmp_path / "t.npy", "--no-cache")
    assert r.exit_code == 0, r.output
    assert np.load(tmp_path / "t.npy").shape == (40, 5)                       # the audio's 2 s at 20 fps
    r = run("-r", "words_hash", "-t", tsv, "-o", tmp_path / "w.npy", "--no-cache", "--option", "dim=8",
            "--n-frames", "50")
    assert r.exit_code == 0, r.output
    assert np.load(tmp_path / "w.npy").shape == (50, 8)


@pytest.mark.skipif(not DEMO_WAV.is_file(), reason=f"the demo's recording ({DEMO_WAV}) is not present")
def test_demo_windows_are_written_as_the_model_reads_them(tmp_path):
    pytest.importorskip("parselmouth", reason="the demo recipe needs the praat extra")
    r = run(DEMO_WAV, "-r", "aud2repr2pose_demo_windows", "-o", tmp_path / "w.npy", "--no-cache")
    assert r.exit_code == 0, r.output
    assert np.load(tmp_path / "w.npy").shape == (399, 61, 30)


def test_errors_are_one_line_without_traceback(tmp_path, wav):
    r = run(tmp_path / "missing.wav", "-r", "pitch", "-o", tmp_path / "x.npy")
    assert r.exit_code == 1 and "missing.wav: no such audio file" in r.output and "Traceback" not in r.output
    bad = tmp_path / "bad.wav"
    bad.write_text("not audio")
    r = run(bad, "-r", "pitch", "-o", tmp_path / "x.npy")
    assert r.exit_code == 1 and "bad.wav: not a readable WAV file" in r.output
    r = run(wav, "-r", "mfcc", "-o", tmp_path / "x.npy")
    assert r.exit_code == 1 and "recipe: unknown feature recipe 'mfcc'; known: aud2repr2pose_demo" in r.output
    tsv = tmp_path / "bad.tsv"
    tsv.write_text("0.1\t0.5\thello\n0.6\tlate\tworld\n")
    r = run(wav, "-r", "text_timing", "-t", tsv, "-o", tmp_path / "x.npy")
    assert r.exit_code == 1 and "bad.tsv:2: end (field 2): expected a time in seconds" in r.output
    r = run(wav, "-r", "pitch", "-o", tmp_path / "x.npy", "--option", "fmin")
    assert r.exit_code == 1 and "--option: expected KEY=VALUE, got 'fmin'" in r.output
    r = run(wav, "-r", "pitch")
    assert r.exit_code == 2 and "give -o OUT.npy" in r.output
