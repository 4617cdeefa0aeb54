"""benchmarks/gpu_check.py runs anywhere: the CPU part always, the CUDA part where torch sees a GPU (and says so
where it does not)."""
from __future__ import annotations

import pathlib
import subprocess
import sys

import torch

SCRIPT = pathlib.Path(__file__).resolve().parents[1] / "benchmarks" / "gpu_check.py"


def test_gpu_check_runs_and_says_whether_cuda_ran():
    out = subprocess.run([sys.executable, str(SCRIPT), "--minutes", "0.3", "--only", "aud2pose"],
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    line = next(ln for ln in out.stdout.splitlines() if ln.startswith("aud2pose"))
    assert "cpu: train" in line and "generate" in line
    if torch.cuda.is_available():
        assert "cuda: train" in line and "max|cpu-cuda|/range" in line
    else:
        assert "cuda:" not in line
        assert "no GPU: CUDA part not run" in out.stdout
