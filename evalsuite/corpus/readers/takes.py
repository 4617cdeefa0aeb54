"""Layouts of one file per take and modality: BEAT, BEAT2 (SMPL-X, per language folder), ZEGGS, and a plain folder
matched by file stem."""
from __future__ import annotations

import csv
import pathlib
import re
import zipfile
from typing import Any

import numpy as np

from evalsuite.corpus.readers.base import CorpusBuilder, register_layout
from evalsuite.corpus.transcripts import transcript_suffixes
from evalsuite.errors import InputError

_MOTION = (".bvh", ".npz", ".npy", ".csv")
# BEAT: <speaker id>_<name>_<type>_<...>_<...>, e.g. 1_wayne_0_1_1 (BEAT2: 2_scott_0_1_1)
_BEAT = re.compile(r"^(\d+)_([A-Za-z]+)_(\d+)_(\d+)_(\d+)$")
# ZEGGS: <index>_<style>_<...>, e.g. 001_Neutral_0_x_1_0
_ZEGGS = re.compile(r"^(\d{3})_([A-Za-z]+)_.*$")


def _files(root: pathlib.Path, recursive: bool) -> list[pathlib.Path]:
    it = root.rglob("*") if recursive else root.iterdir()
    return sorted(p for p in it if p.is_file() and not p.name.startswith("."))


def _group(files: list[pathlib.Path], pattern: re.Pattern[str] | None, motion: tuple[str, ...] = _MOTION,
           transcripts: tuple[str, ...] | None = None) -> dict[str, dict[str, pathlib.Path]]:
    """stem -> {"audio"|"motion"|"transcript": path}; two files of one kind for a stem is an error, except that
    a ``.bvh`` is preferred to other motion files (BEAT2 beside SMPL-X ``.npz``). ``transcripts``: the
    transcript suffixes (default: every registered transcript format's, installed plug-ins included)."""
    transcripts = transcript_suffixes() if transcripts is None else transcripts
    out: dict[str, dict[str, pathlib.Path]] = {}
    for p in files:
        suffix = p.suffix.lower()
        kind = "audio" if suffix == ".wav" else "motion" if suffix in motion else \
            "transcript" if suffix in transcripts else None
        if kind is None or (pattern is not None and not pattern.match(p.stem)):
            continue
        entry = out.setdefault(p.stem, {})
        if kind == "motion" and kind in entry and (suffix == ".bvh") != (entry[kind].suffix.lower() == ".bvh"):
            if suffix == ".bvh":
                entry[kind] = p
            continue
        if kind in entry:
            raise InputError(f"two {kind} files for {p.stem!r}: {entry[kind]} and {p}; keep one", path=p.parent)
        entry[kind] = p
    return out


def _split_table(path: pathlib.Path, id_cols: tuple[str, ...], split_cols: tuple[str, ...]
                 ) -> dict[str, dict[str, str]]:
    """Rows of a CSV with a header, keyed by the first of ``id_cols`` present."""
    with open(path, newline="", encoding="utf-8-sig") as fh:
        reader = csv.DictReader(fh)
        header = [h.strip() for h in reader.fieldnames or []]
        id_col = next((c for c in id_cols if c in header), None)
        split_col = next((c for c in split_cols if c in header), None)
        if id_col is None or split_col is None:
            raise InputError(f"expected a header with columns {id_cols[0]!r} and {split_cols[0]!r}, found "
                             f"{', '.join(header) or 'nothing'}", path=path, line=1)
        out = {}
        for n, row in enumerate(reader, start=2):
            key, split = (row.get(id_col) or "").strip(), (row.get(split_col) or "").strip()
            if not key or not split:
                raise InputError(f"expected a {id_col} and a {split_col}, found {key!r}, {split!r}", path=path, line=n)
            out[key] = {k.strip(): (v or "").strip() for k, v in row.items() if k}
            out[key]["split"] = split
        return out


# --- BEAT / BEAT2 --------------------------------------------------------------------------------------------

def is_beat2_folder(root: pathlib.Path) -> bool:
    """A BEAT2 language folder (it holds ``smplxflame_30/``) or a folder of them: the ``beat2`` layout's."""
    return (root / "smplxflame_30").is_dir() or any((p / "smplxflame_30").is_dir() for p in root.iterdir()
                                                    if p.is_dir())


def _detect_beat(root: pathlib.Path) -> bool:
    if is_beat2_folder(root):
        return False  # the beat2 layout reads it (SMPL-X motion, sem, betas)
    return any(p.suffix.lower() == ".textgrid" and _BEAT.match(p.stem) for p in root.rglob("*"))


@register_layout("beat", detect=_detect_beat,
                 description="BEAT/BEAT2: <speaker>_<name>_<...>.wav + .TextGrid + .bvh (or .npz) per take, in "
                             "any sub-folders; splits from train_test_split.csv (id, type) when present")
def read_beat(root: pathlib.Path, b: CorpusBuilder) -> None:
    splits: dict[str, dict[str, str]] = {}
    table = next(iter(sorted(root.glob("train_test_split.csv"))), None) or \
        next(iter(sorted(root.glob("*/train_test_split.csv"))), None)
    if table is not None:
        splits = _split_table(table, ("id", "name", "segment"), ("type", "split"))
    # BEAT keeps other annotations beside each take under the same stem (.json facial blendshapes, .txt
    # semantic labels, .csv emotions): only .TextGrid is the transcript, only .bvh/.npz the motion
    for stem, files in sorted(_group(_files(root, True), _BEAT, (".bvh", ".npz"), (".textgrid",)).items()):
        m = _BEAT.match(stem)
        assert m is not None
        split = splits.get(stem, {}).get("split")
        expected = files.get("audio") or (files.get("motion") or files["transcript"]).with_suffix(".wav")
        b.add(stem, audio=expected, motion=files.get("motion"), transcript=files.get("transcript"),
              speaker=m.group(1), split=split, meta={"speaker_name": m.group(2)})


# --- BEAT2 (SMPL-X) ------------------------------------------------------------------------------------------
# BEAT2 as released (one folder per language, e.g. ``beat_english_v2.0.0/``): ``smplxflame_30/*.npz`` SMPL-X
# motion at 30 fps, ``wave16k/*.wav`` speech, ``textgrid/*.TextGrid`` word timings, ``sem/*.txt`` semantic
# relevance annotations and ``train_test_split.csv`` (``id``, ``type``: train, val, test, additional).
#
# The corpus root is either one language folder or a folder holding several (``BEAT2/beat_english_v2.0.0``,
# ``BEAT2/beat_chinese_v2.0.0``, ...; their segment ids are then ``<language folder>/<take>``). Each segment has
# the speaker id and name from the take's name (``2_scott_0_103_103``: speaker 2, scott), its language, its
# ``sem`` file where there is one (``segment.meta['sem']``) and the body shape ``betas`` of its motion file
# (``segment.meta['betas']``, a float64 array; the GENEA Leaderboard computes positions with the ground truth's).

_LANGUAGE = re.compile(r"^beat_([a-z]+)_v[\d.]+$", re.IGNORECASE)


def language_folders(root: pathlib.Path) -> list[pathlib.Path]:
    """The BEAT2 language folders of ``root``: itself when it holds ``smplxflame_30/``, else its sub-folders
    that do."""
    if (root / "smplxflame_30").is_dir():
        return [root]
    return [p for p in sorted(root.iterdir()) if p.is_dir() and (p / "smplxflame_30").is_dir()]


def _language(folder: pathlib.Path) -> str:
    m = _LANGUAGE.match(folder.name)
    return m.group(1).lower() if m else folder.name


def read_betas(path: pathlib.Path) -> np.ndarray | None:
    """The ``betas`` array of a BEAT2 ``.npz`` as float64 (the first row when stored per frame), or None when
    the file has none."""
    try:
        with np.load(path, allow_pickle=False) as npz:
            if "betas" not in npz.files:
                return None
            betas = np.asarray(npz["betas"], dtype=np.float64)
    except (OSError, ValueError, zipfile.BadZipFile) as exc:
        raise InputError(f"cannot read betas ({exc}); expected a BEAT2 SMPL-X .npz", path=path) from None
    return betas[0] if betas.ndim == 2 else betas.reshape(-1)


def _stems(folder: pathlib.Path, suffix: str) -> dict[str, pathlib.Path]:
    if not folder.is_dir():
        return {}
    return {p.stem: p for p in sorted(folder.iterdir())
            if p.is_file() and p.suffix.lower() == suffix and not p.name.startswith(".") and _BEAT.match(p.stem)}


def _read_language(folder: pathlib.Path, b: CorpusBuilder, prefix: str, summary: dict[str, Any]) -> None:
    language = _language(folder)
    table = folder / "train_test_split.csv"
    splits = _split_table(table, ("id",), ("type",)) if table.is_file() else {}
    if table.is_file():
        b.meta.setdefault("split_tables", []).append(table.relative_to(b.root).as_posix())
    motion = _stems(folder / "smplxflame_30", ".npz")
    audio = _stems(folder / "wave16k", ".wav")
    text = {p.stem: p for p in sorted((folder / "textgrid").glob("*")) if p.suffix.lower() == ".textgrid"} \
        if (folder / "textgrid").is_dir() else {}
    sem = _stems(folder / "sem", ".txt")
    count = 0
    for stem in sorted(set(motion) | set(audio)):
        m = _BEAT.match(stem)
        assert m is not None
        meta: dict[str, Any] = {"language": language, "speaker_name": m.group(2)}
        if stem in sem:
            meta["sem"] = sem[stem]
        if stem in motion:
            betas = read_betas(motion[stem])
            if betas is not None:
                meta["betas"] = betas
                spk = summary["betas"].setdefault(m.group(1), {"files": 0, "n_betas": set(), "shapes": set()})
                spk["files"] += 1
                spk["n_betas"].add(int(betas.size))
                spk["shapes"].add(betas.tobytes())
        b.add(f"{prefix}{stem}", audio=audio.get(stem, folder / "wave16k" / f"{stem}.wav"), motion=motion.get(stem),
              transcript=text.get(stem), speaker=m.group(1), split=splits.get(stem, {}).get("split"), meta=meta)
        count += 1
        summary["sem_files"] += "sem" in meta
    summary["languages"][language] = count


@register_layout("beat2", detect=is_beat2_folder,
                 description="BEAT2 (SMPL-X): per language folder smplxflame_30/*.npz, wave16k/*.wav, "
                             "textgrid/*.TextGrid, sem/*.txt, train_test_split.csv; speaker ids from the names, "
                             "betas from the motion")
def read_beat2(root: pathlib.Path, b: CorpusBuilder) -> None:
    folders = language_folders(root)
    summary: dict[str, Any] = {"languages": {}, "sem_files": 0, "betas": {}}
    for folder in folders:
        _read_language(folder, b, "" if folder == root else f"{folder.name}/", summary)
    betas = {spk: {"files": v["files"], "n_betas": sorted(v["n_betas"]), "distinct": len(v["shapes"])}
             for spk, v in sorted(summary["betas"].items(), key=lambda kv: (len(kv[0]), kv[0]))}
    b.meta["beat2"] = {"languages": summary["languages"], "sem_files": summary["sem_files"], "betas": betas}


# --- ZEGGS -----------------------------------------------------------------------------------------------------

def _detect_zeggs(root: pathlib.Path) -> bool:
    files = _files(root, True)
    named = [p for p in files if _ZEGGS.match(p.stem)]
    transcripts = transcript_suffixes()
    return (any(p.suffix.lower() == ".bvh" for p in named) and any(p.suffix.lower() == ".wav" for p in named)
            and not any(p.suffix.lower() in transcripts for p in named))


@register_layout("zeggs", detect=_detect_zeggs,
                 description="ZEGGS: <index>_<style>_<...>.wav + .bvh per take (one speaker, no transcripts)")
def read_zeggs(root: pathlib.Path, b: CorpusBuilder) -> None:
    for stem, files in sorted(_group(_files(root, True), _ZEGGS, (".bvh",), ()).items()):
        m = _ZEGGS.match(stem)
        assert m is not None
        expected = files.get("audio") or (files.get("motion") or files["transcript"]).with_suffix(".wav")
        b.add(stem, audio=expected, motion=files.get("motion"), transcript=files.get("transcript"),
              meta={"style": m.group(2)})


# --- a plain folder ---------------------------------------------------------------------------------------------

def _detect_folder(root: pathlib.Path) -> bool:
    return any(p.suffix.lower() in (".wav",) + _MOTION for p in _files(root, False))


@register_layout("folder", detect=_detect_folder,
                 description="a plain folder: files matched by stem (.wav; .bvh/.npz/.npy/.csv motion; "
                             ".json/.tsv/.TextGrid/.txt transcripts); optional splits.csv (segment, split[, speaker])")
def read_folder(root: pathlib.Path, b: CorpusBuilder) -> None:
    if (root / "metadata.csv").is_file():
        raise InputError("metadata.csv is read in the GENEA layouts only (trn|val|tst/ folders); in a plain folder "
                         "give each segment's speaker in splits.csv (segment, split, speaker)", path=root / "metadata.csv")
    files = [p for p in _files(root, False) if p.name.lower() not in ("splits.csv", "corpus.json")]
    groups = _group(files, None)
    splits: dict[str, dict[str, str]] = {}
    if (root / "splits.csv").is_file():
        splits = _split_table(root / "splits.csv", ("segment", "id"), ("split",))
        unknown = sorted(set(splits) - set(groups))
        if unknown:
            raise InputError(f"splits.csv names segments that are not in the folder: {', '.join(unknown[:5])}",
                             path=root / "splits.csv")
    has_audio = any("audio" in g for g in groups.values())
    for stem, g in sorted(groups.items()):
        if "audio" not in g and "motion" not in g:
            continue  # a transcript alone is not a segment (e.g. notes.txt)
        row = splits.get(stem, {})
        b.add(stem, audio=g.get("audio", root / f"{stem}.wav"), motion=g.get("motion"),
              transcript=g.get("transcript"), split=row.get("split"), speaker=row.get("speaker") or None,
              require_audio=has_audio)
