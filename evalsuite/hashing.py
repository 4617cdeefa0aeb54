"""Content hashes recorded in provenance (scores, model files, rendered stimuli)."""
from __future__ import annotations

import hashlib


def file_sha256(path) -> str:
    """SHA-256 hex digest of a file's bytes, read in 1 MiB blocks."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()
