"""Joint maps: which joint of the motion drives which joint of a skinned character.

A map is YAML, ``character joint: motion joint`` (or a list of motion joints, the first one the motion has is
used), either flat or under a ``joints:`` key. evalsuite ships maps for its character (Mixamo-style joint names)
in ``renderers/data/joint_maps/``: ``genea2023`` (GENEA 2022/2023 ``b_*``), ``mixamo`` (BEAT/BEAT2, ZEGGS,
Mixamo), ``cmu``, ``smplx`` and ``classic`` (the BVH specification's Chest/LeftCollar/LeftElbow names). Without a
user map the shipped map that matches most of the motion's joints is used.

A character joint maps to a motion joint at the same place of the body: the character's ``LeftArm`` (the
shoulder end of the upper arm) to GENEA's ``b_l_arm``, SMPL-X's ``left_shoulder``, the classic ``LeftShoulder``.
"""
from __future__ import annotations

import pathlib

import yaml

from evalsuite.errors import InputError, did_you_mean

MAP_DIR = pathlib.Path(__file__).resolve().parent.parent / "data" / "joint_maps"
PREFERENCE = ["genea2023", "mixamo", "smplx", "cmu", "classic"]   # ties go to the earlier map
MIN_MAPPED = 5   # fewer mapped joints than this cannot pose a body


def _entries(doc, path) -> dict[str, list[str]]:
    if isinstance(doc, dict) and "joints" in doc:
        doc = doc["joints"]
    if not isinstance(doc, dict) or not doc:
        raise InputError("expected a joint map: 'character joint: motion joint' lines (optionally under 'joints:')",
                         path=path, field="joint_map")
    out = {}
    for key, value in doc.items():
        names = value if isinstance(value, list) else [value]
        if not names or not all(isinstance(n, str) and n for n in names):
            raise InputError(f"{key}: expected a motion joint name or a list of names, got {value!r}", path=path,
                             field="joint_map")
        out[str(key)] = list(names)
    return out


def load_map(path) -> dict[str, list[str]]:
    """A joint map from a YAML file (see the module doc); :class:`InputError` naming the file if malformed."""
    path = pathlib.Path(path)
    try:
        doc = yaml.safe_load(path.read_text())
    except OSError as e:
        raise InputError(f"cannot read the joint map ({e.strerror or e})", path=path, field="joint_map") from None
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        raise InputError(f"not valid YAML: {getattr(e, 'problem', e)}", path=path,
                         line=mark.line + 1 if mark else None, field="joint_map") from None
    return _entries(doc, path)


def shipped_maps() -> dict[str, dict[str, list[str]]]:
    """The maps shipped with evalsuite, by name."""
    return {p.stem: load_map(p) for p in sorted(MAP_DIR.glob("*.yaml"))}


def resolve(entries: dict[str, list[str]], character_joints, motion_joints, *, strict: bool,
            map_path=None) -> dict[int, int]:
    """``{character joint index: motion joint index}``.

    ``strict`` (a user's map): every character joint it names must exist in the character and the first
    motion joint of every entry in the motion, else a one-line :class:`InputError` naming the map file.
    Otherwise entries whose joints are absent are skipped, and a motion joint is used once at most.
    """
    char_index = {n: i for i, n in enumerate(character_joints)}
    motion_index = {n: i for i, n in enumerate(motion_joints)}
    out: dict[int, int] = {}
    used: set[int] = set()
    for cj, candidates in entries.items():
        if cj not in char_index:
            if strict:
                raise InputError(f"names character joint {cj!r}, which the character does not have"
                                 f"{did_you_mean(cj, char_index)}", path=map_path, field="joint_map")
            continue
        found = [motion_index[m] for m in candidates if m in motion_index and motion_index[m] not in used]
        if not found:
            if strict:
                raise InputError(f"{cj}: names motion joint {candidates[0]!r}, which the motion does not have"
                                 f"{did_you_mean(candidates[0], motion_index)}", path=map_path, field="joint_map")
            continue
        out[char_index[cj]] = found[0]
        used.add(found[0])
    return out


def choose_map(character_joints, motion_joints, *, joint_map=None, motion_source=None,
               character_source=None) -> tuple[str, dict[int, int]]:
    """The map to use and its resolution: the user's ``joint_map`` file if given, else the best shipped map.

    Raises a one-line :class:`InputError` naming the motion file when fewer than ``MIN_MAPPED`` joints map.
    """
    if joint_map is not None:
        resolved = resolve(load_map(joint_map), character_joints, motion_joints, strict=True, map_path=joint_map)
        name = str(joint_map)
        tried = name
    else:
        scored = [(len(r), n, r) for n, r in ((n, resolve(e, character_joints, motion_joints, strict=False))
                                              for n, e in shipped_maps().items())]
        best = max(scored, key=lambda s: (s[0], -PREFERENCE.index(s[1]) if s[1] in PREFERENCE else -99))
        name, resolved = best[1], best[2]
        tried = ", ".join(s[1] for s in scored)
    if len(resolved) < MIN_MAPPED:
        shown = ", ".join(list(motion_joints)[:8]) + (", ..." if len(motion_joints) > 8 else "")
        raise InputError(f"only {len(resolved)} of the motion's joints ({shown}) map onto the character "
                         f"{character_source or ''} (maps tried: {tried}); give a joint map (YAML, character joint: "
                         "motion joint)", path=motion_source, field="joint_map")
    return name, resolved
