"""Study definitions (YAML or JSON) and stimulus manifests (CSV), validated at load time.

A study definition names the stimulus manifest, the crowd platform, the completion codes and
an ordered list of pages. Rating pages (``pairwise``, ``mushra``, ``likert``) are *blocks*:
the session-plan builder (:mod:`study_app.design`) expands each into several pages per
participant. See ``docs/study_app.md`` for the full schema.

Every problem is raised as :class:`~study_app.errors.StudyDefinitionError` naming the file,
the field path (``pages[2].levels``) and what was expected.
"""
from __future__ import annotations

import csv
import hashlib
import pathlib
import re

from study_app.embodiment import embodiment_columns
from study_app.errors import StudyDefinitionError
from study_app.model import MANIFEST_KINDS, MANIFEST_REQUIRED, PLATFORMS, Manifest, Page, Stimulus, Study
from study_app.outcomes import load_outcomes
from study_app.pages import get_kind, page_kinds
from study_app.pages.pairwise import PAIRWISE_ANSWERS
from study_app.parse import MAX_FILE_BYTES, parse_definition
from study_app.schema import Checker, describe

MAX_SESSIONS = 5_000   # plans for 5,000 sessions take about a second to build; 100,000 took half a minute

__all__ = ["load_study", "load_manifest", "Study", "Manifest", "Stimulus", "Page", "PAIRWISE_ANSWERS"]


def _read_text(path: pathlib.Path, missing: str, encoding: str) -> tuple[bytes, str]:
    """A definition file's bytes (for its hash) and text, or a StudyDefinitionError saying it is
    missing or not UTF-8."""
    name = str(path)
    if "\x00" in name or any(len(part) > 255 for part in path.parts):
        raise StudyDefinitionError("not a usable file name (a NUL byte, or a part longer than 255 characters)",
                                   path=repr(name)[:200])
    try:
        exists = path.is_file()
    except (ValueError, OSError) as exc:
        raise StudyDefinitionError(f"not a usable file name ({exc})", path=repr(name)[:200]) from None
    if not exists:
        raise StudyDefinitionError(missing, path=path)
    if encoding == "utf-8" and path.stat().st_size > MAX_FILE_BYTES:
        raise StudyDefinitionError(f"{path.stat().st_size:,} bytes; a study definition is a few kilobytes (limit "
                                   f"{MAX_FILE_BYTES:,} bytes)", path=path)
    raw = path.read_bytes()
    try:
        return raw, raw.decode(encoding)
    except UnicodeDecodeError as exc:
        raise StudyDefinitionError(f"not UTF-8 text ({exc.reason})", path=path) from None


# ----------------------------------------------------------------------------------- manifest

def load_manifest(path) -> Manifest:
    """Read a stimulus manifest CSV (columns ``file, condition, segment`` and optionally
    ``kind, expected, check, motion_segment, block, duration_s``); file names are relative to its folder."""
    path = pathlib.Path(path)
    raw, text = _read_text(path, "stimulus manifest not found; expected a CSV file", "utf-8-sig")
    reader = csv.DictReader(text.splitlines())
    header = [h.strip() for h in (reader.fieldnames or [])]
    missing = [c for c in MANIFEST_REQUIRED if c not in header]
    if missing:
        raise StudyDefinitionError(
            f"missing column(s) {', '.join(missing)}; expected a header with at least "
            f"{', '.join(MANIFEST_REQUIRED)}", path=path, line=1)
    root = path.parent.resolve()
    stimuli: list[Stimulus] = []
    seen_files: dict[str, int] = {}
    seen_keys: dict[tuple, int] = {}
    for lineno, row in enumerate(reader, start=2):
        row = {(k or "").strip(): (v or "").strip() for k, v in row.items() if k is not None}
        if not any(row.values()):
            continue
        kind = row.get("kind") or "stimulus"
        if kind not in MANIFEST_KINDS:
            raise StudyDefinitionError(f"expected one of {', '.join(MANIFEST_KINDS)}, got {kind!r}",
                                       path=path, line=lineno, field="kind")
        for col in MANIFEST_REQUIRED:
            # Attention-check clips belong to no condition: theirs may stay empty.
            if not row.get(col) and not (col == "condition" and kind == "attention"):
                raise StudyDefinitionError("empty value; expected a non-empty string",
                                           path=path, line=lineno, field=col)
        file = row["file"]
        _check_file_name(file, root, path, lineno)
        if file in seen_files:
            raise StudyDefinitionError(f"duplicate file, already on line {seen_files[file]}",
                                       path=path, line=lineno, field="file")
        seen_files[file] = lineno
        stim = Stimulus(file=file, condition=row["condition"], segment=row["segment"], kind=kind,
                        expected=row.get("expected", ""), motion_segment=row.get("motion_segment", ""),
                        block=row.get("block", ""), duration_s=_duration(row.get("duration_s", ""), path, lineno),
                        check=row.get("check", ""), line=lineno)
        if kind == "attention" and not stim.expected:
            raise StudyDefinitionError("attention-check rows need the answer an attentive "
                                       "participant gives", path=path, line=lineno, field="expected")
        if kind == "stimulus":
            key = (stim.condition, stim.segment, stim.motion_segment if stim.mismatched else "")
            if key in seen_keys:
                raise StudyDefinitionError(
                    f"condition {stim.condition!r} segment {stim.segment!r} already on line "
                    f"{seen_keys[key]}; expected one file per condition, segment (and motion_segment)",
                    path=path, line=lineno, field="file")
            seen_keys[key] = lineno
        stimuli.append(stim)
    if not stimuli:
        raise StudyDefinitionError("no stimuli; expected at least one data row", path=path)
    conditions = {s.condition for s in stimuli if s.kind == "stimulus"}
    for s in stimuli:
        leaked = _condition_in_name(s.file, conditions)
        if leaked:
            raise StudyDefinitionError(
                f"file name {s.file!r} contains the condition name {leaked!r}; expected blinded "
                "file names (participants see them)", path=path, line=s.line, field="file")
    return Manifest(path=path, root=root, stimuli=stimuli, sha256=hashlib.sha256(raw).hexdigest(),
                    embodiment=embodiment_columns(csv.DictReader(text.splitlines())))


def _duration(text: str, path, lineno) -> float | None:
    if not text:
        return None
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not 0 < value < 1e6:
        raise StudyDefinitionError(f"expected a clip length in seconds (a positive number), got {text!r}",
                                   path=path, line=lineno, field="duration_s")
    return value


def _check_file_name(file: str, root: pathlib.Path, path, lineno):
    p = pathlib.PurePosixPath(file)
    if "\x00" in file or len(file) > 255 or any(len(part) > 255 for part in p.parts):
        raise StudyDefinitionError(f"{file[:60]!r}{'...' if len(file) > 60 else ''} is not a usable file name "
                                   "(a NUL byte, or longer than 255 characters)", path=path, line=lineno, field="file")
    if p.is_absolute() or "\\" in file or any(part in ("..", "") for part in p.parts) or ":" in file:
        raise StudyDefinitionError(f"{file!r} is not a relative path inside the manifest's folder",
                                   path=path, line=lineno, field="file")
    full = (root / file).resolve()
    if not full.is_relative_to(root):
        raise StudyDefinitionError(f"{file!r} points outside the manifest's folder",
                                   path=path, line=lineno, field="file")
    if not full.is_file():
        raise StudyDefinitionError(f"{file!r} does not exist; expected a video file next to the "
                                   "manifest", path=path, line=lineno, field="file")


def _condition_in_name(file: str, conditions) -> str | None:
    tokens = [t for t in re.split(r"[^A-Za-z0-9]+", file.lower()) if t]
    stem = pathlib.PurePosixPath(file).stem.lower()
    for c in sorted(conditions):
        cl = c.lower()
        if cl in tokens or (len(cl) >= 3 and cl in stem):
            return c
    return None


# --------------------------------------------------------------------------------- definition

def load_study(path) -> Study:
    """Load and validate a study definition (``.yaml``, ``.yml`` or ``.json``)."""
    path = pathlib.Path(path)
    raw, text = _read_text(path, "study definition not found; expected a YAML or JSON file", "utf-8")
    data = parse_definition(path, text)
    chk = Checker(path)
    if not isinstance(data, dict):
        chk.fail("", f"expected a mapping at the top level, got {describe(data)}")
    chk.unknown_keys(data, TOP_LEVEL_KEYS, "")
    study_id = chk.ident(data, "id", "")
    manifest_rel = chk.get(data, "stimuli", "", str, required=True,
                           expected="the path of the stimulus manifest CSV")
    manifest_path = (path.parent / manifest_rel)
    try:
        manifest = load_manifest(manifest_path)
    except StudyDefinitionError:
        raise
    platform = chk.get(data, "platform", "", str, default="anonymous")
    if platform not in PLATFORMS:
        chk.fail("platform", f"expected one of {', '.join(PLATFORMS)}, got {platform!r}")
    study = Study(
        id=study_id,
        title=chk.get(data, "title", "", str, default=study_id),
        path=path.resolve(),
        manifest=manifest,
        pages=[],
        platform=platform,
        sessions=chk.int_range(data, "sessions", "", 1, MAX_SESSIONS, default=10),
        seed=chk.int_range(data, "seed", "", 0, 2**31 - 1, default=0),
        completion_code=chk.get(data, "completion_code", "", str, default=""),
        failure_code=chk.get(data, "failure_code", "", str, default=""),
        max_failed_attention_checks=chk.int_range(data, "max_failed_attention_checks", "", 1, 1000,
                                                  default=2),
        reservation_minutes=float(chk.get(data, "reservation_minutes", "", (int, float), default=100)),  # <= 1e15
        require_full_playback=chk.get(data, "require_full_playback", "", bool, default=True),
        min_width=chk.int_range(data, "min_width", "", 0, 10000, default=1100),
        block_mobile=chk.get(data, "block_mobile", "", bool, default=True),
        resume=chk.get(data, "resume", "", bool, default=True),
        release_failed=chk.get(data, "release_failed", "", bool, default=True),
        prolific_study_id=chk.get(data, "prolific_study_id", "", str, default=""),
        redirect_seconds=chk.int_range(data, "redirect_seconds", "", 0, 3600, default=0),
        new_sessions_per_address=chk.int_range(data, "new_sessions_per_address", "", 0, 1_000_000, default=10),
        new_sessions_window_minutes=float(chk.int_range(data, "new_sessions_window_minutes", "", 1, 525_600,
                                                        default=60)),
        playback_min_fraction=float(chk.get(data, "playback_min_fraction", "", (int, float), default=1.0)),
        sha256=hashlib.sha256(raw).hexdigest(),
    )
    if not 0 <= study.playback_min_fraction <= 1:
        chk.fail("playback_min_fraction", f"expected a number from 0 to 1, got {study.playback_min_fraction}")
    if not 0 < study.reservation_minutes <= 525_600:
        chk.fail("reservation_minutes", f"expected a positive number of minutes up to 525600 (a year), got "
                 f"{study.reservation_minutes:g}")
    if study.completion_code and study.completion_code == study.failure_code:
        chk.fail("failure_code", f"the same as completion_code ({study.completion_code!r}); expected a different code, "
                 "or a participant who fails would be paid as one who completed")
    for key in ("completion_code", "failure_code"):
        code = getattr(study, key)
        if code and not re.match(r"^[A-Za-z0-9_-]{1,64}$", code):
            chk.fail(key, f"expected letters, digits, '_' or '-' (at most 64), got {code!r}")
    if study.prolific_study_id and not re.match(r"^[0-9a-fA-F]{24}$", study.prolific_study_id):
        chk.fail("prolific_study_id", f"expected a Prolific study id (24 hexadecimal characters), got "
                 f"{study.prolific_study_id!r}")
    study.outcomes = load_outcomes(chk, data, study.completion_code, study.failure_code)
    study.completion_code = study.outcomes["completed"].code
    if platform in ("prolific", "mturk") and not study.completion_code:
        chk.fail("completion_code", f"missing; expected the completion code for {platform} (or outcomes.completed)")
    pages = chk.get(data, "pages", "", list, required=True, expected="a list of pages")
    if not pages:
        chk.fail("pages", "expected at least one page")
    for i, page in enumerate(pages):
        study.pages.append(_load_page(chk, page, f"pages[{i}]", study))
    _check_page_order(chk, study)
    return study


TOP_LEVEL_KEYS = ("id", "title", "stimuli", "platform", "sessions", "seed", "completion_code",
                  "failure_code", "max_failed_attention_checks", "reservation_minutes",
                  "require_full_playback", "min_width", "block_mobile", "resume", "release_failed",
                  "prolific_study_id", "redirect_seconds", "new_sessions_per_address",
                  "new_sessions_window_minutes", "playback_min_fraction", "outcomes", "pages")
def _load_page(chk: Checker, page, where: str, study: Study) -> Page:
    kinds = page_kinds()
    if not isinstance(page, dict):
        chk.fail(where, f"expected a mapping with id and type, got {describe(page)}")
    ptype = chk.get(page, "type", where, str, required=True, expected=f"one of {', '.join(kinds)}")
    if ptype not in kinds:
        chk.fail(f"{where}.type", f"expected one of {', '.join(kinds)}, got {ptype!r}")
    kind = kinds[ptype]
    chk.unknown_keys(page, kind.allowed_keys, where)
    pid = chk.ident(page, "id", where)
    cfg = {"title": chk.get(page, "title", where, str, default="") or kind.default_title,
           "text": chk.get(page, "text", where, str, default="") or kind.default_text}
    cfg.update(kind.load(chk, page, where, study))
    return Page(id=pid, type=ptype, cfg=cfg)


def _check_page_order(chk: Checker, study: Study):
    pages = study.pages
    ids = [p.id for p in pages]
    for i, pid in enumerate(ids):
        if ids.index(pid) != i:
            chk.fail(f"pages[{i}].id", f"duplicate page id {pid!r}")
    for kind in page_kinds().values():
        at = [i for i, p in enumerate(pages) if p.type == kind.name]
        if kind.position == "last" and at != [len(pages) - 1]:
            chk.fail(f"pages[{at[0] if at else len(pages) - 1}]",
                     f"expected exactly one page of type {kind.name}, as the last page")
        if kind.position == "first" and at and at != [0]:
            chk.fail(f"pages[{at[-1]}]", f"expected at most one {kind.name} page, as the first page")
    if not study.blocks:
        blocks = [k for k, kind in page_kinds().items() if kind.block]
        chk.fail("pages", f"expected at least one {', '.join(blocks[:-1])} or {blocks[-1]} page")
    for i, p in enumerate(pages):
        get_kind(p.type).check_order(chk, study, i)
