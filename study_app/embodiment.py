"""The embodiment of a study's stimuli (body style, character, framing, face), read from the manifest's columns
that ``evalsuite render stimuli`` writes, and said in one line for the admin page, the export and a paper."""
from __future__ import annotations

from collections.abc import Iterable, Mapping

from evalsuite.contracts.manifest import EMBODIMENT

__all__ = ["embodiment_columns", "describe_embodiment"]


def embodiment_columns(rows: Iterable[Mapping[str, str | None]]) -> dict[str, list[str]]:
    """Column -> its distinct non-empty values in order of appearance, for each of ``EMBODIMENT`` the rows have."""
    out: dict[str, list[str]] = {}
    for row in rows:
        for col in EMBODIMENT:
            value = (row.get(col) or "").strip()
            if value and value not in out.setdefault(col, []):
                out[col].append(value)
    return {k: v for k, v in out.items() if v}


def describe_embodiment(embodiment: Mapping[str, list[str]]) -> str:
    """``"mannequin body; framing above-knees; face blank"`` (several values joined by ``/``: mixed stimuli), or
    a note that the manifest does not say (made by hand or by an older evalsuite)."""
    if not embodiment:
        return "not recorded in the manifest (no style/character/framing/face columns)"
    parts = []
    if "style" in embodiment:
        parts.append(f"{'/'.join(embodiment['style'])} body")
    if "character" in embodiment:
        parts.append(f"character {'/'.join(embodiment['character'])}")
    for col in ("framing", "face"):
        if col in embodiment:
            parts.append(f"{col} {'/'.join(embodiment[col])}")
    return "; ".join(parts)
