"""gesticulator-original: the adapter to the ORIGINAL Gesticulator code, tested against a STUB of the original.

The stub repository below (made in tmp_path) mimics the original's Python interface as the driver uses it
(GesticulatorModel.load_from_checkpoint, GesturePredictor with transformers' from_pretrained looked up in its
module, motion_visualizer.convert2bvh.write_bvh, gesticulator/utils/data_pipe.sav). It checks what it receives
(a wav; Google ASR JSON with "N.NNNs" times and a last word ending in . ! or ?; the local BERT folder, never a
download) and writes a 20 fps BVH that ends with the last word, as the original does. It is not the real code.
"""
from __future__ import annotations

import ast
import json
import pathlib
import sys
import textwrap
from dataclasses import replace

import pytest
from click.testing import CliRunner

from evalsuite.cli import main
from evalsuite.corpus.types import Transcript, Word
from evalsuite.generators import GeneratorError, find_generator
from evalsuite.generators.checking import tiny_corpus
from evalsuite.generators.gesticulator_original.plugin import DRIVER, GesticulatorOriginal
from evalsuite.generators.gesticulator_original.transcript import google_asr_json, seconds_string
from evalsuite.generators.requests import requests_from_corpus
from evalsuite.generators.runner import generate
from evalsuite.motion.io import load_motion

STUB_MODEL = '''
import json

class _Weight:
    def __init__(self, shape):
        self.shape = shape

class GesticulatorModel:
    text_dim = 773

    def __init__(self, ckpt):
        self.ckpt = ckpt
        self.encode_speech = [_Weight_holder(ckpt["audio_dim"] + 773)]

    @classmethod
    def load_from_checkpoint(cls, path, inference_mode=False):
        assert inference_mode, "the demo loads with inference_mode=True"
        with open(path) as f:
            return cls(json.load(f))

class _Weight_holder:
    def __init__(self, in_dim):
        self.weight = _Weight((256, in_dim))
'''

STUB_PREDICTOR = '''
import json, os, re, sys, wave

def _log(model, entry):
    with open(model.ckpt["log"], "a") as f:
        f.write(json.dumps(entry) + "\\n")

class _Pretrained:
    @classmethod
    def from_pretrained(cls, name):
        if name == "bert-base-cased":
            raise OSError("stub: would download bert-base-cased from a hub")
        assert os.path.isfile(os.path.join(name, "config.json")), name
        return (cls.__name__, name)

class BertTokenizer(_Pretrained):
    pass

class BertModel(_Pretrained):
    pass

TIME = re.compile(r"^[0-9]+[.][0-9]{3}s$")

class GesturePredictor:
    def __init__(self, model, feature_type):
        assert feature_type == "Spectro", feature_type
        self.model = model
        self.embedding = (BertTokenizer.from_pretrained("bert-base-cased"), BertModel.from_pretrained("bert-base-cased"))

    def predict_gestures(self, audio_path, text):
        if self.model.ckpt.get("fail"):
            print("ERROR: GesticulatorModel.forward() returned None!")
            exit(-1)
        with wave.open(audio_path) as w:   # a wav, or this raises
            seconds = w.getnframes() / w.getframerate()
        assert text.endswith(".json") and os.path.isfile(text), text
        with open(text) as f:
            results = json.load(f)
        last_end = 0.0
        for result in results:
            words = result["alternatives"][0]["words"]
            for w in words:
                assert TIME.match(w["start_time"]) and TIME.match(w["end_time"]), w
                assert w["word"].strip(), w
                last_end = float(w["end_time"].rstrip("s"))
            if words[-1]["word"][-1] not in ".!?":
                print("ERROR: missing delimiter in input to BERT!")
                exit(-1)
        _log(self.model, {"audio": audio_path, "transcript": results, "embedding": self.embedding})
        n = min(int(seconds * 20), 2 * int(last_end * 10))   # the text ends with the last word
        n -= n % 2
        return [[[0.01 * i + 0.001 * j for j in range(45)] for i in range(n)]]
'''

STUB_CONVERT2BVH = '''
import os

def write_bvh(datapipe_file, anim_clip, filename, fps):
    assert isinstance(datapipe_file, tuple) and os.path.isfile(datapipe_file[0]), datapipe_file
    joints = ["Spine", "RightArm", "LeftArm"]
    lines = ["HIERARCHY", "ROOT Hips", "{", "  OFFSET 0 0 0",
             "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation"]
    for j in joints:
        lines += ["  JOINT " + j, "  {", "    OFFSET 0 10 0", "    CHANNELS 3 Zrotation Xrotation Yrotation",
                  "    End Site", "    {", "      OFFSET 0 5 0", "    }", "  }"]
    lines += ["}", "MOTION", "Frames: %d" % len(anim_clip[0]), "Frame Time: %.6f" % (1.0 / fps)]
    for frame in anim_clip[0]:
        lines.append(" ".join("%.4f" % v for v in [0, 90, 0, 0, 0, 0] + list(frame[:9])))
    with open(filename, "w") as f:
        f.write("\\n".join(lines) + "\\n")
'''


def make_stub(root: pathlib.Path, **ckpt_extra) -> dict[str, str]:
    """A stub 'original repository', checkpoint and BERT folder; returns the plug-in's config."""
    repo = root / "gesticulator-clone"
    files = {"gesticulator/__init__.py": "", "gesticulator/model/__init__.py": "",
             "gesticulator/model/model.py": STUB_MODEL, "gesticulator/interface/__init__.py": "",
             "gesticulator/interface/gesture_predictor.py": STUB_PREDICTOR,
             "gesticulator/visualization/motion_visualizer/__init__.py": "",
             "gesticulator/visualization/motion_visualizer/convert2bvh.py": STUB_CONVERT2BVH,
             "gesticulator/utils/data_pipe.sav": "stub pipeline"}
    for rel, text in files.items():
        (repo / rel).parent.mkdir(parents=True, exist_ok=True)
        (repo / rel).write_text(textwrap.dedent(text))
    bert = root / "bert-base-cased"
    bert.mkdir(parents=True)
    for name in ("config.json", "vocab.txt", "pytorch_model.bin"):
        (bert / name).write_text("{}")
    ckpt = root / "default.ckpt"
    ckpt.write_text(json.dumps({"audio_dim": 64, "log": str(root / "stub_log.jsonl"), **ckpt_extra}))
    return {"repo": str(repo), "python": sys.executable, "checkpoint": str(ckpt), "bert": str(bert)}


def stub_log(config: dict[str, str]) -> list[dict]:
    path = pathlib.Path(json.loads(pathlib.Path(config["checkpoint"]).read_text())["log"])
    return [json.loads(line) for line in path.read_text().splitlines()]


# -- the transcript conversion ------------------------------------------------------------------------------
def test_google_asr_json_times_full_stop_and_empty():
    words = (Word("deep", 0.4, 0.8), Word("learning", 0.8, 1.3), Word("  ", 1.3, 1.4), Word("works", 1.5, 2.0))
    out = google_asr_json(Transcript(words))
    assert len(out) == 1
    got = out[0]["alternatives"][0]["words"]
    assert got == [{"start_time": "0.400s", "end_time": "0.800s", "word": "deep"},
                   {"start_time": "0.800s", "end_time": "1.300s", "word": "learning"},
                   {"start_time": "1.500s", "end_time": "2.000s", "word": "works."}]   # blank word dropped
    assert out[0]["alternatives"][0]["transcript"] == "deep learning works."
    assert seconds_string(12) == "12.000s" and seconds_string(-0.01) == "0.000s"
    # a last word already ending a sentence keeps its mark; earlier words are left alone
    asked = google_asr_json([Word("ready.", 0.0, 0.5), Word("go?", 0.6, 0.9)])[0]["alternatives"][0]["words"]
    assert [w["word"] for w in asked] == ["ready.", "go?"]
    assert google_asr_json([Word("stop", 0.0, 0.5), Word("now", 0.5, 0.7)])[0]["alternatives"][0]["words"][-1][
        "word"] == "now."
    # nothing to say: no recognition results
    assert google_asr_json(Transcript(())) == []
    assert google_asr_json(None) == []
    assert google_asr_json([Word(" ", 0.0, 0.2)]) == []


# -- generation through the runner ---------------------------------------------------------------------------
def test_generation_through_the_runner_has_the_right_duration(tmp_path):
    config = make_stub(tmp_path / "stub")
    corpus = tiny_corpus(tmp_path / "corpus")
    reqs = requests_from_corpus(corpus, "test", 30.0)
    run = generate(find_generator("gesticulator-original"), reqs, tmp_path / "out", config=config, seed=1,
                   progress=False)
    row = run.files[0]
    m = load_motion(tmp_path / "out" / row["file"])
    assert m.fps == pytest.approx(30.0)
    assert m.n_frames == reqs[0].n_frames
    assert any(n["rule"] == "fps" and n["from_fps"] == pytest.approx(20.0) for n in row["notes"])
    meta = row["meta"]
    assert meta["feature_type"] == "Spectro"
    last_end = reqs[0].transcript.words[-1].end
    assert meta["native_frames"] == 2 * int(last_end * 10) - (2 * int(last_end * 10)) % 2
    assert meta["held_last_frames"] > 0   # the speech ends before the segment: the tail is held
    assert meta["native_frames"] + meta["held_last_frames"] == round(reqs[0].duration * 20)
    # what the stub original received: the segment's wav, Google ASR JSON, the local BERT folder
    entry = stub_log(config)[0]
    assert pathlib.Path(entry["audio"]).resolve() == pathlib.Path(reqs[0].audio).resolve()
    words = entry["transcript"][0]["alternatives"][0]["words"]
    assert [w["word"].rstrip(".") for w in words] == [w.text for w in reqs[0].transcript.words]
    assert words[-1]["word"].endswith(".")
    bert = pathlib.Path(config["bert"]).resolve()
    assert [(c, pathlib.Path(f).resolve()) for c, f in entry["embedding"]] == [("BertTokenizer", bert), ("BertModel", bert)]


def test_segment_without_words_is_a_precise_error(tmp_path):
    config = make_stub(tmp_path / "stub")
    corpus = tiny_corpus(tmp_path / "corpus")
    req = replace(requests_from_corpus(corpus, "test", 20.0)[0], transcript=Transcript(()))
    with pytest.raises(GeneratorError, match="needs a transcript with at least one word"):
        generate(find_generator("gesticulator-original"), [req], tmp_path / "out", config=config, progress=False)


def test_failing_original_reports_exit_code_and_stderr_tail(tmp_path):
    config = make_stub(tmp_path / "stub", fail=True)
    corpus = tiny_corpus(tmp_path / "corpus")
    reqs = requests_from_corpus(corpus, "test", 20.0)
    with pytest.raises(GeneratorError, match=r"gesticulator-original, segment 'seg05': the command failed with "
                                             r"exit code 255; stderr \(last lines\):\n(.|\n)*ERROR: "
                                             r"GesticulatorModel.forward\(\) returned None!"):
        generate(find_generator("gesticulator-original"), reqs, tmp_path / "out", config=config, progress=False)


# -- options ---------------------------------------------------------------------------------------------------
def _load(config):
    GesticulatorOriginal().load(config)


def test_missing_and_invalid_options_are_precise(tmp_path):
    good = make_stub(tmp_path / "stub")
    _load(good)  # valid
    for name in ("repo", "python", "checkpoint", "bert"):
        with pytest.raises(GeneratorError, match=f"the option '{name}' is required"):
            _load({k: v for k, v in good.items() if k != name})
    nowhere = str(tmp_path / "nowhere")
    cases = {
        "repo": (nowhere, "option 'repo': .*nowhere is not a folder; expected your clone of the original"),
        "python": (nowhere, "option 'python': .*nowhere is not an executable file; expected the Python interpreter"),
        "checkpoint": (nowhere, "option 'checkpoint': .*nowhere is not a file; expected a trained Gesticulator"),
        "bert": (nowhere, "option 'bert': .*nowhere is not a folder; expected bert-base-cased saved with "
                          "save_pretrained"),
    }
    for name, (value, message) in cases.items():
        with pytest.raises(GeneratorError, match=message):
            _load({**good, name: value})
    # a folder that is not a clone of the original
    with pytest.raises(GeneratorError, match=r"option 'repo': .* is not a clone of the original Gesticulator "
                                             r"repository: missing gesticulator/model/model.py"):
        _load({**good, "repo": str(tmp_path)})
    # a BERT folder saved in the safetensors format only
    bert = pathlib.Path(good["bert"])
    (bert / "pytorch_model.bin").rename(bert / "model.safetensors")
    with pytest.raises(GeneratorError, match=r"option 'bert': .* lacks pytorch_model.bin; .*transformers 4.3.2 "
                                             r"reads only pytorch_model.bin"):
        _load(good)
    (bert / "model.safetensors").rename(bert / "pytorch_model.bin")
    for bad in (0, -5, "soon", True):
        with pytest.raises(GeneratorError, match="option 'timeout' must be a positive number of seconds"):
            _load({**good, "timeout": bad})
    with pytest.raises(GeneratorError, match=r"unknown option\(s\) command"):
        _load({**good, "command": "x"})


# -- what it says about itself; the driver's portability ---------------------------------------------------
def test_info_says_citation_licence_inputs_fps_and_install():
    result = CliRunner().invoke(main, ["generators", "info", "gesticulator-original"])
    assert result.exit_code == 0, result.output
    out = result.output
    for text in ("citation:", "Kucherenko", "licence:", "GPL-3", "out of process", "inputs:",
                 "audio required, transcript required", "bvh at 20 fps", "Python 3.6", "torch 1.4.0",
                 "pytorch-lightning 0.8.5", "bert-base-cased", "checkpoint", "repo:", "python:", "bert:", "timeout:"):
        assert text in out, text


def test_driver_is_python36_stdlib_only():
    source = DRIVER.read_text(encoding="utf-8")
    tree = ast.parse(source, feature_version=(3, 6))
    imported = {a.name.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    imported |= {n.module.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and n.module}
    assert imported <= {"argparse", "json", "os", "sys", "traceback", "gesticulator", "motion_visualizer"}, imported
    assert "from __future__" not in source
