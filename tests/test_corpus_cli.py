"""``evalsuite corpus info|split`` through the top-level command."""
from __future__ import annotations

import json

import pytest
from click.testing import CliRunner
from corpus_helpers import bvh, genea2020, synth, wav

from evalsuite.cli import main


def _run(*args):
    return CliRunner().invoke(main, ["corpus", *map(str, args)])


def test_info_prints_layout_splits_speakers_rates_and_what_is_missing(tmp_path):
    root = synth(tmp_path / "syn")
    r = _run("info", root)
    assert r.exit_code == 0, r.output
    lines = r.output.splitlines()
    assert "layout:     genea2023" in lines
    assert "segments:   4, 12.0 s (0:00:12.0)" in lines
    assert "  train      2 segments, 6.0 s (0:00:06.0), 2 speakers" in lines
    assert "speakers:   3 (01, 02, 03)" in lines
    assert "audio:      16000 Hz x4; channels 1 x4" in lines
    assert "motion:     30 fps x3" in lines
    assert "missing motion: 1 segments (tst_2023_v0_000)" in lines
    assert "interlocutor: 4 segments" in lines
    assert any(line.startswith('corpus.json: {"model": "synthetic speaker v1"') for line in lines)
    assert "metadata:   trn/metadata.csv, tst/metadata.csv, val/metadata.csv" in lines
    for split in ("trn", "val", "tst"):
        (root / split / "metadata.csv").unlink()
    lines = _run("info", root).output.splitlines()
    assert "speakers:   0" in lines and "metadata:   none found (speaker ids come from metadata.csv in each split " \
        "folder or at the root)" in lines


def test_info_json_and_mismatch_report(tmp_path):
    root = genea2020(tmp_path / "g20")
    bvh(root / "Motion" / "Recording_002.bvh", 9.0, fps=60)
    r = _run("info", root, "--json")
    assert r.exit_code == 0, r.output
    data = json.loads(r.output)
    assert data["layout"] == "genea2020" and data["segments"] == 2 and data["motion_fps"] == {"60": 2}
    assert data["audio_rates"] == {"44100": 2}
    (m,) = data["mismatches"]
    assert (m["segment"], m["audio_duration"], m["motion_duration"], m["action"]) == ("Recording_002", 4.0, 9.0, "warn")
    text = _run("info", root).output
    assert "MISMATCH Recording_002: audio Audio/Recording_002.wav 4.000 s, motion Motion/Recording_002.bvh 9.000 s" \
        in text
    r = _run("info", root, "--on-mismatch", "error")
    assert r.exit_code == 1 and "lasts 4.000 s but motion Motion/Recording_002.bvh lasts 9.000 s" in r.output
    assert "Traceback" not in r.output


def test_split_is_reproducible_by_seed_and_keeps_speakers_disjoint(tmp_path):
    root = tmp_path / "takes"
    for k in range(10):
        wav(root / f"t{k}.wav", 1.0, rate=8000)
    (root / "splits.csv").write_text("segment,split,speaker\n" + "".join(f"t{k},train,p{k % 5}\n" for k in range(10)))
    outs = []
    for name in ("a.csv", "b.csv"):
        r = _run("split", root, "--val", "0.2", "--test", "0.2", "--seed", "4", "-o", tmp_path / name)
        assert r.exit_code == 0, r.output
        assert "speakers disjoint, seed 4" in r.output
        outs.append((tmp_path / name).read_text())
    assert outs[0] == outs[1] and outs[0].startswith("segment,split\n")
    rows = dict(line.split(",") for line in outs[0].splitlines()[1:])
    splits_of = {}
    for k in range(10):
        splits_of.setdefault(f"p{k % 5}", set()).add(rows[f"t{k}"])
    assert all(len(v) == 1 for v in splits_of.values())
    assert {v for s in splits_of.values() for v in s} == {"train", "val", "test"}


def test_help_everywhere_with_examples_and_errors_without_traceback(tmp_path):
    for args in (["--help"], ["info", "--help"], ["split", "--help"]):
        r = _run(*args)
        assert r.exit_code == 0 and "Examples:" in r.output
    r = _run("info", tmp_path / "nowhere")
    assert r.exit_code == 1 and "nowhere: no such corpus folder" in r.output
    assert "corpus" in CliRunner().invoke(main, ["--help"]).output


def test_a_subcommand_is_one_entry_in_the_lazy_table(monkeypatch):
    from evalsuite.corpus import cli

    monkeypatch.setitem(cli.SUBCOMMANDS, "hello", "evalsuite.corpus.cli:_hello_for_test")
    monkeypatch.setitem(cli.SUBCOMMANDS, "absent", "evalsuite.corpus.no_such_module:cmd")
    import click

    @click.command()
    def _hello_for_test():
        """Say hello."""
        click.echo("hello from the table")

    monkeypatch.setattr(cli, "_hello_for_test", _hello_for_test, raising=False)
    r = _run("--help")
    assert "hello" in r.output and "absent" not in r.output
    assert _run("hello").output == "hello from the table\n"


def _mismatched_corpus(tmp_path):
    root = genea2020(tmp_path / "g20")
    bvh(root / "Motion" / "Recording_002.bvh", 9.0, fps=60)  # the audio lasts 4 s
    return root


def test_every_command_that_loads_a_corpus_has_the_on_mismatch_its_error_names(tmp_path):
    from evalsuite.corpus import load_corpus
    from evalsuite.errors import InputError

    root = _mismatched_corpus(tmp_path)
    hint = "rerun with --on-mismatch warn (keep such segments, listed) or --on-mismatch skip (leave them out)"
    commands = [("generate", "-g", "natural", "--corpus", root, "--split", "all"),
                ("train", "-g", "aud2pose", "--corpus", root),
                ("score", "-r", f"NA={root / 'Motion'}", f"B={root / 'Motion'}", "--corpus", root, "--quiet",
                 "--no-figures"),
                ("validate-metrics", "--corpus", root, "--no-fgd", "--quiet"),
                ("corpus", "split", root), ("corpus", "info", root, "--on-mismatch", "error")]
    for i, args in enumerate(commands):
        r = CliRunner().invoke(main, [*map(str, args), "-o", str(tmp_path / f"out{i}")] if args[0] != "corpus"
                               else [*map(str, args)])
        assert r.exit_code == 1 and "Traceback" not in r.output, (args, r.output)
        assert "segment 'Recording_002': audio Audio/Recording_002.wav lasts 4.000 s" in r.output and hint in r.output
        help_text = CliRunner().invoke(main, [*map(str, args[:2 if args[0] == "corpus" else 1]), "--help"]).output
        assert "--on-mismatch [error|warn|skip]" in help_text, args
    with pytest.raises(InputError, match=r"load with on_mismatch='warn' or 'skip' \(`evalsuite corpus info DIR`"):
        load_corpus(root)  # outside a command: the Python argument


def test_on_mismatch_skip_lets_generate_and_score_use_the_rest(tmp_path):
    root = _mismatched_corpus(tmp_path)
    r = CliRunner().invoke(main, ["generate", "-g", "natural", "--corpus", str(root), "--split", "all",
                                  "--on-mismatch", "skip", "-o", str(tmp_path / "nat")])
    assert r.exit_code == 0, r.output
    assert sorted(p.name for p in (tmp_path / "nat").glob("*.bvh")) == ["Recording_001.bvh"]
    r = CliRunner().invoke(main, ["score", "-r", f"NA={tmp_path / 'nat'}", f"B={tmp_path / 'nat'}", "--corpus",
                                  str(root), "--on-mismatch", "skip", "-m", "coupling", "--quiet", "--no-figures",
                                  "-o", str(tmp_path / "scores")])
    assert r.exit_code == 0, r.output
    assert (tmp_path / "scores" / "summary.csv").is_file()
