"""The subprocess bridge: run a generator that lives in another environment (original code pinned to Python
3.6 / TensorFlow 1.15 / torch 1.4, or GPL code kept out of this process) through files.

Per segment the runner writes ``request.json`` into a fresh work folder and runs the configured command there
(in the user's own environment, with a timeout). The command writes ``result.json`` naming its motion file;
the runner reads it and applies the usual rules. ``request.json``::

    {"format": "evalsuite-bridge-request/1", "segment_id": "...", "audio": "/abs/path.wav" | null,
     "duration": 12.3, "fps": 30.0, "seed": 123, "sample": 0, "speaker": null,
     "transcript": {"words": [{"word": "hello", "start": 0.1, "end": 0.4, "estimated": false}, ...]} | null,
     "out_dir": "/abs/work/folder"}

``result.json``: ``{"motion": "out.bvh" (relative to out_dir, or absolute; .bvh, .npz, .npy or .csv),
"fps": 20 (needed for .npy/.csv), "joint_names": [...] (for .npy), "meta": {...}}``.
A failing command gives an error with its exit code and the last lines of its stderr.
"""
from __future__ import annotations

import json
import os
import pathlib
import shlex
import subprocess
import tempfile
from collections.abc import Mapping
from typing import Any

from evalsuite.generators.contract import (
    GenerationRequest,
    GenerationResult,
    Generator,
    GeneratorError,
    GeneratorSpec,
)
from evalsuite.motion.io import load_motion

__all__ = ["ExternalCommand", "request_payload", "REQUEST_FORMAT", "STDERR_LINES"]

REQUEST_FORMAT = "evalsuite-bridge-request/1"
STDERR_LINES = 20


def request_payload(req: GenerationRequest, out_dir: pathlib.Path) -> dict[str, Any]:
    words = None
    if req.transcript is not None:
        words = {"words": [{"word": w.text, "start": w.start, "end": w.end, "estimated": w.estimated}
                           for w in req.transcript.words]}
    return {"format": REQUEST_FORMAT, "segment_id": req.segment_id,
            "audio": str(pathlib.Path(req.audio).resolve()) if req.audio else None,
            "duration": req.duration, "fps": req.fps, "seed": req.seed, "sample": req.sample,
            "speaker": req.speaker, "transcript": words, "out_dir": str(out_dir.resolve())}


def _tail(text: str) -> str:
    lines = [ln for ln in text.strip().splitlines() if ln.strip()]
    return "\n".join(lines[-STDERR_LINES:]) if lines else "(nothing)"


class ExternalCommand(Generator):
    spec = GeneratorSpec(
        name="external", version="1", kind="adapter", audio="optional", transcript="optional",
        word_timings="estimated", output="any",
        summary="Runs a command in another environment through request.json / result.json (see docs/generators.md "
                "§ Subprocess bridge).",
        config={"command": "the command, a list or a string; {request}, {out_dir} and {python} are replaced",
                "python": "the interpreter of the other environment (for {python})",
                "timeout_s": "seconds per segment (default 600)", "env": "extra environment variables (a mapping)",
                "cwd": "working folder of the command (default: the segment's work folder)"})

    def load(self, config: Mapping[str, Any], model_dir: pathlib.Path | None = None) -> None:
        super().load(config, model_dir)
        command = self.option("command")
        if not command:
            raise GeneratorError(f"{self.spec.name}: the option 'command' is required", field="command")
        self.command = shlex.split(command) if isinstance(command, str) else [str(c) for c in command]
        env = self.option("env", {}) or {}
        if not isinstance(env, Mapping):
            raise GeneratorError(f"{self.spec.name}: 'env' must be a mapping of names to values", field="env")
        self.env = {str(k): str(v) for k, v in env.items()}

    def _argv(self, request_path: pathlib.Path, out_dir: pathlib.Path) -> list[str]:
        python = str(self.option("python", "python3"))
        return [a.replace("{request}", str(request_path)).replace("{out_dir}", str(out_dir)).replace("{python}", python)
                for a in self.command]

    def run_bridge(self, req: GenerationRequest, out_dir: pathlib.Path) -> dict[str, Any]:
        """Write request.json, run the command, return result.json's content (checked)."""
        request_path = out_dir / "request.json"
        request_path.write_text(json.dumps(request_payload(req, out_dir), indent=1), encoding="utf-8")
        argv = self._argv(request_path, out_dir)
        timeout = self.float_option("timeout_s", 600)
        where = f"{self.spec.name}, segment {req.segment_id!r}"
        try:
            proc = subprocess.run(argv, cwd=self.option("cwd") or out_dir, env={**os.environ, **self.env},
                                  capture_output=True, text=True, timeout=timeout, stdin=subprocess.DEVNULL)
        except FileNotFoundError:
            raise GeneratorError(f"{where}: cannot run {argv[0]!r}: no such program") from None
        except subprocess.TimeoutExpired as exc:
            err = exc.stderr.decode(errors="replace") if isinstance(exc.stderr, bytes) else (exc.stderr or "")
            raise GeneratorError(f"{where}: the command did not finish within {timeout:g} s; "
                                 f"stderr (last lines):\n{_tail(err)}") from None
        if proc.returncode != 0:
            raise GeneratorError(f"{where}: the command failed with exit code {proc.returncode}; "
                                 f"stderr (last lines):\n{_tail(proc.stderr)}")
        result_path = out_dir / "result.json"
        try:
            result = json.loads(result_path.read_text(encoding="utf-8"))
        except OSError:
            raise GeneratorError(f"{where}: the command exited 0 but wrote no result.json in {out_dir}; "
                                 f"stderr (last lines):\n{_tail(proc.stderr)}") from None
        except ValueError as exc:
            raise GeneratorError(f"{where}: result.json is not valid JSON ({exc})") from None
        if not isinstance(result, dict) or not isinstance(result.get("motion"), str):
            raise GeneratorError(f"{where}: result.json must be an object with a 'motion' file name")
        return result

    def generate(self, request: GenerationRequest) -> GenerationResult:
        with tempfile.TemporaryDirectory(prefix="evalsuite-bridge-", dir=request.work_dir) as tmp:
            out_dir = pathlib.Path(tmp)
            result = self.run_bridge(request, out_dir)
            path = pathlib.Path(result["motion"])
            path = path if path.is_absolute() else out_dir / path
            if not path.is_file():
                raise GeneratorError(f"{self.spec.name}, segment {request.segment_id!r}: result.json names "
                                     f"{result['motion']!r}, which the command did not write")
            fps = result.get("fps")
            motion = load_motion(path, fps=float(fps) if fps is not None and path.suffix != ".bvh" else None,
                                 joint_names=result.get("joint_names"))
            meta: dict[str, Any] = result["meta"] if isinstance(result.get("meta"), dict) else {}
            return GenerationResult(motion, {"bridge": self._argv(out_dir / "request.json", out_dir)[0], **meta})
