"""Study stimuli in batch: every condition x segment, attention checks, blinded names, manifest.

A YAML (or JSON) config says what to render (paths relative to the config file)::

    output: stimuli                      # videos + manifest.csv go here
    segments: [seg01, seg02]             # or {seg01: {start: 0, end: 8}, ...}
    conditions:                          # name -> motion file; {segment} is filled in
      natural: conditions/natural/{segment}.bvh
      baseline: conditions/baseline/{segment}.bvh
    audio: audio/{segment}.wav           # optional; cut with the motion (start-end)
    start: 0                             # optional cut (seconds) for every segment
    end: 10
    render: {width: 640, height: 480, view: front, framing: upper, fps: 30,
             style: mannequin, face: blank}  # style: stick, mannequin, character (+ character: FILE) or a plug-in's
    mute: false                          # true: videos without sound even where segments have audio
    attention_checks:
      - {check: instruction, segment: seg01, condition: natural,
         text: "Attention: please rate this video 73", expected: "73", appear_s: 3}
      - {check: distorted_audio, segment: seg02, condition: baseline, expected: bad}
      - {check: distorted_video, segment: seg01, condition: baseline}
    equal_size: cbr                      # optional: off (default), pad, or cbr (constant bitrate, then pad)
    bitrate: 400k                        # the bitrate of equal_size: cbr

Output names are blinded: ``v`` + 12 hex digits of an HMAC of the condition, segment and
check under a secret key kept in ``<output>/.blinding-key`` (created on first run), so
names are stable across runs but reveal nothing. ``manifest.csv`` maps them back; keep it
(and the key) away from participants.

A video is re-rendered only when its *input hash* changed: a SHA-256 over the motion and
audio file contents, the render settings, the segment's shared camera, the cut and the
renderer version, as recorded in the previous manifest (and the file's own SHA-256 still
matches).

``equal_size`` makes a file's size reveal nothing (:mod:`renderers.filesize`): ``pad`` brings the videos of each
segment (its stimuli and attention checks, what one study page shows) to one size with a trailing ``free``
box; ``cbr`` encodes at a constant ``bitrate`` first, so the padding stays small.
"""
from __future__ import annotations

import csv
import hashlib
import hmac
import json
import os
import pathlib
import secrets
import warnings

from tqdm import tqdm

from evalsuite.contracts import manifest as manifest_contract
from evalsuite.errors import InputError
from evalsuite.hashing import file_sha256
from evalsuite.parallel import run
from renderers.filesize import pad_group
from renderers.stimuli_config import load_config

# Part of every input hash: bump it when a change to the renderer changes how videos look.
# 2: audio cut with the motion; non-body joints left out. 3: body styles, the camera aimed at the mean root,
# above-knees framing, floor shaded like the figures
RENDERER_VERSION = "evalsuite-renderers-3"
MANIFEST_COLUMNS = list(manifest_contract.COLUMNS)


# ------------------------------------------------------------------------------- paths

def _resolve(base: pathlib.Path, pattern: str, segment: str) -> pathlib.Path:
    try:
        rel = pattern.format(segment=segment)
    except (KeyError, IndexError, ValueError) as exc:
        raise InputError(f"bad path pattern {pattern!r} ({exc}); the only placeholder is {{segment}}") from None
    return (base / rel).resolve()


# ------------------------------------------------------------------------------- blinding

def blinding_key(output: pathlib.Path) -> bytes:
    """The secret key of this output folder (created on first use)."""
    key_file = output / ".blinding-key"
    if key_file.is_file():
        return key_file.read_text().strip().encode()
    output.mkdir(parents=True, exist_ok=True)
    key = secrets.token_hex(32)
    key_file.write_text(key + "\n")
    return key.encode()


def blinded_name(key: bytes, conditions, *parts: str) -> str:
    """``v<12 hex>.mp4`` from an HMAC of ``parts``; never contains a condition name."""
    banned = [c.lower() for c in conditions if len(c) >= 2]
    for attempt in range(1000):
        msg = "\x1f".join(parts + (str(attempt),)).encode()
        stem = "v" + hmac.new(key, msg, hashlib.sha256).hexdigest()[:12]
        if not any(b in stem for b in banned):
            return stem + ".mp4"
    raise InputError("could not find a blinded name free of condition names; rename the conditions")


# ------------------------------------------------------------------------------- jobs

def plan(cfg: dict) -> tuple[list[dict], list[dict]]:
    """Render jobs (one per condition x segment) and attention-check jobs, JSON-serialisable."""
    from renderers.render import prepare_motions, view_for

    settings = cfg["settings"]
    out = cfg["output"]
    bitrate = cfg.get("bitrate") if cfg.get("equal_size") == "cbr" else None
    key = blinding_key(out)
    conds = list(cfg["conditions"])
    if cfg.get("mute") and any(chk["check"] == "distorted_audio" for chk in cfg["checks"]):
        raise InputError("the stimuli are muted (mute: true): a distorted_audio attention check has no sound to "
                         "distort; use distorted_video or instruction", field="attention_checks")
    character = ""
    if settings.character:
        if not pathlib.Path(settings.character).is_file():
            raise InputError("character file not found", path=settings.character, field="render.character")
        character = file_sha256(settings.character)
    render_jobs, by_pair = [], {}
    embodiment = embodiment_of(settings)
    for seg, opts in cfg["segments"].items():
        paths = {c: _resolve(cfg["base"], cfg["conditions"][c], seg) for c in conds}
        for c, p in paths.items():
            if not p.is_file():
                raise InputError(f"motion file of condition {c!r}, segment {seg!r} not found", path=p)
        audio = _resolve(cfg["base"], opts["audio"], seg) if opts.get("audio") and not cfg.get("mute") else None
        if audio is not None and not audio.is_file():
            raise InputError(f"audio of segment {seg!r} not found", path=audio)
        motions = prepare_motions([paths[c] for c in conds], settings, opts["start"], opts["end"])
        view = view_for(motions, settings).to_dict()   # shared by every condition of the segment
        audio_hash = file_sha256(audio) if audio else ""
        for c in conds:
            file = blinded_name(key, conds, "stimulus", c, seg)
            spec = {"kind": "render", "file": file, "out": str(out / file), "condition": c, "segment": seg,
                    "motion": str(paths[c]), "audio": str(audio) if audio else None,
                    "start": opts["start"], "end": opts["end"], "settings": settings.to_dict(), "view": view,
                    "bitrate": bitrate, "embodiment": embodiment}
            spec["input_hash"] = _hash({"v": RENDERER_VERSION, "motion": file_sha256(paths[c]), "audio": audio_hash,
                                        **({"character": character} if character else {}),
                                        "settings": spec["settings"], "view": view, "start": spec["start"],
                                        "end": spec["end"], **({"bitrate": bitrate} if bitrate else {})})
            render_jobs.append(spec)
            by_pair[(c, seg)] = spec
    attention_jobs = []
    for chk in cfg["checks"]:
        src = by_pair[(chk["condition"], chk["segment"])]
        file = blinded_name(key, conds, "attention", chk["check"], chk["condition"], chk["segment"],
                            str(chk["index"]))
        spec = {"kind": "attention", "file": file, "out": str(out / file), "src": src["out"],
                "source_file": src["file"], "condition": chk["condition"], "segment": chk["segment"],
                "check": chk["check"], "text": chk["text"], "expected": chk["expected"],
                "appear_s": chk["appear_s"], "seed": chk["index"], "crf": settings.crf, "bitrate": bitrate,
                "embodiment": embodiment}
        spec["input_hash"] = _hash({"v": RENDERER_VERSION, "src": src["input_hash"], "check": chk["check"],
                                    "text": chk["text"], "appear_s": chk["appear_s"], "seed": chk["index"],
                                    **({"bitrate": bitrate} if bitrate else {})})
        attention_jobs.append(spec)
    return render_jobs, attention_jobs


def _hash(obj) -> str:
    return hashlib.sha256(json.dumps(obj, sort_keys=True, default=str).encode()).hexdigest()


def run_job(spec: dict) -> dict:
    """Render one job (in any process: this is what --jobs and --dask workers run)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        if spec["kind"] == "render":
            from renderers.render import prepare_motions, render_video
            from renderers.scene import RenderSettings, View

            settings = RenderSettings.from_dict(spec["settings"])
            motions = prepare_motions([spec["motion"]], settings, spec["start"], spec["end"])
            info = render_video(motions, spec["out"], settings, audio=spec["audio"],
                                view=View.from_dict(spec["view"]), label=f"{spec['condition']}/{spec['segment']}",
                                bitrate=spec.get("bitrate"))
            info.pop("view")
        else:
            from renderers.attention import make_attention_check

            info = make_attention_check(spec["src"], spec["out"], spec["check"], text=spec["text"] or None,
                                        appear_s=spec["appear_s"], seed=spec["seed"], crf=spec["crf"],
                                        bitrate=spec.get("bitrate"))
    info["sha256"] = file_sha256(spec["out"])
    info["warnings"] = [str(w.message) for w in caught if issubclass(w.category, UserWarning)]
    return info


# ------------------------------------------------------------------------------- manifest

def read_manifest(path) -> dict[str, dict]:
    """Rows of an existing manifest by file name (empty if there is none)."""
    path = pathlib.Path(path)
    if not path.is_file():
        return {}
    with open(path, newline="", encoding="utf-8") as f:
        return {row["file"]: row for row in csv.DictReader(f) if row.get("file")}


def _up_to_date(spec: dict, old: dict[str, dict]) -> bool:
    row = old.get(spec["file"])
    out = pathlib.Path(spec["out"])
    return bool(row and row.get("input_hash") == spec["input_hash"] and out.is_file()
                and row.get("sha256") == file_sha256(out))


def _row(spec: dict, info: dict) -> dict:
    att = spec["kind"] == "attention"
    return {"file": spec["file"], "condition": spec["condition"], "segment": spec["segment"],
            "kind": "attention" if att else "stimulus", "expected": spec.get("expected", "") if att else "",
            "sha256": info["sha256"], "check": spec.get("check", ""), "source_file": spec.get("source_file", ""),
            "motion_segment": "", "text": spec.get("text", ""),
            "appear_s": "" if info.get("appear_s") is None else f"{info['appear_s']:.3f}",
            "duration_s": f"{float(info['duration']):.4f}", "n_frames": int(info["n_frames"]),
            "fps": f"{float(info['fps']):g}", "width": int(info["width"]), "height": int(info["height"]),
            "input_hash": spec["input_hash"], **spec["embodiment"]}


def embodiment_of(settings) -> dict[str, str]:
    """The manifest's embodiment columns (contracts.manifest.EMBODIMENT) for clips rendered with ``settings``; the
    character style names its file, evalsuite's own when ``settings.character`` is unset."""
    character = ""
    if settings.body == "character":
        from renderers.styles.character import DEFAULT_CHARACTER
        character = pathlib.Path(settings.character or DEFAULT_CHARACTER).name
    return {"style": settings.body, "character": character, "framing": settings.framing, "face": settings.face}


def write_manifest(path, rows: list[dict]) -> None:
    path = pathlib.Path(path)
    tmp = path.with_suffix(".csv.tmp")
    with open(tmp, "w", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, fieldnames=MANIFEST_COLUMNS)
        w.writeheader()
        w.writerows(rows)
    os.replace(tmp, path)


def _describe_spec(spec: dict) -> str:
    return f"video {spec['file']}"


def build_stimuli(config, *, jobs: int = 1, dask_address: str | None = None, force: bool = False,
                  echo=print, equal_size: str | None = None, bitrate: str | None = None,
                  mute: bool | None = None) -> dict:
    """Render every condition x segment and the attention checks of ``config``; write the manifest.
    ``equal_size``, ``bitrate`` and ``mute`` override the config's keys of those names.

    Returns ``{"manifest": path, "rendered": n, "skipped": n, "rows": [...]}``.
    """
    cfg = load_config(config)
    cfg.update({k: v for k, v in (("equal_size", equal_size), ("bitrate", bitrate), ("mute", mute)) if v is not None})
    render_jobs, attention_jobs = plan(cfg)
    manifest = cfg["output"] / "manifest.csv"
    old = {} if force else read_manifest(manifest)
    rows, rendered, skipped = {}, 0, 0
    for phase, specs in (("stimuli", render_jobs), ("attention checks", attention_jobs)):
        todo = []
        for s in specs:
            if _up_to_date(s, old):
                rows[s["file"]] = {**old[s["file"]], **s["embodiment"]}   # (a manifest from before the columns)
                skipped += 1
            else:
                todo.append(s)
        if len(todo) < len(specs):
            echo(f"  {phase}: {len(specs) - len(todo)} of {len(specs)} videos are up to date")

        def done(i: int, info: dict, todo: list = todo) -> None:
            nonlocal rendered
            for msg in info.pop("warnings", []):
                tqdm.write(f"Warning: {msg}")
            rows[todo[i]["file"]] = _row(todo[i], info)
            rendered += 1
            # Written after every video, so an interrupted run resumes where it stopped.
            write_manifest(manifest, [rows[s["file"]] for s in render_jobs + attention_jobs if s["file"] in rows])

        # local worker processes are spawned: each opens its own GL context
        run(run_job, todo, jobs=jobs, dask_address=dask_address, desc=phase, unit="video", consume=done,
            describe=_describe_spec)
    ordered = [rows[s["file"]] for s in render_jobs + attention_jobs]
    if cfg["equal_size"] != "off":
        _equal_sizes(cfg["output"], ordered, echo)
    write_manifest(manifest, ordered)
    return {"manifest": manifest, "rendered": rendered, "skipped": skipped, "rows": ordered}


def _equal_sizes(output: pathlib.Path, rows: list[dict], echo) -> None:
    """Pad the files of each segment (its stimuli and attention checks: what one study page shows) to one size
    (:func:`renderers.filesize.pad_group`) and record their new SHA-256 in ``rows``."""
    by_segment: dict[str, list[dict]] = {}
    for r in rows:
        by_segment.setdefault(r["segment"], []).append(r)
    for seg, group in by_segment.items():
        size = pad_group(output / r["file"] for r in group)
        for r in group:
            r["sha256"] = file_sha256(output / r["file"])
        echo(f"  segment {seg}: {len(group)} videos padded to {size:,} bytes each")
