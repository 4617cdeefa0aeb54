"""Sample motion bundled with evalsuite (MIT-licensed real mocap; see data/samples/ATTRIBUTION.md)."""
from __future__ import annotations

import pathlib

SAMPLES_DIR = pathlib.Path(__file__).resolve().parent.parent / "data" / "samples"


def sample_paths() -> list[pathlib.Path]:
    """The bundled BVH files, sorted by name."""
    return sorted(SAMPLES_DIR.glob("*.bvh"))


def sample_path(name: str) -> pathlib.Path:
    """One bundled file by stem, e.g. ``sample_path("walk01")``."""
    path = SAMPLES_DIR / f"{name}.bvh"
    if not path.exists():
        raise FileNotFoundError(f"no bundled sample {name!r}; have {[p.stem for p in sample_paths()]}")
    return path
