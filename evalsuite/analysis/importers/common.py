"""Shared pieces of the importers: reading a CSV by column aliases and building results.csv rows."""
from __future__ import annotations

import pathlib
from typing import NoReturn

import pandas as pd

from evalsuite.analysis import csvtext
from evalsuite.contracts.results import COLUMNS
from evalsuite.errors import InputError

__all__ = ["fail", "read_aliased", "rows"]


def fail(message: str, path, line: int | None = None, field: str | None = None) -> NoReturn:
    raise InputError(message, path=path, line=line, field=field)


def read_aliased(path: pathlib.Path, aliases: dict[str, tuple[str, ...]], required: tuple[str, ...],
                 what: str) -> pd.DataFrame:
    """The CSV's cells (strings, plus ``line``) with each wanted column under its own name: the first of its
    aliases (case-insensitive) present in the header. A required column with no alias present is an error
    naming the accepted names."""
    if not path.is_file():
        fail(f"file not found (expected {what})", path)
    df = csvtext.read_cells(path)
    lower = {c.lower(): c for c in df.columns}
    out = pd.DataFrame({"line": df["line"]})
    for name, names in aliases.items():
        found = next((lower[a] for a in names if a in lower), None)
        if found is not None:
            out[name] = df[found]
        elif name in required:
            fail(f"no {name} column: expected one of {', '.join(names)} ({what})", path, line=1)
    for name in required:
        bad = out[name] == ""
        if bad.any():
            fail(f"empty value; every row needs its {name}", path, line=int(out.loc[bad, "line"].iloc[0]), field=name)
    return out


def rows(n: int, study: str, **columns) -> pd.DataFrame:
    """``n`` results.csv rows of finished, non-training judgements; ``columns`` sets the others (scalars or
    sequences). A participant's rows form one session unless ``session`` is given."""
    base: dict[str, object] = {c: "" for c in COLUMNS}
    base.update(study=study, session_status="finished", is_training="0", is_attention_check="0")
    base.update(columns)
    df = pd.DataFrame({c: base[c] for c in COLUMNS}, index=range(n))
    if "session" not in columns:
        df["session"] = df["participant"]
    return df.astype(str)
