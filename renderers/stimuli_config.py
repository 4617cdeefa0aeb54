"""The stimuli config of :mod:`renderers.stimuli` (YAML or JSON; its format is in that module's doc): read,
checked field by field, paths resolved relative to the config file."""
from __future__ import annotations

import pathlib
import re

import yaml

from evalsuite.errors import InputError
from renderers.attention import CHECKS, DEFAULT_TEXT

DEFAULT_EXPECTED = {"instruction": "73", "distorted_audio": "bad", "distorted_video": "bad"}
# Stimulus files of one segment made equally large (renderers.filesize): not at all, padded, or
# constant-bitrate encoded and padded; the bitrate of "cbr".
EQUAL_SIZE = ("off", "pad", "cbr")
DEFAULT_BITRATE = "400k"
BITRATE_RE = re.compile(r"^[1-9][0-9]*(\.[0-9]+)?[kM]$")
_NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]*$")


def load_config(path) -> dict:
    """Read and validate a stimuli config; returns it with absolute paths resolved."""
    path = pathlib.Path(path)
    if not path.is_file():
        raise InputError("no such config file", path=path)
    try:
        raw = yaml.safe_load(path.read_text(encoding="utf-8"))
    except yaml.YAMLError as exc:
        raise InputError(f"not valid YAML/JSON ({exc})", path=path) from None
    if not isinstance(raw, dict):
        raise InputError("expected a mapping at the top level", path=path)
    known = {"output", "segments", "conditions", "audio", "start", "end", "render", "attention_checks", "layout",
             "drop_joints", "equal_size", "bitrate", "mute"}
    unknown = set(raw) - known
    if unknown:
        raise InputError(f"unknown key(s) {', '.join(sorted(unknown))}; expected any of {', '.join(sorted(known))}",
                         path=path)
    base = path.parent
    cfg: dict = {"path": path, "base": base}
    cfg["output"] = (base / str(raw.get("output", "stimuli"))).resolve()
    segs = raw.get("segments")
    if isinstance(segs, list):
        segs = {str(s): {} for s in segs}
    if not isinstance(segs, dict) or not segs:
        raise InputError("expected a non-empty list or mapping of segment names", path=path, field="segments")
    cfg["segments"] = {}
    for name, opts in segs.items():
        opts = opts or {}
        if not isinstance(opts, dict):
            raise InputError("expected a mapping (start, end, audio)", path=path, field=f"segments.{name}")
        _check_name(name, path, f"segments.{name}")
        cfg["segments"][str(name)] = {"start": opts.get("start", raw.get("start")),
                                      "end": opts.get("end", raw.get("end")),
                                      "audio": opts.get("audio", raw.get("audio"))}
    conds = raw.get("conditions")
    if not isinstance(conds, dict) or not conds:
        raise InputError("expected a mapping condition name -> motion path pattern", path=path, field="conditions")
    cfg["conditions"] = {}
    for name, pattern in conds.items():
        _check_name(name, path, f"conditions.{name}")
        if not isinstance(pattern, str):
            raise InputError("expected a path pattern such as 'motion/{segment}.bvh'", path=path,
                             field=f"conditions.{name}")
        cfg["conditions"][str(name)] = pattern
    from renderers.scene import RenderSettings

    render = raw.get("render") or {}
    if not isinstance(render, dict) or (raw.get("drop_joints") is not None and "drop_joints" in render):
        raise InputError("expected a mapping of render settings, with drop_joints there or at the top level, "
                         "not both", path=path, field="render")
    render = {**render, **({"drop_joints": raw["drop_joints"]} if raw.get("drop_joints") is not None else {})}
    if isinstance(render.get("character"), str):   # relative to the config file, like the motion paths
        render["character"] = str((base / render["character"]).resolve())
    try:
        cfg["settings"] = RenderSettings.from_dict(render)
    except TypeError as exc:
        raise InputError(f"bad render settings ({exc})", path=path, field="render") from None
    except InputError as exc:
        raise InputError(exc.reason, path=path, field=f"render.{exc.field}" if exc.field else "render") from None
    cfg["equal_size"] = str(raw.get("equal_size", "off"))
    if cfg["equal_size"] not in EQUAL_SIZE:
        raise InputError(f"expected one of {', '.join(EQUAL_SIZE)}, got {cfg['equal_size']!r}", path=path,
                         field="equal_size")
    bitrate = str(raw.get("bitrate", DEFAULT_BITRATE))
    if not BITRATE_RE.match(bitrate):
        raise InputError(f"expected a bitrate such as 400k or 1.5M, got {bitrate!r}", path=path, field="bitrate")
    cfg["bitrate"] = bitrate
    if not isinstance(raw.get("mute", False), bool):
        raise InputError(f"expected true or false, got {raw['mute']!r}", path=path, field="mute")
    cfg["mute"] = bool(raw.get("mute", False))   # videos without sound (realism studies), even with segment audio
    checks = raw.get("attention_checks") or []
    if not isinstance(checks, list):
        raise InputError("expected a list", path=path, field="attention_checks")
    cfg["checks"] = []
    for i, chk in enumerate(checks):
        where = f"attention_checks[{i}]"
        if not isinstance(chk, dict):
            raise InputError("expected a mapping with check, segment, condition", path=path, field=where)
        kind = chk.get("check")
        if kind not in CHECKS:
            raise InputError(f"expected check to be one of {', '.join(CHECKS)}, got {kind!r}", path=path,
                             field=f"{where}.check")
        seg = str(chk.get("segment", next(iter(cfg["segments"]))))
        cond = str(chk.get("condition", next(iter(cfg["conditions"]))))
        if seg not in cfg["segments"]:
            raise InputError(f"unknown segment {seg!r}", path=path, field=f"{where}.segment")
        if cond not in cfg["conditions"]:
            raise InputError(f"unknown condition {cond!r}", path=path, field=f"{where}.condition")
        text = str(chk.get("text", DEFAULT_TEXT)) if kind == "instruction" else ""
        expected = str(chk.get("expected", _expected_from_text(text) if kind == "instruction"
                               else DEFAULT_EXPECTED[kind]))
        try:
            appear = float(chk.get("appear_s", 3.0))
        except (TypeError, ValueError):
            raise InputError("expected a number of seconds", path=path, field=f"{where}.appear_s") from None
        cfg["checks"].append({"check": kind, "segment": seg, "condition": cond, "text": text,
                              "expected": expected, "appear_s": appear, "index": i})
    return cfg


def _expected_from_text(text: str) -> str:
    """The answer an instruction asks for: its last number, or left/right if it names a side."""
    nums = re.findall(r"\d+", text)
    if nums:
        return nums[-1]
    low = text.lower()
    for side in ("left", "right"):
        if side in low:
            return side
    return DEFAULT_EXPECTED["instruction"]


def _check_name(name, path, field):
    if not isinstance(name, str) or not _NAME_RE.match(name):
        raise InputError(f"expected a name of letters, digits, '_', '-' or '.', got {name!r}", path=path,
                         field=field)
