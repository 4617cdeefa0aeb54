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
import json
import pathlib
import re
from dataclasses import dataclass, field

import yaml

from study_app.errors import StudyDefinitionError

ID_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$")
PAGE_TYPES = ("consent", "instructions", "questionnaire", "headphone_check", "training", "pairwise",
              "mushra", "likert", "finish")
BLOCK_TYPES = ("pairwise", "mushra", "likert")
PLATFORMS = ("prolific", "mturk", "anonymous")
QUESTION_TYPES = ("number", "choice", "text")
DEFAULT_BANDS = ["Bad", "Poor", "Fair", "Good", "Excellent"]
# Screen answers of a pairwise question, 3-level and 5-level.
PAIRWISE_ANSWERS = {3: ("left", "equal", "right"),
                    5: ("left_strong", "left_weak", "equal", "right_weak", "right_strong")}
PAIRWISE_LABELS = {
    3: ("Left", "They are equal", "Right"),
    5: ("Left is clearly better", "Left is slightly better", "They are equal",
        "Right is slightly better", "Right is clearly better"),
}
# Expected answers of a pairwise attention-check stimulus: relative to the side showing the
# check video (this/other) or absolute (left/right/equal); optional strength suffix.
PAIRWISE_EXPECTED_RE = re.compile(r"^(this|other|left|right|equal)(_(strong|weak))?$")
MANIFEST_REQUIRED = ("file", "condition", "segment")
MANIFEST_KINDS = ("stimulus", "attention")


@dataclass(frozen=True)
class Stimulus:
    """One row of the stimulus manifest: a blinded video file and what it shows."""

    file: str
    condition: str
    segment: str
    kind: str = "stimulus"          # "stimulus" or "attention"
    expected: str = ""              # attention checks: the answer an attentive participant gives
    motion_segment: str = ""        # mismatched stimuli: the segment the motion comes from
    block: str = ""                 # attention checks: restrict to this block id
    line: int = 0

    @property
    def mismatched(self) -> bool:
        return bool(self.motion_segment) and self.motion_segment != self.segment


@dataclass
class Manifest:
    path: pathlib.Path
    root: pathlib.Path              # folder the file names are relative to
    stimuli: list[Stimulus]
    sha256: str

    def by_file(self) -> dict[str, Stimulus]:
        return {s.file: s for s in self.stimuli}


@dataclass
class Page:
    """One entry of the definition's ``pages`` list (a block expands to several plan pages)."""

    id: str
    type: str
    cfg: dict = field(default_factory=dict)


@dataclass
class Study:
    id: str
    title: str
    path: pathlib.Path
    manifest: Manifest
    pages: list[Page]
    platform: str = "anonymous"
    sessions: int = 10
    seed: int = 0
    completion_code: str = ""
    failure_code: str = ""
    max_failed_attention_checks: int = 2
    reservation_minutes: float = 100.0
    require_full_playback: bool = True
    min_width: int = 1100
    block_mobile: bool = True
    resume: bool = True
    release_failed: bool = True
    prolific_study_id: str = ""
    redirect_seconds: int = 0
    sha256: str = ""

    @property
    def blocks(self) -> dict[str, Page]:
        return {p.id: p for p in self.pages if p.type in BLOCK_TYPES}

    def page(self, page_id: str) -> Page:
        for p in self.pages:
            if p.id == page_id:
                return p
        raise KeyError(page_id)

    @property
    def conditions(self) -> list[str]:
        """Every condition name a participant must never see (used by leak checks too)."""
        return sorted({s.condition for s in self.manifest.stimuli if s.kind == "stimulus"})

    def completion_url(self, code: str) -> str:
        return f"https://app.prolific.com/submissions/complete?cc={code}"


class _Checker:
    """Small helpers that raise errors naming file and field path."""

    def __init__(self, path):
        self.path = path

    def fail(self, field_path: str, message: str):
        raise StudyDefinitionError(message, path=self.path, field=field_path)

    def get(self, obj: dict, key: str, where: str, types, *, required=False, default=None,
            expected: str = ""):
        fp = f"{where}.{key}" if where else key
        if key not in obj or obj[key] is None:
            if required:
                self.fail(fp, f"missing; expected {expected or _type_name(types)}")
            return default
        value = obj[key]
        # bool is an int subclass: reject True where a number is expected.
        if isinstance(value, bool) and bool not in _as_tuple(types):
            self.fail(fp, f"expected {expected or _type_name(types)}, got {value!r}")
        if not isinstance(value, types):
            self.fail(fp, f"expected {expected or _type_name(types)}, got {_describe(value)}")
        return value

    def ident(self, obj, key, where, *, required=True, default=None):
        value = self.get(obj, key, where, str, required=required, default=default,
                         expected="an id of letters, digits, '_', '-', '.' (at most 64)")
        if value is not None and not ID_RE.match(value):
            self.fail(f"{where}.{key}" if where else key,
                      f"expected an id of letters, digits, '_', '-', '.' (at most 64), got {value!r}")
        return value

    def int_range(self, obj, key, where, lo, hi, *, required=False, default=None):
        value = self.get(obj, key, where, int, required=required, default=default,
                         expected=f"an integer in {lo}..{hi}")
        if value is not None and not lo <= value <= hi:
            self.fail(f"{where}.{key}" if where else key,
                      f"expected an integer in {lo}..{hi}, got {value}")
        return value

    def str_list(self, obj, key, where, *, required=False, default=None, min_len=0):
        fp = f"{where}.{key}" if where else key
        value = self.get(obj, key, where, list, required=required, default=default,
                         expected="a list of strings")
        if value is None:
            return value
        for i, v in enumerate(value):
            if not isinstance(v, str) or not v.strip():
                self.fail(f"{fp}[{i}]", f"expected a non-empty string, got {_describe(v)}")
        if len(value) < min_len:
            self.fail(fp, f"expected at least {min_len} entries, got {len(value)}")
        return value

    def unknown_keys(self, obj: dict, allowed, where: str):
        extra = sorted(set(obj) - set(allowed))
        if extra:
            self.fail(f"{where}.{extra[0]}" if where else extra[0],
                      f"unknown field; expected one of {', '.join(sorted(allowed))}")


def _as_tuple(types):
    return types if isinstance(types, tuple) else (types,)


def _type_name(types) -> str:
    names = {str: "a string", int: "an integer", float: "a number", bool: "true or false",
             list: "a list", dict: "a mapping"}
    return " or ".join(names.get(t, t.__name__) for t in _as_tuple(types))


def _describe(value) -> str:
    return f"{type(value).__name__} {value!r}"[:80]


def _read_text(path: pathlib.Path, missing: str, encoding: str) -> tuple[bytes, str]:
    """A definition file's bytes (for its hash) and text, or a StudyDefinitionError saying it is
    missing or not UTF-8."""
    if not path.is_file():
        raise StudyDefinitionError(missing, path=path)
    raw = path.read_bytes()
    try:
        return raw, raw.decode(encoding)
    except UnicodeDecodeError as exc:
        raise StudyDefinitionError(f"not UTF-8 text ({exc.reason})", path=path) from None


# ----------------------------------------------------------------------------------- manifest

def load_manifest(path) -> Manifest:
    """Read a stimulus manifest CSV (columns ``file, condition, segment`` and optionally
    ``kind, expected, motion_segment, block``); file names are relative to its folder."""
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
    stimuli, seen_files, seen_keys = [], {}, {}
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
                        block=row.get("block", ""), line=lineno)
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
    return Manifest(path=path, root=root, stimuli=stimuli, sha256=hashlib.sha256(raw).hexdigest())


def _check_file_name(file: str, root: pathlib.Path, path, lineno):
    p = pathlib.PurePosixPath(file)
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
    try:
        data = json.loads(text) if path.suffix.lower() == ".json" else yaml.safe_load(text)
    except json.JSONDecodeError as exc:
        raise StudyDefinitionError(f"invalid JSON: {exc.msg}", path=path, line=exc.lineno) from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        raise StudyDefinitionError(f"invalid YAML: {getattr(exc, 'problem', exc)}", path=path,
                                   line=mark.line + 1 if mark else None) from None
    chk = _Checker(path)
    if not isinstance(data, dict):
        chk.fail("", f"expected a mapping at the top level, got {_describe(data)}")
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
        sessions=chk.int_range(data, "sessions", "", 1, 100000, default=10),
        seed=chk.int_range(data, "seed", "", 0, 2**31 - 1, default=0),
        completion_code=chk.get(data, "completion_code", "", str, default=""),
        failure_code=chk.get(data, "failure_code", "", str, default=""),
        max_failed_attention_checks=chk.int_range(data, "max_failed_attention_checks", "", 1, 1000,
                                                  default=2),
        reservation_minutes=float(chk.get(data, "reservation_minutes", "", (int, float), default=100)),
        require_full_playback=chk.get(data, "require_full_playback", "", bool, default=True),
        min_width=chk.int_range(data, "min_width", "", 0, 10000, default=1100),
        block_mobile=chk.get(data, "block_mobile", "", bool, default=True),
        resume=chk.get(data, "resume", "", bool, default=True),
        release_failed=chk.get(data, "release_failed", "", bool, default=True),
        prolific_study_id=chk.get(data, "prolific_study_id", "", str, default=""),
        redirect_seconds=chk.int_range(data, "redirect_seconds", "", 0, 3600, default=0),
        sha256=hashlib.sha256(raw).hexdigest(),
    )
    if study.reservation_minutes <= 0:
        chk.fail("reservation_minutes", f"expected a positive number, got {study.reservation_minutes}")
    for key in ("completion_code", "failure_code"):
        code = getattr(study, key)
        if code and not re.match(r"^[A-Za-z0-9_-]{1,64}$", code):
            chk.fail(key, f"expected letters, digits, '_' or '-' (at most 64), got {code!r}")
    if platform in ("prolific", "mturk") and not study.completion_code:
        chk.fail("completion_code", f"missing; expected the completion code for {platform}")
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
                  "prolific_study_id", "redirect_seconds", "pages")
COMMON_PAGE_KEYS = ("id", "type", "title", "text")
PAGE_KEYS = {
    "consent": COMMON_PAGE_KEYS + ("honeypot", "agree_label"),
    "instructions": COMMON_PAGE_KEYS,
    "questionnaire": COMMON_PAGE_KEYS + ("questions",),
    "finish": COMMON_PAGE_KEYS,
    "headphone_check": COMMON_PAGE_KEYS + ("trials", "pass", "on_fail"),
    "training": COMMON_PAGE_KEYS + ("of", "count", "segments"),
    "pairwise": COMMON_PAGE_KEYS + ("conditions", "pairs", "segments", "mismatched", "levels",
                                    "questions", "reasons", "reasons_required", "pages", "attention_checks",
                                    "muted"),
    "mushra": COMMON_PAGE_KEYS + ("conditions", "reference", "anchor", "segments", "question",
                                  "bands", "pages", "attention_checks", "tolerance", "muted"),
    "likert": COMMON_PAGE_KEYS + ("conditions", "segments", "statements", "points", "labels",
                                  "pages", "attention_checks", "muted"),
}


def _load_page(chk: _Checker, page, where: str, study: Study) -> Page:
    if not isinstance(page, dict):
        chk.fail(where, f"expected a mapping with id and type, got {_describe(page)}")
    ptype = chk.get(page, "type", where, str, required=True, expected=f"one of {', '.join(PAGE_TYPES)}")
    if ptype not in PAGE_TYPES:
        chk.fail(f"{where}.type", f"expected one of {', '.join(PAGE_TYPES)}, got {ptype!r}")
    chk.unknown_keys(page, PAGE_KEYS[ptype], where)
    pid = chk.ident(page, "id", where)
    cfg = {"title": chk.get(page, "title", where, str, default=""),
           "text": chk.get(page, "text", where, str, default="")}
    if ptype == "consent":
        cfg["honeypot"] = chk.get(page, "honeypot", where, bool, default=True)
        cfg["agree_label"] = chk.get(page, "agree_label", where, str,
                                     default="I have read the information above and agree to take part.")
    elif ptype == "questionnaire":
        cfg["questions"] = _load_questions(chk, page, where)
    elif ptype == "headphone_check":
        cfg.update(_load_headphone_check(chk, page, where))
        cfg["title"] = cfg["title"] or "Headphone check"
        cfg["text"] = cfg["text"] or HEADPHONE_TEXT
    elif ptype == "training":
        cfg["of"] = chk.ident(page, "of", where)
        cfg["count"] = chk.int_range(page, "count", where, 1, 100, default=1)
        cfg["segments"] = chk.str_list(page, "segments", where, default=None, min_len=1)
    elif ptype in BLOCK_TYPES:
        cfg.update(_load_block(chk, page, where, ptype, study))
    return Page(id=pid, type=ptype, cfg=cfg)


HEADPHONE_TEXT = (
    "Please put on headphones and set a comfortable volume. Each sound below has three tones. "
    "Play it once (it cannot be repeated) and choose the tone that was the quietest.")
HEADPHONE_ON_FAIL = ("end", "continue")


def _load_headphone_check(chk, page, where) -> dict:
    """Woods et al. (2017) screening: ``trials`` (default 6), ``pass`` = correct answers needed
    (default 5 of 6, their threshold), ``on_fail`` = ``end`` the session with the failure code
    (default) or ``continue`` and only record the outcome."""
    trials = chk.int_range(page, "trials", where, 1, 30, default=6)
    need = chk.int_range(page, "pass", where, 1, 30, default=max(1, round(trials * 5 / 6)))
    if need > trials:
        chk.fail(f"{where}.pass", f"expected at most trials ({trials}), got {need}")
    on_fail = chk.get(page, "on_fail", where, str, default="end",
                      expected=f"one of {', '.join(HEADPHONE_ON_FAIL)}")
    if on_fail not in HEADPHONE_ON_FAIL:
        chk.fail(f"{where}.on_fail", f"expected one of {', '.join(HEADPHONE_ON_FAIL)}, got {on_fail!r}")
    return {"trials": trials, "pass": need, "on_fail": on_fail}


def _load_questions(chk, page, where):
    qs = chk.get(page, "questions", where, list, required=True, expected="a list of questions")
    if not qs:
        chk.fail(f"{where}.questions", "expected at least one question")
    out, ids = [], set()
    for j, q in enumerate(qs):
        qw = f"{where}.questions[{j}]"
        if not isinstance(q, dict):
            chk.fail(qw, f"expected a mapping with id, type and text, got {_describe(q)}")
        chk.unknown_keys(q, ("id", "type", "text", "required", "min", "max", "options", "max_length"), qw)
        qid = chk.ident(q, "id", qw)
        if qid in ids:
            chk.fail(f"{qw}.id", f"duplicate question id {qid!r}")
        ids.add(qid)
        qtype = chk.get(q, "type", qw, str, required=True, expected=f"one of {', '.join(QUESTION_TYPES)}")
        if qtype not in QUESTION_TYPES:
            chk.fail(f"{qw}.type", f"expected one of {', '.join(QUESTION_TYPES)}, got {qtype!r}")
        item = {"id": qid, "type": qtype, "text": chk.get(q, "text", qw, str, required=True),
                "required": chk.get(q, "required", qw, bool, default=True)}
        if qtype == "number":
            item["min"] = chk.get(q, "min", qw, (int, float), default=None)
            item["max"] = chk.get(q, "max", qw, (int, float), default=None)
            if item["min"] is not None and item["max"] is not None and item["min"] > item["max"]:
                chk.fail(f"{qw}.min", f"expected min <= max, got {item['min']} > {item['max']}")
        elif qtype == "choice":
            item["options"] = chk.str_list(q, "options", qw, required=True, min_len=2)
        else:
            item["max_length"] = chk.int_range(q, "max_length", qw, 1, 10000, default=1000)
        out.append(item)
    return out


def _load_block(chk: _Checker, page, where, ptype, study: Study) -> dict:
    manifest = study.manifest
    known_conditions = sorted({s.condition for s in manifest.stimuli if s.kind == "stimulus"})
    conditions = chk.str_list(page, "conditions", where, required=True,
                              min_len=2 if ptype in ("pairwise", "mushra") and not page.get("mismatched") else 1)
    for i, c in enumerate(conditions):
        if c not in known_conditions:
            chk.fail(f"{where}.conditions[{i}]", f"unknown condition {c!r}; expected one of the "
                     f"manifest's conditions: {', '.join(known_conditions)}")
    if len(set(conditions)) != len(conditions):
        chk.fail(f"{where}.conditions", "expected distinct conditions")
    cfg = {"conditions": list(conditions),
           "muted": chk.get(page, "muted", where, bool, default=False),
           "pages": chk.int_range(page, "pages", where, 1, 1000, required=True)}
    all_segments = sorted({s.segment for s in manifest.stimuli if s.kind == "stimulus"})
    segments = chk.str_list(page, "segments", where, default=None, min_len=1)
    for i, s in enumerate(segments or []):
        if s not in all_segments:
            chk.fail(f"{where}.segments[{i}]", f"unknown segment {s!r}; expected one of the "
                     f"manifest's segments")
    if ptype == "mushra":
        for role in ("reference", "anchor"):
            r = chk.get(page, role, where, str, default="")
            if r and r not in known_conditions:
                chk.fail(f"{where}.{role}", f"unknown condition {r!r}; expected one of the manifest's "
                         f"conditions: {', '.join(known_conditions)}")
            if r and r in conditions:
                chk.fail(f"{where}.{role}", f"{r!r} is also in conditions; the hidden {role} is "
                         "added to the page by itself")
            cfg[role] = r
        q = chk.get(page, "question", where, dict, required=True, expected="a mapping with id and text")
        cfg["question"] = {"id": chk.ident(q, "id", f"{where}.question"),
                           "text": chk.get(q, "text", f"{where}.question", str, required=True)}
        cfg["bands"] = chk.str_list(page, "bands", where, default=list(DEFAULT_BANDS), min_len=2)
        cfg["tolerance"] = chk.int_range(page, "tolerance", where, 0, 50, default=3)
    if ptype == "pairwise":
        cfg["mismatched"] = chk.get(page, "mismatched", where, bool, default=False)
        cfg["levels"] = chk.get(page, "levels", where, int, default=3, expected="3 or 5")
        if cfg["levels"] not in (3, 5):
            chk.fail(f"{where}.levels", f"expected 3 or 5, got {cfg['levels']}")
        cfg["questions"] = _load_text_items(chk, page, "questions", where, required=True)
        cfg["reasons"] = _load_text_items(chk, page, "reasons", where, required=False)
        # HEMVIP (GENEA 2023) asks for at least one reason whenever a side is preferred.
        cfg["reasons_required"] = chk.get(page, "reasons_required", where, bool, default=False)
        if cfg["reasons_required"] and not cfg["reasons"]:
            chk.fail(f"{where}.reasons_required", "needs a list of reasons to choose from")
        pairs = chk.get(page, "pairs", where, list, default=None, expected="a list of [condition, condition]")
        if cfg["mismatched"]:
            if pairs is not None:
                chk.fail(f"{where}.pairs", "not allowed with mismatched: true (each page pairs one "
                         "condition's matched and mismatched video)")
        else:
            if pairs is None:
                pairs = [[a, b] for i, a in enumerate(conditions) for b in conditions[i + 1:]]
            for i, pair in enumerate(pairs):
                if (not isinstance(pair, list) or len(pair) != 2 or pair[0] == pair[1]
                        or any(c not in conditions for c in pair)):
                    chk.fail(f"{where}.pairs[{i}]", f"expected two different conditions of this "
                             f"block, got {pair!r}")
            cfg["pairs"] = [list(p) for p in pairs]
    if ptype == "likert":
        cfg["points"] = chk.int_range(page, "points", where, 2, 11, default=7)
        cfg["statements"] = _load_text_items(chk, page, "statements", where, required=True,
                                             extra=("scale",))
        labels = chk.str_list(page, "labels", where, default=None)
        if labels is not None and len(labels) not in (2, cfg["points"]):
            chk.fail(f"{where}.labels", f"expected 2 labels (ends) or {cfg['points']} (one per "
                     f"point), got {len(labels)}")
        cfg["labels"] = labels or ["Strongly disagree", "Strongly agree"]
    # Segments that have a stimulus for every condition the block shows.
    needed = list(conditions) + [cfg.get("reference")] + [cfg.get("anchor")]
    needed = [c for c in needed if c]
    have = {(s.condition, s.segment) for s in manifest.stimuli if s.kind == "stimulus" and not s.mismatched}
    have_mm = {(s.condition, s.segment) for s in manifest.stimuli if s.kind == "stimulus" and s.mismatched}
    usable = []
    for seg in (segments or all_segments):
        ok = all((c, seg) in have for c in needed)
        if cfg.get("mismatched"):
            ok = ok and all((c, seg) in have_mm for c in needed)
        if ok:
            usable.append(seg)
        elif segments:
            missing = [c for c in needed if (c, seg) not in have]
            what = (f"a matched stimulus for {', '.join(missing)}" if missing else
                    "a mismatched stimulus (motion_segment differs) for every condition")
            chk.fail(f"{where}.segments", f"segment {seg!r} lacks {what} in {manifest.path.name}")
    if not usable:
        chk.fail(f"{where}.segments", "no segment has a stimulus for every condition of this block"
                 + ("; mismatched blocks also need mismatched rows (motion_segment)" if cfg.get("mismatched") else ""))
    cfg["segments"] = usable
    checks = chk.get(page, "attention_checks", where, list, default=[],
                     expected="a list of positions within the block")
    for i, pos in enumerate(checks):
        if isinstance(pos, bool) or not isinstance(pos, int) or not 0 < pos <= cfg["pages"]:
            chk.fail(f"{where}.attention_checks[{i}]", f"expected an integer in 1..{cfg['pages']} "
                     "(a check is never the first page of a block), got " + _describe(pos))
    if len(set(checks)) != len(checks):
        chk.fail(f"{where}.attention_checks", "expected distinct positions")
    cfg["attention_checks"] = sorted(checks)
    if checks:
        pool = attention_pool(manifest, page["id"] if isinstance(page.get("id"), str) else "", ptype, cfg)
        if not pool:
            chk.fail(f"{where}.attention_checks", f"no attention-check stimulus in {manifest.path.name} "
                     f"fits a {ptype} page (kind=attention with a valid expected answer"
                     + (", segment of this block" if ptype == "mushra" else "") + ")")
    return cfg


def _load_text_items(chk, page, key, where, *, required, extra=()):
    items = chk.get(page, key, where, list, required=required, default=[],
                    expected="a list of {id, text}")
    if required and not items:
        chk.fail(f"{where}.{key}", "expected at least one entry")
    out, ids = [], set()
    for j, it in enumerate(items):
        iw = f"{where}.{key}[{j}]"
        if not isinstance(it, dict):
            chk.fail(iw, f"expected a mapping with id and text, got {_describe(it)}")
        chk.unknown_keys(it, ("id", "text") + extra, iw)
        iid = chk.ident(it, "id", iw)
        if iid in ids:
            chk.fail(f"{iw}.id", f"duplicate id {iid!r}")
        ids.add(iid)
        entry = {"id": iid, "text": chk.get(it, "text", iw, str, required=True)}
        for e in extra:
            entry[e] = chk.get(it, e, iw, str, default="")
        out.append(entry)
    return out


def attention_pool(manifest: Manifest, block_id: str, ptype: str, cfg: dict) -> list[Stimulus]:
    """Attention-check stimuli usable on pages of this block."""
    out = []
    for s in manifest.stimuli:
        if s.kind != "attention" or (s.block and s.block != block_id):
            continue
        if ptype == "pairwise":
            m = PAIRWISE_EXPECTED_RE.match(s.expected)
            ok = bool(m) and not (m.group(2) and cfg["levels"] == 3)
        elif ptype == "mushra":
            ok = (_mushra_expected(s.expected, cfg["bands"]) is not None
                  and s.segment in cfg["segments"])
        else:
            ok = s.expected.isdigit() and 1 <= int(s.expected) <= cfg["points"]
        if ok:
            out.append(s)
    return out


def _mushra_expected(expected: str, bands: list[str]):
    """(lo, hi) interval an attentive rating falls in before tolerance, or None."""
    if expected.isdigit() and 0 <= int(expected) <= 100:
        return (int(expected), int(expected))
    names = [b.lower() for b in bands]
    if expected.lower() in names:
        k = names.index(expected.lower())
        width = 100 / len(bands)
        return (k * width, (k + 1) * width)
    return None


def mushra_check_passes(expected: str, rating: int, bands: list[str], tolerance: int) -> bool:
    lo, hi = _mushra_expected(expected, bands)
    return lo - tolerance <= rating <= hi + tolerance


def _check_page_order(chk: _Checker, study: Study):
    pages = study.pages
    ids = [p.id for p in pages]
    for i, pid in enumerate(ids):
        if ids.index(pid) != i:
            chk.fail(f"pages[{i}].id", f"duplicate page id {pid!r}")
    finishes = [i for i, p in enumerate(pages) if p.type == "finish"]
    if finishes != [len(pages) - 1]:
        chk.fail(f"pages[{finishes[0] if finishes else len(pages) - 1}]",
                 "expected exactly one page of type finish, as the last page")
    consents = [i for i, p in enumerate(pages) if p.type == "consent"]
    if consents and consents != [0]:
        chk.fail(f"pages[{consents[-1]}]", "expected at most one consent page, as the first page")
    blocks = study.blocks
    if not blocks:
        chk.fail("pages", "expected at least one pairwise, mushra or likert page")
    for i, p in enumerate(pages):
        if p.type == "training":
            if p.cfg["of"] not in blocks:
                chk.fail(f"pages[{i}].of", f"expected the id of a pairwise, mushra or likert page, "
                         f"got {p.cfg['of']!r}")
            target = blocks[p.cfg["of"]]
            for j, s in enumerate(p.cfg["segments"] or []):
                if s not in target.cfg["segments"]:
                    chk.fail(f"pages[{i}].segments[{j}]", f"segment {s!r} has no stimulus for every "
                             f"condition of {target.id!r}")
