"""evalsuite.generators.device: --device auto|cpu|cuda|mps and --amp on train and generate; the runner's determinism
check within a tolerance on a GPU."""
from __future__ import annotations

import numpy as np
import pytest
import torch
from click.testing import CliRunner

from evalsuite.cli import main
from evalsuite.errors import InputError
from evalsuite.generators import runner
from evalsuite.generators.checking import tiny_corpus
from evalsuite.generators.contract import GenerationResult
from evalsuite.generators.device import _mode_class, current_device, resolve_device, use_device
from evalsuite.generators.registry import find_generator
from evalsuite.generators.requests import requests_from_corpus
from evalsuite.generators.runner import generate
from evalsuite.generators.training import train
from evalsuite.motion import Motion


def test_resolution_and_errors(monkeypatch):
    expected = "cuda" if torch.cuda.is_available() else "mps" if torch.backends.mps.is_available() else "cpu"
    assert resolve_device("auto") == expected and resolve_device("cpu") == "cpu"
    monkeypatch.setattr(torch.cuda, "is_available", lambda: False)
    monkeypatch.setattr(torch.backends.mps, "is_available", lambda: False)
    assert resolve_device("auto") == "cpu"
    with pytest.raises(InputError, match="--device cuda: torch .* sees no CUDA GPU"):
        resolve_device("cuda")
    with pytest.raises(InputError, match="--device mps"):
        resolve_device("mps")
    with pytest.raises(InputError, match="--amp needs --device cuda"), use_device("cpu", amp=True):
        pass
    assert current_device() == "cpu"


def test_cuda_without_a_gpu_is_a_clear_error_on_both_commands(monkeypatch, tmp_path):
    monkeypatch.setattr(torch.cuda, "is_available", lambda: False)
    for args in (["train", "-g", "aud2pose", "--corpus", str(tmp_path), "-o", str(tmp_path / "m")],
                 ["generate", "-g", "mean_pose", "--corpus", str(tmp_path), "-o", str(tmp_path / "g")]):
        res = CliRunner().invoke(main, [*args, "--device", "cuda"])
        assert res.exit_code != 0
        assert "--device cuda" in res.output and "no CUDA GPU" in res.output and "Traceback" not in res.output


def test_cpu_device_trains_and_generates_as_before(tmp_path):
    corpus = tiny_corpus(tmp_path / "corpus", n_segments=6, seconds=11.0)
    entry = find_generator("ferstl-mogan")
    cfg = {"classifier_epochs": 1, "pretrain_epochs": 2, "adversarial_steps": 2, "batch_size": 4,
           "realism_pretrain_steps": 2, "phase_pretrain_tries": 2}
    plain = train(entry, corpus, tmp_path / "plain", seed=1, config=cfg, progress=False)
    with use_device("cpu"):
        on_cpu = train(entry, corpus, tmp_path / "cpu", seed=1, config=cfg, progress=False)
    # the GPU path's operation hook, run on the CPU: it must not change a single weight or sample
    with _mode_class(torch)("cpu"):
        hooked = train(entry, corpus, tmp_path / "hooked", seed=1, config=cfg, progress=False)
    assert plain.meta["weights_sha256"] == on_cpu.meta["weights_sha256"] == hooked.meta["weights_sha256"]
    reqs = requests_from_corpus(corpus, "test", 20.0)
    with use_device("cpu"):
        run = generate(entry, reqs, tmp_path / "gen", model_dir=tmp_path / "plain", seed=2, progress=False)
    with _mode_class(torch)("cpu"):
        hooked_run = generate(entry, reqs, tmp_path / "gen_hooked", model_dir=tmp_path / "plain", seed=2,
                              progress=False)
    assert [r["sha256"] for r in run.files] == [r["sha256"] for r in hooked_run.files]
    assert run.record["device"] == "cpu" and run.record["determinism_check"] == "bitwise"


def test_determinism_within_a_tolerance_on_a_gpu(monkeypatch):
    rng = np.random.default_rng(0)
    pos = rng.normal(size=(30, 3, 3)) * 10.0
    a = GenerationResult(Motion.from_positions(pos, ["a", "b", "c"], 20.0))
    near = GenerationResult(Motion.from_positions(pos + 1e-6, ["a", "b", "c"], 20.0))
    far = GenerationResult(Motion.from_positions(pos + 1.0, ["a", "b", "c"], 20.0))
    assert not runner._same_output(a, near)                       # on the CPU: bitwise
    monkeypatch.setattr(runner, "current_device", lambda: "cuda")
    assert runner._same_output(a, near) and not runner._same_output(a, far)
    assert runner._determinism_rule().startswith("within 0.001 x the value range (cuda)")


def test_the_gpu_hook_moves_cpu_tensors_to_the_device():
    # "meta" stands in for a GPU: tensors there have shapes but no data, and need no hardware
    with _mode_class(torch)("meta"):
        on_device = torch.zeros(2, 3, device="meta")
        mixed = on_device + torch.from_numpy(np.ones((2, 3), dtype=np.float32))   # a CPU array meets it
        assert mixed.device.type == "meta"
        drawn = torch.randn(4, generator=torch.Generator().manual_seed(0))       # seeded CPU numbers ...
        assert drawn.device.type == "meta"                                      # ... handed to the device
        cpu_only = torch.ones(2) * 2                                            # nothing on the device: stays
        assert cpu_only.device.type == "cpu" and np.asarray(cpu_only).tolist() == [2.0, 2.0]
