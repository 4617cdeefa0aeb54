"""Reading a CSV file as text cells with the file line of every record, fast.

Every cell is kept as a string with surrounding white space removed (the validation decides what
each column must hold; "NA", a common condition name, stays a string). Blank lines are skipped;
a record with another number of fields than the header, a file that is not UTF-8, or one with a
control character is an :class:`~evalsuite.errors.InputError` naming the line.

Two paths with the same result: pandas' C parser (a million rows in seconds), with the line of
each record taken from the non-blank lines; when a quoted field spans lines (so records and lines
do not match up) the ``csv`` module reads the file record by record instead (``line`` is then the
line where the record ends).
"""
from __future__ import annotations

import csv
import io
import pathlib
from typing import NoReturn

import numpy as np
import pandas as pd

from evalsuite.analysis import validate
from evalsuite.errors import InputError


def _fail(message, path, line=None) -> NoReturn:
    raise InputError(message, path=path, line=line)


def _width_error(n: int, header: list, path, line: int) -> NoReturn:
    _fail(f"row has {n} fields but the header has {len(header)}; not a well-formed CSV (unquoted comma?)",
          path, line=line)


def read_cells(path) -> pd.DataFrame:
    """The records of the CSV at ``path`` as a DataFrame of stripped strings, with ``line`` (the
    1-based file line of each record) as its first column."""
    path = pathlib.Path(path)
    try:
        text = path.read_bytes().decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        _fail(f"not UTF-8 text ({exc.reason} at byte {exc.start})", path)
    validate.check_control_characters(text, path)
    fast = _fast(text, path)
    header, df, lines = fast if fast is not None else _quoted(text, path)
    dupes = sorted({c for c in header if header.count(c) > 1})
    if dupes:
        _fail(f"duplicate column(s) in the header: {', '.join(dupes)}", path, line=1)
    if len(df) == 0:
        _fail("no data rows after the header", path)
    for col in df.columns:
        uniq = pd.unique(df[col])
        stripped = [u.strip() for u in uniq]
        if any(a != b for a, b in zip(uniq, stripped)):
            df[col] = df[col].map(dict(zip(uniq, stripped)))
    # Unknown extra columns are ignored; one called "line" or "value" would clash with ours.
    df = df.drop(columns=[c for c in ("line", "value") if c in df.columns])
    df.insert(0, "line", np.asarray(lines, dtype=int))
    return df


QUOTED = r'"(?:[^"]|"")*"'


def _fast(text: str, path):
    """pandas' C parser, after counting each line's fields (commas outside quoted fields); ``None``
    when a quoted field spans lines (records and lines do not match up)."""
    rows = text.split("\n")
    header = [c.strip() for c in next(csv.reader([rows[0]]), [])] if rows[0].strip() else []
    if not header:
        _fail("empty file: expected a header row and at least one data row", path)
    body = pd.Series(rows[1:], dtype=object)
    keep = (body.str.strip() != "").to_numpy()
    nb = body[keep]
    if '"' in text:
        quoted = nb.str.contains('"', regex=False)
        if (nb[quoted].str.count('"') % 2 == 1).any():
            return None                       # a quoted field continues on the next line
        bare = nb.where(~quoted, nb[quoted].str.replace(QUOTED, "", regex=True))
    else:
        bare = nb
    fields = bare.str.count(",").to_numpy() + 1
    lines = np.flatnonzero(keep) + 2
    bad = np.flatnonzero(fields != len(header))
    if bad.size:
        _width_error(int(fields[bad[0]]), header, path, int(lines[bad[0]]))
    if len(nb) == 0:
        return header, pd.DataFrame(columns=header, dtype=str), lines
    df = pd.read_csv(io.StringIO("\n".join(nb)), header=None, names=range(len(header)), dtype=str,
                     keep_default_na=False, na_filter=False, engine="c", skip_blank_lines=False)
    if len(df) != len(nb):
        return None
    df.columns = header
    return header, df, lines


def _quoted(text: str, path):
    records, lines = [], []
    try:
        reader = csv.reader(io.StringIO(text, newline=""), strict=True)
        header = next(reader, None)
        if not header:
            _fail("empty file: expected a header row and at least one data row", path)
        header = [c.strip() for c in header]
        for row in reader:
            if not row or (len(row) == 1 and not row[0].strip()):
                continue  # blank line
            if len(row) != len(header):
                _width_error(len(row), header, path, reader.line_num)
            records.append(row)
            # reader.line_num is the file line where this record ended (quoted newlines ok).
            lines.append(reader.line_num)
    except csv.Error as exc:
        _fail(f"not a well-formed CSV: {exc}", path)
    return header, pd.DataFrame(records, columns=header, dtype=str), lines
