"""torch is an optional extra: without it, a clear message names the extra and the rest works.

The subprocesses hide torch with a ``sitecustomize`` on PYTHONPATH that installs an import
hook refusing ``torch`` (ModuleNotFoundError, as when the package is not installed).
"""
from __future__ import annotations

import os
import pathlib
import subprocess
import sys

import evalsuite

SAMPLES = pathlib.Path(evalsuite.__file__).resolve().parent / "data" / "samples"
HINT = 'pip install "evalsuite[learned]"'
BLOCK_TORCH = """
import importlib.abc, sys


class _HideTorch(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name == "torch" or name.startswith("torch."):
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return None


sys.meta_path.insert(0, _HideTorch())
"""


def _run(tmp_path, code: str, *args: str, hide_torch: bool = True) -> subprocess.CompletedProcess:
    env = dict(os.environ)
    if hide_torch:
        shim = tmp_path / "shim"
        shim.mkdir(exist_ok=True)
        (shim / "sitecustomize.py").write_text(BLOCK_TORCH)
        env["PYTHONPATH"] = os.pathsep.join([str(shim), env.get("PYTHONPATH", "")])
    return subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, env=env,
                          timeout=600, cwd=tmp_path)


def test_importing_the_learned_package_without_torch_names_the_extra(tmp_path):
    code = (
        "import evalsuite.errors as e\n"
        "try:\n"
        "    import evalsuite.learned\n"
        "except ImportError as exc:\n"
        "    assert isinstance(exc, e.InputError), type(exc)\n"
        "    print('MESSAGE', exc)\n"
        "else:\n"
        "    raise SystemExit('imported without torch')\n")
    r = _run(tmp_path, code)
    assert r.returncode == 0, r.stderr
    assert HINT in r.stdout
    assert "PyTorch" in r.stdout


def test_fgd_command_without_torch_prints_the_message_without_traceback(tmp_path):
    cli = "from evalsuite.cli import main; main()"
    r = _run(tmp_path, cli, "fgd", "score", "model.pt", "natural", "system")
    assert r.returncode == 1
    assert HINT in r.stderr
    assert "Traceback" not in r.stderr
    r = _run(tmp_path, cli, "fgd")
    assert r.returncode == 1
    assert HINT in r.stderr
    assert "Traceback" not in r.stderr
    r = _run(tmp_path, cli, "--help")
    assert r.returncode == 0
    assert "fgd" in r.stdout
    assert "info" in r.stdout


def test_the_rest_of_evalsuite_works_without_torch(tmp_path):
    code = (
        "import sys, numpy as np, evalsuite\n"
        "from evalsuite.metrics.frechet import frechet_distance_samples\n"
        "m = evalsuite.load_motion(sys.argv[1])\n"
        "assert m.positions().shape[0] == m.n_frames > 0\n"
        "rng = np.random.default_rng(0)\n"
        "print('FD', frechet_distance_samples(rng.normal(size=(500, 3)), rng.normal(size=(500, 3))))\n"
        "from evalsuite.cli import main\n"
        "main(['info', sys.argv[1]])\n")
    r = _run(tmp_path, code, str(SAMPLES / "walk01.bvh"))
    assert r.returncode == 0, r.stderr
    assert "FD" in r.stdout
    assert "frames" in r.stdout


def test_nothing_outside_the_learned_package_imports_torch(tmp_path):
    modules = ["evalsuite", "evalsuite.cli", "evalsuite.motion", "evalsuite.metrics.frechet", "evalsuite.demo"]
    code = ("import importlib, sys\n"
            f"for m in {modules!r}: importlib.import_module(m)\n"
            "from evalsuite.cli import main\n"
            "try:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
            "print('TORCH', 'torch' in sys.modules)\n")
    r = _run(tmp_path, code, hide_torch=False)
    assert r.returncode == 0, r.stderr
    assert "TORCH False" in r.stdout


def test_demo_without_torch_says_how_to_get_it_before_doing_anything(tmp_path):
    """The demo trains generators and an FGD encoder: without torch it stops at once with the install command
    (scripts/demo installs it), one line, no traceback, nothing written."""
    r = _run(tmp_path, "from evalsuite.cli import main; main(['demo', '-o', 'demo'])")
    assert r.returncode == 1
    assert HINT in r.stderr
    assert "Traceback" not in r.stderr
    assert not (tmp_path / "demo").exists()
