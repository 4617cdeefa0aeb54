"""GENEA Challenge layouts: 2020 (Trinity), 2022 and 2023 (Talking With Hands), and the synthetic speaker's
output (GENEA 2023 plus ``corpus.json`` and per-frame ``labels/``)."""
from __future__ import annotations

import csv
import json
import pathlib
import re
from typing import Any

from evalsuite.corpus.readers.base import CorpusBuilder, register_layout
from evalsuite.errors import InputError

_SPLIT_DIRS = ("trn", "val", "tst", "train", "test")  # GENEA names; the canonical ones accepted too
_MOTION = (".bvh", ".npz", ".npy", ".csv")


def _child(folder: pathlib.Path, name: str) -> pathlib.Path | None:
    """The sub-folder ``name`` of ``folder``, matched without regard to case."""
    if not folder.is_dir():
        return None
    for p in folder.iterdir():
        if p.is_dir() and p.name.lower() == name.lower():
            return p
    return None


def _stems(folder: pathlib.Path | None, suffixes: tuple[str, ...]) -> dict[str, pathlib.Path]:
    if folder is None or not folder.is_dir():
        return {}
    return {p.stem: p for p in sorted(folder.iterdir())
            if p.is_file() and p.suffix.lower() in suffixes and not p.name.startswith(".")}  # not macOS ._ files


def _split_of(name: str) -> str | None:
    low = name.lower()
    for key, split in (("train", "train"), ("trn", "train"), ("val", "val"), ("dev", "val"),
                       ("test", "test"), ("tst", "test")):
        if key in low:
            return split
    return None


# --- GENEA 2020 / Trinity -------------------------------------------------------------------------------------

def _genea2020_roots(root: pathlib.Path) -> list[pathlib.Path]:
    if _child(root, "Audio") is not None:
        return [root]
    return [p for p in sorted(root.iterdir()) if p.is_dir() and _child(p, "Audio") is not None]


def _detect_genea2020(root: pathlib.Path) -> bool:
    return any(_child(r, "Motion") is not None or _child(r, "Transcripts") is not None
               for r in _genea2020_roots(root))


@register_layout("genea2020", detect=_detect_genea2020,
                 description="GENEA 2020 / Trinity: Audio/*.wav, Motion/*.bvh, Transcripts/*.json by recording "
                             "name (optionally inside Training_data/, Test_data/ ...)")
def read_genea2020(root: pathlib.Path, b: CorpusBuilder) -> None:
    for sub in _genea2020_roots(root):
        split = None if sub == root else _split_of(sub.name)
        audio = _stems(_child(sub, "Audio"), (".wav",))
        motion = _stems(_child(sub, "Motion"), _MOTION)
        text = _stems(_child(sub, "Transcripts"), (".json", ".tsv", ".textgrid", ".txt"))
        audio_dir = _child(sub, "Audio") or sub / "Audio"
        for stem in sorted(set(audio) | set(motion)):
            seg_id = stem if sub == root else f"{sub.name}/{stem}"
            b.add(seg_id, audio=audio.get(stem, audio_dir / f"{stem}.wav"), motion=motion.get(stem),
                  transcript=text.get(stem), split=split)


# --- GENEA 2022 and 2023 --------------------------------------------------------------------------------------

def _split_dirs(root: pathlib.Path) -> list[pathlib.Path]:
    return [p for p in sorted(root.iterdir()) if p.is_dir() and p.name.lower() in _SPLIT_DIRS]


def _detect_genea2023(root: pathlib.Path) -> bool:
    return any(_child(s, "main-agent") is not None for s in _split_dirs(root))


def _detect_genea2022(root: pathlib.Path) -> bool:
    return any(_child(s, "wav") is not None and _child(s, "main-agent") is None for s in _split_dirs(root))


def _first(row: dict[str, str], *names: str) -> str | None:
    for n in names:
        if row.get(n) not in (None, ""):
            return row[n].strip()
    return None


_INCL, _EXCL = ("finger_incl", "fingers_incl", "1", "true", "yes"), ("finger_excl", "fingers_excl", "0", "false", "no")


def _fingers(value: str | None, path: pathlib.Path, line: int, field: str) -> bool | None:
    if value is None:
        return None
    if value.strip().lower() not in _INCL + _EXCL:
        raise InputError(f"{value!r} is not a finger flag; expected fingers_incl or fingers_excl", path=path, line=line,
                         field=field)
    return value.strip().lower() in _INCL


_FINGERS = re.compile(r"^fingers?_(incl|excl)$", re.IGNORECASE)
_IDS, _SPEAKERS = ("prefix", "fname"), ("main-agent_id", "userid", "speaker", "speaker_id")
_GENEA2023_HEADER = "prefix, main-agent_id, main-agent_has_fingers, interloctr_id, interloctr_has_fingers"


def _metadata_files(folder: pathlib.Path) -> list[pathlib.Path]:
    """``metadata.csv`` (GENEA 2023) or ``<split>_2022_v1_metadata.csv`` / ``<split>_metadata.csv`` (2022)."""
    if (folder / "metadata.csv").is_file():
        return [folder / "metadata.csv"]
    return sorted(p for p in folder.glob("*metadata.csv") if p.is_file())


def read_metadata(path: pathlib.Path) -> dict[str, dict[str, Any]]:
    """One GENEA metadata file by recording prefix: ``{prefix: {speaker, finger_incl, interlocutor_speaker,
    interlocutor_finger_incl}}``.

    GENEA 2023 ``metadata.csv`` (one per split) has the header ``prefix, main-agent_id, main-agent_has_fingers,
    interloctr_id, interloctr_has_fingers``; GENEA 2022 ``trn_2022_v1_metadata.csv`` has none and holds ``fname,
    finger flag, speaker id`` (the flag column is recognised by its values). ``fingers_incl`` and ``finger_incl``
    (both spellings occur) mean True, ``*_excl`` False. Any other header, a header without a speaker column or
    an unknown finger flag is an :class:`InputError` naming the file and line."""
    with open(path, newline="", encoding="utf-8-sig") as fh:
        rows = [r for r in csv.reader(fh)]
    if not rows:
        return {}
    header = [h.strip() for h in rows[0]]
    first_line = 2
    if not set(_IDS) & set(header):  # no header: GENEA 2022's fname, finger flag, speaker id
        flag = next((i for i, c in enumerate(header) if _FINGERS.match(c)), None)
        if flag is None or len(header) < 3:
            raise InputError(f"cannot read the columns {', '.join(header)}: expected GENEA 2023's header "
                             f"{_GENEA2023_HEADER}, or GENEA 2022's rows without a header: recording name, "
                             "fingers_incl|fingers_excl, speaker id", path=path, line=1)
        header = ["fname"] + ["fingers" if i == flag else "userid" for i in range(1, len(rows[0]))]
        rows, first_line = [header] + rows, 1
    elif not set(_SPEAKERS) & set(header):
        raise InputError(f"no speaker column in the header {', '.join(header)}; expected {_GENEA2023_HEADER}",
                         path=path, line=1)
    out: dict[str, dict[str, Any]] = {}
    for n, row in enumerate(rows[1:], start=first_line):
        if not any(c.strip() for c in row):
            continue
        if len(row) != len(header):
            raise InputError(f"expected {len(header)} comma-separated fields ({', '.join(header)}), found {len(row)}",
                             path=path, line=n)
        rec = dict(zip(header, row))
        prefix = _first(rec, *_IDS)
        if prefix is None:
            raise InputError("the recording prefix is empty; expected e.g. trn_2023_v0_000", path=path, line=n)
        out[prefix] = {"speaker": _first(rec, *_SPEAKERS),
                       "finger_incl": _fingers(_first(rec, "main-agent_has_fingers", "fingers", "has_fingers"),
                                               path, n, "main-agent_has_fingers"),
                       "interlocutor_speaker": _first(rec, "interloctr_id"),
                       "interlocutor_finger_incl": _fingers(_first(rec, "interloctr_has_fingers"), path, n,
                                                            "interloctr_has_fingers")}
    return out


def _metadata(folder: pathlib.Path, b: CorpusBuilder, into: dict[str, dict[str, Any]] | None = None,
              ) -> dict[str, dict[str, Any]]:
    """The metadata files of ``folder`` merged into ``into`` (a recording in two files with different values is
    an error); the files read are listed in ``b.meta["metadata_files"]``."""
    out = {} if into is None else into
    for path in _metadata_files(folder):
        b.meta.setdefault("metadata_files", []).append(path.relative_to(b.root).as_posix())
        for prefix, rec in read_metadata(path).items():
            if prefix in out and out[prefix] != rec:
                raise InputError(f"{prefix} is also in another metadata file with other values ({out[prefix]} vs "
                                 f"{rec}); keep one", path=path)
            out[prefix] = rec
    return out


def _agent_files(agent_dir: pathlib.Path | None, suffix: str) -> dict[str, pathlib.Path]:
    """Files of one agent's folder keyed by recording prefix (``trn_2023_v0_000_main-agent`` -> prefix)."""
    out: dict[str, pathlib.Path] = {}
    for kind, sufs in (("wav", (".wav",)), ("bvh", _MOTION), ("tsv", (".tsv", ".json", ".textgrid", ".txt"))):
        if suffix != kind:
            continue
        for stem, p in _stems(_child(agent_dir, kind) if agent_dir else None, sufs).items():
            for tag in ("_main-agent", "_interloctr"):
                if stem.endswith(tag):
                    stem = stem[: -len(tag)]
            out[stem] = p
    return out


def _read_genea_split(split_dir: pathlib.Path, b: CorpusBuilder, dyadic: bool,
                      root_meta: dict[str, dict[str, Any]]) -> set[str]:
    """Read one split folder; returns the recordings its metadata (and the root's) name."""
    split = split_dir.name
    meta = _metadata(split_dir, b, dict(root_meta))
    main = _child(split_dir, "main-agent") if dyadic else split_dir
    other = _child(split_dir, "interloctr") if dyadic else None
    wav, bvh, tsv = (_agent_files(main, k) for k in ("wav", "bvh", "tsv"))
    o_wav, o_bvh, o_tsv = (_agent_files(other, k) for k in ("wav", "bvh", "tsv"))
    labels_dir = _child(main, "labels") if main is not None else None
    tag = "_main-agent" if dyadic else ""
    wav_dir = (_child(main, "wav") if main is not None else None) or split_dir / "wav"
    for prefix in sorted(set(wav) | set(bvh)):
        info = dict(meta.get(prefix, {}))
        speaker = info.pop("speaker", None)
        if not meta.get(prefix) and meta:
            info["metadata"] = "missing"
        inter = None
        if dyadic and other is not None:
            inter = b.stream(o_wav.get(prefix), o_tsv.get(prefix), o_bvh.get(prefix), allow_empty=True)
        labels = None
        if labels_dir is not None:
            labels = next((p for p in (labels_dir / f"{prefix}.csv", labels_dir / f"{prefix}{tag}.csv")
                           if p.is_file()), None)
        b.add(prefix, audio=wav.get(prefix, wav_dir / f"{prefix}{tag}.wav"), motion=bvh.get(prefix),
              transcript=tsv.get(prefix), speaker=speaker, split=split, interlocutor=inter, labels=labels,
              allow_empty_transcript=True, meta={k: v for k, v in info.items() if v is not None})
    return set(meta)


@register_layout("genea2022", detect=_detect_genea2022,
                 description="GENEA 2022: trn|val|tst/{wav,bvh,tsv}/ and trn_2022_v1_metadata.csv "
                             "(speaker ids, finger flags)")
def read_genea2022(root: pathlib.Path, b: CorpusBuilder) -> None:
    _read_genea(root, b, dyadic=False)


def _read_genea(root: pathlib.Path, b: CorpusBuilder, dyadic: bool) -> None:
    """Every split folder, with the metadata of the split folders and of the root (where some copies of the
    release keep one file for all splits; the prefixes name the split)."""
    b.meta["metadata_files"] = []
    root_meta = _metadata(root, b)
    known = set(root_meta)
    for split_dir in _split_dirs(root):
        known |= _read_genea_split(split_dir, b, dyadic, root_meta)
    if known and b.segments and not known & {s.id for s in b.segments}:
        raise InputError(f"no recording of {', '.join(b.meta['metadata_files'])} (e.g. {min(known)}) is in the "
                         f"corpus (e.g. {b.segments[0].id}): metadata of another release?", path=root)


@register_layout("genea2023", detect=_detect_genea2023,
                 description="GENEA 2023: trn|val|tst/{main-agent,interloctr}/{wav,bvh,tsv}/ and metadata.csv "
                             "(in each split or at the root); "
                             "also the synthetic speaker's output (corpus.json, main-agent/labels/)")
def read_genea2023(root: pathlib.Path, b: CorpusBuilder) -> None:
    _read_genea(root, b, dyadic=True)
    path = root / "corpus.json"
    if path.is_file():
        try:
            content = json.loads(path.read_text(encoding="utf-8"))
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise InputError(f"not valid JSON ({exc}); expected the synthetic speaker's description", path=path) \
                from None
        if not isinstance(content, dict):
            raise InputError("expected a JSON object describing the model and seed", path=path)
        b.meta["corpus_json"] = content
        for k, v in content.items():
            b.meta.setdefault(k, v)
        # Each segment carries its corpus's keyword classes, which the lexical-contrast metrics score it by.
        if isinstance(content.get("keyword_classes"), dict):
            for seg in b.segments:
                seg.meta["keyword_classes"] = content["keyword_classes"]
