"""gesture2vec: spec, model folder, decoding options, and issue 15's learning criteria on a small synthetic corpus.

CI budget: most tests train on the ~6-minute corpus of ``g2v_mogan_helpers`` with a codebook of K = 48
(the criterion is relative: perplexity above 0.3 K) and compressed epochs (about a minute on 2 cores). The
translation model needs more data than that to learn the keywords, so the four learning criteria together are
tested on a 15-minute corpus with the defaults (K = 300; about 2 minutes); the 30-minute benchmark
(benchmarks/bench_generators.py) uses the defaults too.
"""
from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from click.testing import CliRunner
from g2v_mogan_helpers import synth_corpus

from evalsuite.cli import main
from evalsuite.generators import GeneratorError, find_generator

CONFIG = {"codebook": 48, "dae_epochs": 10, "vq_epochs": 12, "vq_decoder_epochs": 6, "translation_epochs": 60}


def test_spec_is_text_only_and_info_lists_citation_licence_deviations():
    entry = find_generator("gesture2vec")
    spec = entry.spec
    assert (spec.audio, spec.transcript, spec.word_timings) == ("none", "required", "required")
    assert spec.native_fps == 20.0 and spec.output == "bvh" and spec.trainable and spec.needs_model
    from evalsuite.generators.gesture2vec.info import DEVIATIONS

    assert spec.deviations[:len(DEVIATIONS)] == DEVIATIONS
    out = CliRunner().invoke(main, ["generators", "info", "gesture2vec"])
    assert out.exit_code == 0, out.output
    for text in ("Yazdian", "IROS 2022", "MIT", "retrieval", "rotation", "FastText"):
        assert text in out.output
    code = "import sys, evalsuite.generators.gesture2vec.plugin; print('torch' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True).stdout.strip() == "False"


def test_bad_options_are_named():
    from evalsuite.generators.gesture2vec.plugin import Gesture2Vec

    g = Gesture2Vec()
    g.configure({"decoding": "nearest"})
    with pytest.raises(GeneratorError, match="decoding must be generative or retrieval"):
        g._settings()
    g.configure({"size": "huge"})
    with pytest.raises(GeneratorError, match="size must be one of paper, cpu"):
        g._settings()


@pytest.mark.slow
def test_training_twice_with_one_seed_gives_identical_weights(tmp_path):
    from evalsuite.generators.checking import tiny_corpus
    from evalsuite.generators.training import train

    corpus = tiny_corpus(tmp_path / "tiny", n_segments=6, seconds=8.0)
    entry = find_generator("gesture2vec")
    cfg = {"words": "hash", "codebook": 8, "dae_epochs": 2, "vq_epochs": 2, "vq_decoder_epochs": 1,
           "translation_epochs": 2}
    shas = [train(entry, corpus, tmp_path / f"m{i}", seed=5, config=cfg, progress=False).meta["weights_sha256"]
            for i in range(2)]
    assert shas[0] == shas[1]
    other = train(entry, corpus, tmp_path / "m2", seed=6, config=cfg, progress=False).meta["weights_sha256"]
    assert other != shas[0]
    record = json.loads((tmp_path / "m0" / "model.json").read_text())
    assert record["weights_sha256"] == shas[0]
    for name in ("dae.pt", "vqdvae.pt", "translator.pt", "normalisers.npz", "code_counts.npy",
                 "retrieval_pool.npz", "settings.json", "representation.json", "template.bvh"):
        assert name in record["files"]


def test_budget_stops_the_stages_in_order(tmp_path):
    from evalsuite.generators.checking import tiny_corpus
    from evalsuite.generators.training import train

    corpus = tiny_corpus(tmp_path / "tiny", n_segments=6, seconds=8.0)
    cfg = {"words": "hash", "codebook": 8, "dae_epochs": 100000, "vq_epochs": 100000, "vq_decoder_epochs": 100000,
           "translation_epochs": 100000}
    res = train(find_generator("gesture2vec"), corpus, tmp_path / "m", seed=0, budget_minutes=0.05, config=cfg,
                progress=False)
    stages = [r["stage"] for r in res.history]
    assert stages[0] == "frame autoencoder" and stages[-1] == "translation"
    assert "vq-dvae decoder" in stages  # a cut encoder stage still gets a decoder epoch
    assert res.meta["stopped_by_budget"][0] == "frame autoencoder"
    assert [r for r in res.history if r.get("stopped")], "the history says where the budget stopped a stage"
    assert all("val_loss" in r for r in res.history)
    assert res.history[-1]["seconds"] < 0.05 * 60 + 10


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    """gesture2vec trained once on the small synthetic corpus, and its test split generated."""
    from evalsuite.generators.requests import requests_from_corpus
    from evalsuite.generators.runner import generate
    from evalsuite.generators.training import train

    corpus = synth_corpus()
    root = tmp_path_factory.mktemp("g2v")
    entry = find_generator("gesture2vec")
    res = train(entry, corpus, root / "model", seed=0, config=CONFIG, progress=False)
    reqs = requests_from_corpus(corpus, "test", 20.0)
    generate(entry, reqs, root / "gen", model_dir=root / "model", seed=0, progress=False)
    return corpus, root, res, reqs


@pytest.mark.slow
def test_codebook_is_used_and_its_statistics_reach_the_codebook_metrics(trained):
    from evalsuite.generators.gesture2vec.plugin import code_usage

    _, root, res, _ = trained
    print("gesture2vec code perplexity", res.meta["code_perplexity"], "of K =", CONFIG["codebook"])
    assert res.meta["code_perplexity"] > 0.3 * CONFIG["codebook"], res.meta   # no collapse
    usage = code_usage(root / "gen", root / "model")
    counts = np.load(root / "model" / "code_counts.npy")
    assert len(counts) == CONFIG["codebook"] and counts.sum() > 0
    assert 0.0 <= usage["codebook_hellinger"] <= 1.0 and usage["codes_used"] >= 2
    assert usage["training_perplexity"] == pytest.approx(res.meta["code_perplexity"], rel=1e-6)


@pytest.mark.slow
def test_latent_nsd_lower_than_a_shuffled_control(trained):
    from evalsuite.generators import criteria as C
    from evalsuite.generators.gesture2vec.plugin import Gesture2Vec
    from evalsuite.generators.gesture2vec.training import latent_windows

    corpus, root, _, _ = trained
    g = Gesture2Vec()
    g.load({}, root / "model")
    lat = [latent_windows(g.model, g.rep.encode(s.load_motion())) for s in corpus.split("test")]
    nsd = C.latent_nsd(lat)
    print("gesture2vec latent NSD", nsd)
    assert nsd["nsd"] < nsd["nsd_shuffled"], nsd


@pytest.mark.slow
def test_retrieval_decoding_is_flagged_and_seeded(trained):
    from evalsuite.generators.runner import generate

    corpus, root, _, reqs = trained
    entry = find_generator("gesture2vec")
    generate(entry, reqs, root / "retr", model_dir=root / "model", seed=0, config={"decoding": "retrieval"},
             samples=2, progress=False)
    record = json.loads((root / "retr" / "generation.json").read_text())
    assert all(f["meta"]["retrieval"] and f["meta"]["decoding"] == "retrieval" for f in record["files"])
    assert record["files"][0]["sha256"] != record["files"][1]["sha256"]   # two samples, two clips
    gen_record = json.loads((root / "gen" / "generation.json").read_text())
    assert not any(f["meta"]["retrieval"] for f in gen_record["files"])
    assert all(len(f["meta"]["codes"]) >= 1 for f in gen_record["files"])


@pytest.mark.slow
def test_the_four_learning_criteria_hold_with_the_defaults_on_a_15_minute_corpus(tmp_path):
    from evalsuite.corpus import load_corpus
    from evalsuite.generators import criteria as C
    from evalsuite.generators.evaluation import evaluate_condition, segment_scores
    from evalsuite.generators.gesture2vec.plugin import Gesture2Vec
    from evalsuite.generators.gesture2vec.training import latent_windows
    from evalsuite.generators.requests import requests_from_corpus
    from evalsuite.generators.runner import generate
    from evalsuite.generators.training import train
    from evalsuite.synth.corpus import synthesize_corpus

    synthesize_corpus(tmp_path / "corpus", 15.0, 3, jobs=2, progress=False)
    corpus = load_corpus(tmp_path / "corpus")
    entry = find_generator("gesture2vec")
    res = train(entry, corpus, tmp_path / "model", seed=0, progress=False)
    reqs = requests_from_corpus(corpus, "test", 20.0)
    generate(entry, reqs, tmp_path / "gen", model_dir=tmp_path / "model", seed=0, progress=False)
    generate(find_generator("mean_pose"), reqs, tmp_path / "mean_pose", progress=False)
    natural = [segment_scores(s.load_motion(), s) for s in corpus.split("test")]
    natural_lex = np.nanmean([np.nanmean([r.get(f"lexical_{c}", np.nan) for r in natural])
                              for c in ("up", "wide", "self", "point")])
    lexical = evaluate_condition(tmp_path / "gen", corpus)["lexical_mean"]
    g = Gesture2Vec()
    g.load({}, tmp_path / "model")
    nsd = C.latent_nsd([latent_windows(g.model, g.rep.encode(s.load_motion())) for s in corpus.split("test")])
    fgd = C.fgd_against_natural(corpus, {k: C.generated_motions(tmp_path / k, corpus) for k in ("gen", "mean_pose")})
    print("gesture2vec, 15-minute corpus: lexical", lexical, "natural", natural_lex, "perplexity",
          res.meta["code_perplexity"], "NSD", nsd, "FGD", fgd)
    # measured (seed 3): lexical 19.7 of natural's 35.3 (0.56 x), perplexity 173 of K = 300, FGD 54.0 vs 64.1
    assert lexical >= 0.5 * natural_lex
    assert res.meta["code_perplexity"] > 0.3 * 300
    assert nsd["nsd"] < nsd["nsd_shuffled"], nsd
    assert fgd["gen"] < fgd["mean_pose"], fgd


def test_the_conditioned_decoder_is_fed_its_last_frame_from_the_frame_before_the_chunk():
    """conditioned_decoder (the paper's §4.3, the original code's autoencoder_conditioned): a one-direction GRU that
    reads the code and the frame it produced last; in training it starts from the frame before the chunk (the
    chunk's first latent minus its difference), at generation from the last frame of the chunk before."""
    import torch

    from evalsuite.generators.gesture2vec.net import VQDVAE, G2VConfig

    torch.manual_seed(0)
    c = G2VConfig(pose_dim=12, text_dim=8, latent_dim=4, chunk=6, codebook=5, vq_hidden=8, vq_layers=1,
                  conditioned_decoder=True)
    vq = VQDVAE(c)
    assert not vq.decoder.bidirectional and vq.decoder.input_size == vq.code_dim + 8
    assert VQDVAE(G2VConfig(pose_dim=12, text_dim=8, latent_dim=4)).decoder.bidirectional, "the default as before"
    e = torch.randn(3, vq.code_dim)
    with torch.no_grad():
        a, b = vq.decode(e[:1]), vq.decode(e[:1], torch.ones(1, 8))
        assert not torch.allclose(a[:, 0], b[:, 0]), "the first step reads the frame before the chunk"
        seq = vq.decode_sequence(e, torch.full((8,), 0.5))
        first = vq.decode(e[:1], torch.full((1, 8), 0.5))
        np.testing.assert_allclose(seq[0], first[0], atol=1e-6)
        np.testing.assert_allclose(seq[1], vq.decode(e[1:2], first[:, -1])[0], atol=1e-6)   # carried across chunks
    latent = torch.randn(1, 10, 4).cumsum(1)                     # a latent track and its frame differences
    feats = torch.cat([latent, torch.diff(latent, dim=1, prepend=latent[:, :1])], dim=-1)
    seen = []
    original = vq.decode
    vq.decode = lambda code, previous=None: seen.append(previous) or original(code, previous)
    recon, _, loss = vq(feats[:, 3:9])                             # a chunk that starts at frame 3
    np.testing.assert_allclose(seen[0][0, :4].detach(), latent[0, 2], atol=1e-6)
    total = ((recon - feats[:, 3:9]) ** 2).mean() + loss
    total.backward()
    assert total.item() > 0 and all(p.grad is not None for p in vq.decoder.parameters())


def test_a_conditioned_decoder_trains_and_generates_from_the_cli_options(tmp_path):
    from evalsuite.generators.checking import tiny_corpus
    from evalsuite.generators.requests import requests_from_corpus
    from evalsuite.generators.runner import generate
    from evalsuite.generators.training import train

    corpus = tiny_corpus(tmp_path / "tiny", n_segments=6, seconds=8.0)
    entry = find_generator("gesture2vec")
    cfg = {"words": "hash", "codebook": 8, "dae_epochs": 2, "vq_epochs": 2, "vq_decoder_epochs": 2,
           "translation_epochs": 2, "conditioned_decoder": "true"}
    train(entry, corpus, tmp_path / "m", seed=0, config=cfg, progress=False)
    saved = json.loads((tmp_path / "m" / "model.json").read_text())
    assert saved["config"]["conditioned_decoder"] in (True, "true")
    reqs = requests_from_corpus(corpus, "test", 20.0)
    generate(entry, reqs, tmp_path / "gen", model_dir=tmp_path / "m", seed=0, progress=False)
    record = json.loads((tmp_path / "gen" / "generation.json").read_text())
    assert record["files"] and all(f["meta"]["codes"] for f in record["files"])   # loaded with its decoder
