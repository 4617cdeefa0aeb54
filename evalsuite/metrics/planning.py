"""Planning a scoring run: which files pair with which, which joints and groups, which metrics.

:func:`plan_scoring` lists the motion files of the natural (reference) folder and of each condition
folder (:func:`evalsuite.motion.io.list_motion_files`), pairs them by file name (stem), recognising several
samples of a sequence (``<name>_<k>``, :mod:`evalsuite.metrics.samples`), and decides the joint set;
:func:`resolve_metrics` turns family and metric names into the metric list of the registered families
(:mod:`evalsuite.metrics.families`).
"""
from __future__ import annotations

import pathlib
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

from evalsuite.errors import InputError, did_you_mean
from evalsuite.metrics.families import MetricFamily, metric_index, registered_families
from evalsuite.metrics.samples import split_samples
from evalsuite.motion.io import list_motion_files, load_motion
from evalsuite.motion.presets import PRESETS, resolve_joints

__all__ = ["Plan", "parse_condition", "plan_scoring", "resolve_metrics", "find_group", "resolve_groups",
           "GROUP_PATTERNS", "DEFAULT_GROUPS"]

DEFAULT_GROUPS = ("wrists", "forearms")
# Name patterns for skeletons whose joints the presets do not name (e.g. "LeftWrist", "l_elbow").
GROUP_PATTERNS = {"wrists": r"(wrist|hand)$", "forearms": r"(forearm|elbow|lowarm)$", "hands": r"(wrist|hand)$"}


@dataclass
class Plan:
    """Which files are scored: ``files[condition][sequence] = path``; the reference comes first."""

    reference: str
    conditions: list[str]
    folders: dict[str, pathlib.Path]
    files: dict[str, dict[str, pathlib.Path]]
    names: list[str]
    audio: dict[str, pathlib.Path]
    issues: list[str]
    joints: list[str]
    segments: dict[str, Any] = field(default_factory=dict)   # sequence -> corpus Segment (with --corpus)
    # condition -> sequence -> every sample's file in k order, for sequences with several (<name>_<k> files);
    # files[condition][sequence] is then the first (evalsuite.metrics.samples)
    samples: dict[str, dict[str, list[pathlib.Path]]] = field(default_factory=dict)


def resolve_metrics(spec: str | Sequence[str] | None, audio: bool,
                    families: dict[str, MetricFamily] | None = None, corpus: bool = False) -> list[str]:
    """Metric names from family or metric names (comma-separated string or list).

    Default: every default family's metrics, plus those that need audio when ``audio`` is given and those
    that need a corpus when ``corpus`` is (a corpus brings its audio)."""
    audio = audio or corpus
    fams = registered_families() if families is None else families
    index = metric_index(fams)

    def family_metrics(name: str) -> list[str]:
        return [m.name for m in fams[name].metrics]

    def default_set() -> list[str]:
        return [m for f, fam in fams.items()
                if fam.default or (fam.needs_audio and audio and not fam.needs_corpus) or (fam.needs_corpus and corpus)
                for m in family_metrics(f)]

    if spec is None or spec == "" or spec == ():
        items: list[str] = ["all"]
    else:
        parts = [spec] if isinstance(spec, str) else list(spec)
        items = [s.strip() for part in parts for s in str(part).split(",") if s.strip()]
    out: list[str] = []
    for item in items:
        if item == "all":
            names = default_set()
        elif item in fams:
            names = family_metrics(item)
        elif item in index:
            names = [item]
        else:
            raise InputError(f"unknown metric {item!r}; expected a family ({', '.join(fams)}) or one of their "
                             f"metrics (docs/metrics.md){did_you_mean(item, [*fams, *index])}", field="metrics")
        out.extend(n for n in names if n not in out)
    without = [m for m in out if fams[index[m][0]].needs_corpus]
    if without and not corpus:
        raise InputError(f"{', '.join(without)} need(s) a corpus with the speech and transcripts: pass --corpus DIR "
                         "(segments matched to files by name)", field="metrics")
    needing = [m for m in out if fams[index[m][0]].needs_audio]
    if needing and not audio:
        raise InputError(f"{', '.join(needing)} need(s) speech audio: pass --audio AUDIO_DIR with <sequence>.wav "
                         "files", field="metrics")
    return out


def parse_condition(item: str | pathlib.Path, default_name: str | None = None) -> tuple[str, pathlib.Path]:
    """``"name=path"`` or ``"path"`` (the name is the folder name)."""
    text = str(item)
    if "=" in text and not pathlib.Path(text).exists():
        name, _, folder = text.partition("=")
        if not name or not folder:
            raise InputError(f"expected NAME=FOLDER or FOLDER, got {text!r}", field="condition")
        return name, pathlib.Path(folder)
    path = pathlib.Path(text)
    return default_name or path.resolve().name, path


def _pairing_issues(files: dict[str, dict[str, pathlib.Path]], ref_name: str, conds: Iterable[str],
                    strict: bool) -> list[str]:
    issues: list[str] = []
    ref_names = sorted(files[ref_name])
    for cond in conds:
        missing = [s for s in ref_names if s not in files[cond]]
        extra = sorted(s for s in files[cond] if s not in files[ref_name])
        if missing:
            msg = (f"condition {cond!r} has no file for {len(missing)} of {len(ref_names)} natural sequences: "
                   f"{', '.join(missing[:10])}{' ...' if len(missing) > 10 else ''}")
            if strict or len(missing) == len(ref_names):
                raise InputError(msg + ("" if strict else "; no pairs left to score"), field="pairs")
            issues.append(msg + "; scored on the sequences it has")
        if extra:
            msg = (f"condition {cond!r} has {len(extra)} files with no natural counterpart (ignored): "
                   f"{', '.join(extra[:10])}{' ...' if len(extra) > 10 else ''}")
            if strict:
                raise InputError(msg, field="pairs")
            issues.append(msg)
    return issues


def _audio_files(audio_dir: str | pathlib.Path, ref_names: list[str], issues: list[str]) -> dict[str, pathlib.Path]:
    folder = pathlib.Path(audio_dir)
    if not folder.is_dir():
        raise InputError("audio folder does not exist or is not a folder", path=folder)
    audio = {p.stem: p for p in sorted(folder.glob("*.wav")) + sorted(folder.glob("*.WAV"))}
    lacking = [s for s in ref_names if s not in audio]
    if len(lacking) == len(ref_names):
        raise InputError("no <sequence>.wav file matches any natural sequence name", path=folder)
    if lacking:
        issues.append(f"no audio for {len(lacking)} sequences (beat alignment skipped there): "
                      f"{', '.join(lacking[:10])}")
    return audio


def _load_corpus(path: str | pathlib.Path) -> Any:
    """The corpus at ``path``, in any layout :func:`evalsuite.corpus.load_corpus` reads."""
    from evalsuite.corpus.readers import load_corpus

    return load_corpus(path)


def _corpus_segments(corpus_dir: str | pathlib.Path, ref_names: list[str], issues: list[str]) -> dict[str, Any]:
    segments = {s.id: s for s in _load_corpus(corpus_dir)}
    lacking = [s for s in ref_names if s not in segments]
    if len(lacking) == len(ref_names):
        raise InputError("no corpus segment id matches any natural file name (files are matched to segments "
                         "by stem)", path=corpus_dir)
    if lacking:
        issues.append(f"no corpus segment for {len(lacking)} sequences (coupling metrics skipped there): "
                      f"{', '.join(lacking[:10])}")
    return {s: segments[s] for s in ref_names if s in segments}


def plan_scoring(reference: str | pathlib.Path, conditions: Sequence[str | pathlib.Path],
                 joints: str | Sequence[str] | None = None,
                 audio_dir: str | pathlib.Path | None = None, strict: bool = False,
                 fps: float | None = None, corpus: str | pathlib.Path | None = None) -> Plan:
    """Pair files by name, check folders, resolve the joint set (see the module docstring)."""
    ref_name, ref_path = parse_condition(reference)
    pairs = [(ref_name, ref_path)] + [parse_condition(c) for c in conditions]
    names = [n for n, _ in pairs]
    dupes = sorted({n for n in names if names.count(n) > 1})
    if dupes:
        raise InputError(f"condition names must be unique, {', '.join(dupes)} appears twice; "
                         "name them with NAME=FOLDER", field="condition")
    files = {n: list_motion_files(p, what=f"condition {n!r}") for n, p in pairs}
    samples: dict[str, dict[str, list[pathlib.Path]]] = {}
    for n in names[1:]:  # <name>_<k> files are samples of the natural sequence <name>
        firsts, several, other = split_samples(files[n], files[ref_name])
        files[n] = {**firsts, **other}
        if several:
            samples[n] = several
    issues = _pairing_issues(files, ref_name, names[1:], strict)
    ref_names = sorted(files[ref_name])
    audio = _audio_files(audio_dir, ref_names, issues) if audio_dir is not None else {}
    segments = _corpus_segments(corpus, ref_names, issues) if corpus is not None else {}
    for s, seg in segments.items():  # a corpus brings its speech
        if s not in audio and seg.audio is not None:
            audio[s] = seg.audio
    # The joint set comes from the first readable natural file.
    first = None
    errors = []
    for s in ref_names:
        try:
            first = load_motion(files[ref_name][s], fallback_fps=fps)
            break
        except InputError as exc:
            errors.append(str(exc))
            if strict:
                raise
    if first is None:
        raise InputError("none of the natural files can be read: " + "; ".join(errors[:3]), field="reference")
    available = first.joint_names
    if joints:
        try:
            joint_list = resolve_joints(joints, available)
        except KeyError as exc:
            raise InputError(f"joints not in the natural motion ({first.source}): {exc.args[0]}; it has "
                             f"{', '.join(available)}", field="joints") from None
        order = {n: i for i, n in enumerate(available)}
        joint_list = sorted(dict.fromkeys(joint_list), key=order.__getitem__)
    else:
        joint_list = list(available)
    return Plan(ref_name, names, dict(pairs), files, ref_names, audio, issues, joint_list, segments, samples)


def find_group(group: str, names: Sequence[str]) -> list[str]:
    """Members of a preset group present in ``names``; if none, joints matching its name pattern."""
    present = [j for j in PRESETS.get(group, []) if j in names]
    if not present and group in GROUP_PATTERNS:
        present = [j for j in names if re.search(GROUP_PATTERNS[group], j, flags=re.IGNORECASE)]
    return present


def resolve_groups(group_names: Iterable[str] | None, joints: Sequence[str]) -> dict[str, list[str]]:
    """Named joint groups (presets or ``name:A,B``) restricted to the scored joints; empty ones dropped.

    Preset groups fall back to name patterns (``wrists``: names ending in wrist/hand, ``forearms``:
    forearm/elbow/lowarm) when the skeleton uses other names than the presets.
    """
    groups = {"all": list(joints)}
    for g in group_names or ():
        if ":" in g:
            name, _, members = g.partition(":")
            wanted = [m.strip() for m in members.split(",") if m.strip()]
        elif g in PRESETS or g in GROUP_PATTERNS:
            name, wanted = g, find_group(g, joints)
        else:
            raise InputError(f"unknown joint group {g!r}; use a preset ({', '.join(PRESETS)}) or "
                             "NAME:J1;J2 (NAME:J1,J2 in Python)", field="groups")
        present = [j for j in wanted if j in joints]
        if present:
            groups[name] = present
    return groups
