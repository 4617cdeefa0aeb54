"""``gesticulator-original``: the original Gesticulator, run by the user's own environment through the bridge.

Per segment (see :mod:`evalsuite.generators.bridge`): the transcript goes to ``transcript.json`` in Google ASR
format (:mod:`.transcript`), the bridge writes ``request.json`` and runs ``driver.py`` (shipped here, Python 3.6
compatible) with the user's interpreter; the driver calls the original's code with the checkpoint and the local
BERT folder and writes the original's 20 fps BVH, read back here. The runner's rules resample it to the
requested fps. Nothing of the original (GPL-3) is shipped or imported in this process.
"""
from __future__ import annotations

import os
import pathlib
import shutil
from collections.abc import Mapping
from typing import Any

import numpy as np

from evalsuite.generators.bridge import ExternalCommand
from evalsuite.generators.contract import GenerationRequest, GenerationResult, GeneratorError, GeneratorSpec

__all__ = ["GesticulatorOriginal", "DRIVER", "REPO_FILES", "BERT_FILES"]

DRIVER = pathlib.Path(__file__).with_name("driver.py")
FPS = 20.0
# files of the original repository the driver uses (relative to the clone)
REPO_FILES = ("gesticulator/model/model.py", "gesticulator/interface/gesture_predictor.py",
              "gesticulator/visualization/motion_visualizer/convert2bvh.py", "gesticulator/utils/data_pipe.sav")
BERT_FILES = ("config.json", "vocab.txt", "pytorch_model.bin")
DEFAULT_TIMEOUT = 600.0
# nothing may be downloaded at run time
OFFLINE_ENV = {"TRANSFORMERS_OFFLINE": "1", "HF_HUB_OFFLINE": "1", "HF_DATASETS_OFFLINE": "1"}
INSTALL = ("your clone of Svito-zar/gesticulator with its own environment (Python 3.6, torch 1.4.0, "
           "pytorch-lightning 0.8.5, transformers 4.3.2 ...: `python install_script.py` in the clone), a trained "
           "checkpoint (e.g. the demo's demo/models/default.ckpt) and bert-base-cased saved locally with "
           "save_pretrained (see docs/generators.md)")


class GesticulatorOriginal(ExternalCommand):
    spec = GeneratorSpec(
        name="gesticulator-original", version="1", kind="adapter",
        summary="The ORIGINAL Gesticulator code, run out of process in the user's own Python 3.6 environment "
                "through the subprocess bridge: audio + time-aligned transcript -> the original's 20 fps BVH. "
                f"Install: {INSTALL}.",
        citation="Kucherenko, Jonell, van Waveren, Henter, Alexanderson, Leite, Kjellström (2020). Gesticulator: "
                 "A framework for semantically-aware speech-driven gesture generation. ICMI 2020.",
        license="GPL-3.0 (the original code, which the user installs; it runs out of process and nothing of it "
                "is shipped or imported here; this adapter and its driver: MIT)",
        audio="required", transcript="required", word_timings="estimated", native_fps=FPS, output="bvh",
        skeleton="the original's data_pipe.sav skeleton (Trinity / GENEA 2020 hierarchy; 15 upper-body joints "
                 "animated, the hips fixed at the origin)", units="cm",
        config={"repo": "your clone of the original repository (required; must hold " + ", ".join(REPO_FILES) + ")",
                "python": "the Python interpreter of the original's environment (required; Python 3.6 with its "
                          "requirements installed)",
                "checkpoint": "the trained model file (.ckpt, PyTorch Lightning 0.8.5; required)",
                "bert": "a local bert-base-cased folder written by save_pretrained (required: config.json, "
                        "vocab.txt, pytorch_model.bin; nothing is downloaded at run time)",
                "timeout": f"seconds per segment (default {DEFAULT_TIMEOUT:g})"},
        deviations=("The last word of each segment gets a full stop when it ends with none of . ! ? (the "
                    "original embeds a sentence only at such a word and drops the words after the last one).",
                    "The original generates up to the end of the last word only; the frames after it are held "
                    "from the last generated frame up to the segment's end (noted as held_last_frames).",
                    "Plain text without timings gets the runner's estimated word timings, not the original "
                    "demo's syllable-count spreading."))

    # -- options -------------------------------------------------------------------------------------------
    def _path_option(self, name: str, expected: str) -> pathlib.Path:
        value = self.option(name)
        if value is None or (isinstance(value, str) and not value.strip()):
            raise GeneratorError(f"{self.spec.name}: the option '{name}' is required: {expected}", field=name)
        if not isinstance(value, str | os.PathLike):
            raise GeneratorError(f"{self.spec.name}: the option '{name}' must be a path ({expected}), got "
                                 f"{value!r}", field=name)
        return pathlib.Path(value).expanduser()

    def _check_options(self) -> None:
        name = self.spec.name
        repo = self._path_option("repo", "the folder of your clone of the original Gesticulator repository")
        if not repo.is_dir():
            raise GeneratorError(f"{name}: option 'repo': {repo} is not a folder; expected your clone of the "
                                 "original Gesticulator repository (Svito-zar/gesticulator)", field="repo", path=repo)
        missing = [f for f in REPO_FILES if not (repo / f).is_file()]
        if missing:
            raise GeneratorError(f"{name}: option 'repo': {repo} is not a clone of the original Gesticulator "
                                 f"repository: missing {', '.join(missing)}", field="repo", path=repo)
        python = self._path_option("python", "the Python interpreter of the original's environment")
        exe = str(python) if python.parent != pathlib.Path(".") else shutil.which(str(python))
        if exe is None or not pathlib.Path(exe).is_file() or not os.access(exe, os.X_OK):
            raise GeneratorError(f"{name}: option 'python': {python} is not an executable file; expected the "
                                 "Python interpreter of the environment the original's requirements are installed "
                                 "in (e.g. /path/to/gest_env/bin/python)", field="python", path=python)
        checkpoint = self._path_option("checkpoint", "the trained model file (.ckpt)")
        if not checkpoint.is_file():
            raise GeneratorError(f"{name}: option 'checkpoint': {checkpoint} is not a file; expected a trained "
                                 "Gesticulator checkpoint (.ckpt, e.g. the demo's demo/models/default.ckpt)",
                                 field="checkpoint", path=checkpoint)
        bert = self._path_option("bert", "a local bert-base-cased folder written by save_pretrained")
        if not bert.is_dir():
            raise GeneratorError(f"{name}: option 'bert': {bert} is not a folder; expected bert-base-cased saved "
                                 "with save_pretrained (config.json, vocab.txt, pytorch_model.bin)",
                                 field="bert", path=bert)
        missing = [f for f in BERT_FILES if not (bert / f).is_file()]
        if missing:
            hint = (" (model.safetensors is there, but the original's transformers 4.3.2 reads only "
                    "pytorch_model.bin: save it in the original's environment, see docs/generators.md)"
                    if "pytorch_model.bin" in missing and (bert / "model.safetensors").is_file() else "")
            raise GeneratorError(f"{name}: option 'bert': {bert} lacks {', '.join(missing)}; expected "
                                 f"bert-base-cased saved with save_pretrained{hint}", field="bert", path=bert)
        timeout = self.option("timeout", DEFAULT_TIMEOUT)
        try:
            seconds = float(timeout)
        except (TypeError, ValueError):
            seconds = float("nan")
        if isinstance(timeout, bool) or not seconds > 0 or seconds == float("inf"):
            raise GeneratorError(f"{name}: option 'timeout' must be a positive number of seconds, got {timeout!r}",
                                 field="timeout")
        self.repo, self.python, self.checkpoint, self.bert = repo.resolve(), exe, checkpoint.resolve(), bert.resolve()
        self.timeout = seconds

    def load(self, config: Mapping[str, Any], model_dir: pathlib.Path | None = None) -> None:
        # not ExternalCommand.load: the command is ours, built from the options
        self.configure(config)
        self.model_dir = model_dir
        self._check_options()
        self.command = [self.python, str(DRIVER), "{request}", "--repo", str(self.repo),
                        "--checkpoint", str(self.checkpoint), "--bert", str(self.bert)]
        self.env = dict(OFFLINE_ENV)

    def option(self, name: str, default: Any = None) -> Any:
        # the bridge reads 'timeout_s' and 'cwd'; this plug-in's option is 'timeout', the cwd the work folder
        if name == "timeout_s":
            return getattr(self, "timeout", DEFAULT_TIMEOUT)
        if name == "cwd":
            return None
        return super().option(name, default)

    # -- generation ----------------------------------------------------------------------------------------
    def run_bridge(self, req: GenerationRequest, out_dir: pathlib.Path) -> dict[str, Any]:
        import json

        from evalsuite.generators.gesticulator_original.transcript import google_asr_json

        where = f"{self.spec.name}, segment {req.segment_id!r}"
        if req.audio is None:
            raise GeneratorError(f"{where}: needs the segment's audio (a wav)")
        if req.transcript is None or not google_asr_json(req.transcript):
            raise GeneratorError(f"{where}: needs a transcript with at least one word (Gesticulator embeds the "
                                 "words of the speech; a segment without words cannot be generated)")
        (out_dir / "transcript.json").write_text(json.dumps(google_asr_json(req.transcript), indent=1),
                                                 encoding="utf-8")
        return super().run_bridge(req, out_dir)

    def generate(self, request: GenerationRequest) -> GenerationResult:
        result = super().generate(request)
        motion = result.motion
        want = int(round(request.duration * motion.fps))
        held = max(0, want - motion.n_frames)
        if held and motion.is_hierarchical:
            v = motion.values
            motion = motion.with_values(np.concatenate([v, np.repeat(v[-1:], held, axis=0)]))
        meta = {**result.meta, "native_frames": result.motion.n_frames, "held_last_frames": held,
                "repo": str(self.repo), "checkpoint": str(self.checkpoint)}
        return GenerationResult(motion, meta)
