"""Plug-ins from outside evalsuite: an installed package (entry point), an ad-hoc file, the subprocess bridge;
the generate/train/generators commands."""
from __future__ import annotations

import json
import os
import pathlib
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from click.testing import CliRunner

from evalsuite.audio import write_wav
from evalsuite.cli import main
from evalsuite.generators import GeneratorError, find_generator
from evalsuite.generators.checking import tiny_corpus
from evalsuite.generators.requests import requests_from_corpus
from evalsuite.generators.runner import generate
from evalsuite.motion.io import load_motion

PLUGIN = '''
import json, pathlib
import numpy as np
from evalsuite.generators import Generator, GeneratorSpec, GenerationResult, TrainingResult
from evalsuite.motion import Motion

JOINTS = ("Hips", "Head", "RightHand", "LeftHand")

class Sway(Generator):
    """Positions that sway with the speech's loudness; trainable: fit learns the mean pose."""
    spec = GeneratorSpec(name="sway", version="0.1", summary="a test plug-in", audio="required",
                         output="positions", joints=JOINTS, native_fps=25.0, units="m", stochastic=True,
                         trainable=True, config={"amplitude": "metres (default 0.1)"})

    def load(self, config, model_dir=None):
        super().load(config, model_dir)
        self.mean = np.zeros((len(JOINTS), 3))
        if model_dir is not None:
            self.mean = np.load(model_dir / "mean.npy")

    def generate(self, request):
        from evalsuite.audio import read_wav, to_mono
        x, rate = read_wav(request.audio)
        n = int(round(request.duration * 25.0))
        env = np.interp(np.arange(n) / 25.0, np.arange(len(x)) / rate, np.abs(to_mono(x)))
        rng = np.random.default_rng(request.seed)
        pos = self.mean[None] + float(self.option("amplitude", 0.1)) * env[:, None, None] * rng.normal(size=(1, 4, 3))
        return GenerationResult(Motion.from_positions(pos, JOINTS, 25.0))

    def fit(self, corpus, out_dir, *, seed, budget_minutes=None, progress=None):
        poses = [s.load_motion().positions()[:, :4].reshape(-1, 4, 3) for s in corpus.split("train")]
        mean = np.concatenate(poses).mean(axis=0)
        np.save(out_dir / "mean.npy", mean)
        history = [{"epoch": 1, "train_loss": 1.0, "val_loss": 0.5, "seconds": 0.0}]
        if progress:
            progress(history[0])
        return TrainingResult(out_dir, history)
'''


@pytest.fixture()
def plugin_path(tmp_path):
    """An installed package that declares the entry point ``sway`` in the group evalsuite.generators."""
    site = tmp_path / "site"
    (site / "evs_swayplug").mkdir(parents=True)
    (site / "evs_swayplug" / "__init__.py").write_text("")
    (site / "evs_swayplug" / "gen.py").write_text(PLUGIN)
    dist = site / "evs_swayplug-0.1.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: evs-swayplug\nVersion: 0.1\n")
    (dist / "entry_points.txt").write_text("[evalsuite.generators]\nsway = evs_swayplug.gen:Sway\n")
    return site


def _python(site: pathlib.Path, code: str) -> str:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(site), os.getcwd()])}
    return subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout


def _wav(path: pathlib.Path, seconds: float = 2.0) -> pathlib.Path:
    t = np.arange(int(seconds * 16000)) / 16000
    write_wav(path, (0.3 * np.sin(2 * np.pi * 200 * t) * (np.sin(2 * np.pi * 1.5 * t) > 0))[:, None], 16000)
    return path


def test_entry_point_plugin_is_listed_without_import_and_generates(plugin_path, tmp_path):
    out = _python(plugin_path, "import sys\nfrom evalsuite.generators import list_generators\n"
                               "e = [g for g in list_generators() if g.name == 'sway'][0]\n"
                               "print(e.origin, e.distribution, e.spec is None, 'evs_swayplug.gen' in sys.modules, "
                               "'torch' in sys.modules)")
    assert out.split() == ["entry", "point", "evs-swayplug", "0.1", "True", "False", "False"]
    listing = _python(plugin_path, "from evalsuite.cli import main\nmain(['generators', 'list'])")
    assert "sway" in listing
    assert "not imported" in listing
    wav = _wav(tmp_path / "hello.wav")
    _python(plugin_path, f"from evalsuite.cli import main\n"
                         f"main(['generate', '-g', 'sway', '--audio', {str(wav)!r}, '--fps', '30', '-o', "
                         f"{str(tmp_path / 'out')!r}], standalone_mode=False)")
    m = load_motion(tmp_path / "out" / "hello.npz")
    assert m.fps == 30.0
    assert m.n_frames == 60
    record = json.loads((tmp_path / "out" / "generation.json").read_text())
    assert record["origin"] == "entry point"
    assert record["distribution"] == "evs-swayplug 0.1"
    assert record["files"][0]["notes"][0]["rule"] == "fps"


def test_adhoc_file_plugin_trains_and_generates_through_the_commands(tmp_path):
    plugin = tmp_path / "myplugin.py"
    plugin.write_text(PLUGIN)
    corpus = tiny_corpus(tmp_path / "corpus")
    runner = CliRunner()
    info = runner.invoke(main, ["generators", "info", f"{plugin}:Sway"])
    assert info.exit_code == 0, info.output
    assert "a test plug-in" in info.output
    # train through the Python API on the in-memory corpus (the layout readers are tested elsewhere)
    from evalsuite.generators.training import train

    entry = find_generator(f"{plugin}:Sway")
    train(entry, corpus, tmp_path / "model", seed=0, progress=False)
    model = json.loads((tmp_path / "model" / "model.json").read_text())
    assert model["generator"]["name"] == "sway"
    assert set(model["files"]) == {"mean.npy"}
    assert model["history"][0]["val_loss"] == 0.5
    assert (tmp_path / "model" / "train_log.csv").read_text().startswith("epoch,train_loss,val_loss,seconds")
    run = generate(entry, requests_from_corpus(corpus, "test", 30.0), tmp_path / "gen", model_dir=tmp_path / "model",
                   samples=2, seed=3, progress=False)
    assert sorted(r["file"] for r in run.files) == ["seg05_0.npz", "seg05_1.npz"]
    assert run.record["model"]["sha256"]


def test_unknown_generator_and_bad_target_are_precise(tmp_path):
    with pytest.raises(GeneratorError, match="unknown generator 'nope'; known: .*mismatched"):
        find_generator("nope")
    with pytest.raises(GeneratorError, match="no such plug-in file"):
        find_generator(str(tmp_path / "missing.py") + ":X")
    with pytest.raises(GeneratorError, match="is not a subclass of evalsuite.generators.Generator"):
        find_generator("evalsuite.generators.contract:GeneratorSpec")
    result = CliRunner().invoke(main, ["generate", "-g", "nope", "--audio", str(_wav(tmp_path / "a.wav")),
                                       "-o", str(tmp_path / "o")])
    assert result.exit_code == 1
    assert "unknown generator 'nope'" in result.output
    assert "Traceback" not in result.output


def test_check_command_runs_the_rules(tmp_path):
    result = CliRunner().invoke(main, ["generators", "check", "mismatched"])
    assert result.exit_code == 0, result.output
    assert "samples: differ" in result.output
    assert "all checks passed" in result.output


STUB_BRIDGE = '''
import json, sys, time
request = json.load(open(sys.argv[1]))
if request["segment_id"] == "fail":
    print("loading checkpoint", file=sys.stderr)
    print("KeyError: 'bert-base-cased' not found", file=sys.stderr)
    sys.exit(3)
if request["segment_id"] == "slow":
    time.sleep(30)
fps = 20.0
n = int(round(request["duration"] * fps))
words = request["transcript"]["words"] if request["transcript"] else []
rows = ["time,Hips.x,Hips.y,Hips.z,RightHand.x,RightHand.y,RightHand.z"]
for i in range(n):
    t = i / fps
    speaking = any(w["start"] <= t < w["end"] for w in words)
    rows.append(f"{t},0,90,0,-30,{110 + (20 if speaking else 0)},{request['seed'] % 7}")
open(request["out_dir"] + "/out.csv", "w").write("\\n".join(rows) + "\\n")
json.dump({"motion": "out.csv", "fps": fps, "meta": {"prefix": sys.prefix}}, open(request["out_dir"] + "/result.json", "w"))
'''


@pytest.fixture(scope="module")
def bridge_env(tmp_path_factory):
    """A separate virtual environment (no evalsuite, no numpy in it) and a stdlib-only bridge script."""
    root = tmp_path_factory.mktemp("bridge")
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(root / "venv")], check=True)
    (root / "bridge.py").write_text(STUB_BRIDGE)
    return root


def test_subprocess_bridge_round_trip(bridge_env, tmp_path):
    corpus = tiny_corpus(tmp_path / "corpus")
    reqs = requests_from_corpus(corpus, "test", 30.0)
    config = {"command": ["{python}", str(bridge_env / "bridge.py"), "{request}"],
              "python": str(bridge_env / "venv" / "bin" / "python")}
    run = generate(find_generator("external"), reqs, tmp_path / "out", config=config, seed=1, progress=False)
    row = run.files[0]
    assert row["meta"]["prefix"] == str(bridge_env / "venv")
    m = load_motion(tmp_path / "out" / row["file"])
    assert m.n_frames == reqs[0].n_frames
    assert m.fps == 30.0
    # the transcript reached the other side: the hand is up while a word is spoken
    word = reqs[0].transcript.words[0]
    frame = int(round((word.start + word.end) / 2 * 30))
    assert m.positions()[frame, 1, 1] == pytest.approx(130.0, abs=1e-6)


def test_failing_bridge_reports_exit_code_and_stderr_tail(bridge_env, tmp_path):
    from dataclasses import replace

    corpus = tiny_corpus(tmp_path / "corpus")
    req = replace(requests_from_corpus(corpus, "test", 30.0)[0], segment_id="fail")
    config = {"command": [str(bridge_env / "venv" / "bin" / "python"), str(bridge_env / "bridge.py"), "{request}"]}
    with pytest.raises(GeneratorError, match=r"segment 'fail': the command failed with exit code 3; stderr \(last "
                                             r"lines\):\nloading checkpoint\nKeyError: 'bert-base-cased' not found"):
        generate(find_generator("external"), [req], tmp_path / "out", config=config, progress=False)
    slow = replace(req, segment_id="slow")
    with pytest.raises(GeneratorError, match="did not finish within 1 s"):
        generate(find_generator("external"), [slow], tmp_path / "out2", config={**config, "timeout_s": 1},
                 progress=False, check_determinism=False)
    with pytest.raises(GeneratorError, match="cannot run '/no/such/python': no such program"):
        generate(find_generator("external"), [req], tmp_path / "out3",
                 config={"command": ["/no/such/python", "x.py"]}, progress=False)


def test_generate_help_and_listing_do_not_import_torch():
    code = ("import sys\nfrom click.testing import CliRunner\nfrom evalsuite.cli import main\n"
            "r = CliRunner().invoke(main, ['generators', 'list'])\nassert r.exit_code == 0, r.output\n"
            "r = CliRunner().invoke(main, ['generators', 'info', 'mismatched'])\nassert r.exit_code == 0\n"
            "print('torch' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


@pytest.mark.parametrize("name", ["gesticulator", "aud2pose", "aud2motion", "aud2repr2pose", "aud2repr2pose-demo"])
def test_info_of_the_seed_systems_says_what_they_are(name):
    result = CliRunner().invoke(main, ["generators", "info", name])
    assert result.exit_code == 0, result.output
    for label in ("citation:", "licence:", "inputs:", "output:", "deviations from the paper:"):
        assert label in result.output, (name, label)
    assert "20 fps" in result.output
    assert "Kucherenko" in result.output
