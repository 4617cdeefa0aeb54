"""Reading a CSV file as text cells with the file line of every record, fast.

Every cell is kept as a string (``object`` columns: without pyarrow, pandas' own string dtype
compares and groups element by element in Python, many times slower) with surrounding white space removed (the validation decides what
each column must hold; "NA", a common condition name, stays a string). Blank lines are skipped;
a record with another number of fields than the header, a file that is not UTF-8, one with a
control character, an unterminated quote or a field longer than :data:`MAX_FIELD_CHARS` (the ``csv``
module's limit) is an :class:`~evalsuite.errors.InputError` naming the line.

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

MAX_FIELD_CHARS = 131_072   # the csv module's field_size_limit(); both reading paths refuse longer fields


def _fail(message, path, line=None) -> NoReturn:
    raise InputError(message, path=path, line=line)


def _width_error(n: int, header: list, path, line: int) -> NoReturn:
    _fail(f"row has {n} fields but the header has {len(header)}; not a well-formed CSV (unquoted comma?)",
          path, line=line)


def read_cells(path) -> pd.DataFrame:
    """The records of the CSV at ``path`` as a DataFrame of stripped strings, with ``line`` (the
    1-based file line of each record) as its first column."""
    path = pathlib.Path(path)
    raw = path.read_bytes()
    if raw.startswith(b"\xef\xbb\xbf"):
        raw = raw[3:]                                 # a UTF-8 byte-order mark
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        _fail(f"not UTF-8 text ({exc.reason} at byte {exc.start})", path)
    b = np.frombuffer(raw, dtype=np.uint8)
    if (((b < 32) & (b != 9) & (b != 10) & (b != 13)) | (b == 127)).any():
        validate.check_control_characters(text, path)   # finds it again and names line and column
    # White space next to a delimiter, quote or line end (a padded cell) is rare: strip only then.
    sp = np.flatnonzero((b == 32) | (b == 9))
    edge = np.frombuffer(b',\n\r"', dtype=np.uint8)
    padded = bool(sp.size) and bool(np.isin(b[np.maximum(sp - 1, 0)], edge).any()
                                    or np.isin(b[np.minimum(sp + 1, len(b) - 1)], edge).any() or sp[0] == 0
                                    or sp[-1] == len(b) - 1)
    fast = _fast(raw, text, path)
    header, df, lines = fast if fast is not None else _quoted(text, path)
    dupes = sorted({c for c in header if header.count(c) > 1})
    if dupes:
        _fail(f"duplicate column(s) in the header: {', '.join(dupes)}", path, line=1)
    if len(df) == 0:
        _fail("no data rows after the header", path)
    for col in df.columns if padded else ():
        uniq = pd.unique(df[col])
        stripped = [u.strip() for u in uniq]
        if any(a != b for a, b in zip(uniq, stripped)):
            df[col] = df[col].map(dict(zip(uniq, stripped)))
    # Unknown extra columns are ignored; one called "line" or "value" would clash with ours.
    df = df.drop(columns=[c for c in ("line", "value") if c in df.columns])
    df.insert(0, "line", np.asarray(lines, dtype=int))
    return df


def _fast(raw: bytes, text: str, path):
    """pandas' C parser after a vectorised scan of the bytes: each line's fields (commas outside
    quotes), blank lines, and whether a quoted field spans lines (then ``None``: records and lines
    do not match up, the ``csv`` module reads the file instead)."""
    first = text.split("\n", 1)[0]
    header = [c.strip() for c in next(csv.reader([first]), [])] if first.strip() else []
    if not header:
        _fail("empty file: expected a header row and at least one data row", path)
    b = np.frombuffer(raw, dtype=np.uint8)
    nl = np.flatnonzero(b == 10)
    if len(nl) == 0 or nl[-1] != len(b) - 1:
        nl = np.append(nl, len(b))                    # the last line without a newline
    quote = b == 34
    if quote.any():
        inside = (np.cumsum(quote, dtype=np.uint8) & 1).astype(bool)   # odd number of quotes so far
        if inside[nl[nl < len(b)]].any():
            return None                               # a quoted field continues on the next line
        commas = np.flatnonzero((b == 44) & ~inside)
        del inside
    else:
        commas = np.flatnonzero(b == 44)
    del quote
    _check_field_lengths(commas, nl, path)
    # commas before the end of each line, differenced: the commas of each line
    fields = np.diff(np.searchsorted(commas, nl), prepend=0) + 1
    starts = np.r_[0, nl[:-1] + 1]
    blank = np.zeros(len(nl), dtype=bool)
    for i in np.flatnonzero(fields == 1):             # no comma: possibly blank (rare unless 1 column)
        blank[i] = not raw[starts[i]:nl[i]].strip()
    data = np.flatnonzero(~blank[1:]) + 1            # data lines (0-based), header excluded
    bad = data[fields[data] != len(header)]
    if bad.size:
        _width_error(int(fields[bad[0]]), header, path, int(bad[0]) + 1)
    lines = data + 1
    if len(data) == 0:
        return header, pd.DataFrame(columns=header, dtype=object), lines
    try:
        df = pd.read_csv(io.BytesIO(raw), header=None, skiprows=1, names=range(len(header)), dtype=object,
                         keep_default_na=False, na_filter=False, engine="c", skip_blank_lines=True,
                         encoding="utf-8")
    except pd.errors.ParserError:
        return None                                   # e.g. a quote never closed: the csv module says where
    if len(df) != len(data):
        return None
    df.columns = header
    return header, df, lines


def _check_field_lengths(commas: np.ndarray, nl: np.ndarray, path) -> None:
    """Refuse a field longer than :data:`MAX_FIELD_CHARS` bytes (the gap between two separators), naming its line.

    Only lines longer than the limit can hold such a field, so only those are looked at."""
    starts = np.r_[0, nl[:-1] + 1]
    for i in np.flatnonzero(nl - starts > MAX_FIELD_CHARS):
        inner = commas[np.searchsorted(commas, starts[i]):np.searchsorted(commas, nl[i])]
        longest = int(np.diff(np.r_[starts[i] - 1, inner, nl[i]]).max()) - 1
        if longest > MAX_FIELD_CHARS:
            _fail(f"a field of {longest:,} bytes; expected at most {MAX_FIELD_CHARS:,} characters per field (the csv "
                  "module's limit)", path, line=int(i) + 1)


def _quoted(text: str, path):
    records, lines = [], []
    reader = csv.reader(io.StringIO(text, newline=""), strict=True)
    ended = 0                                         # the line where the last whole record ended
    try:
        header = next(reader, None)
        if not header:
            _fail("empty file: expected a header row and at least one data row", path)
        header = [c.strip() for c in header]
        ended = reader.line_num
        for row in reader:
            if not row or (len(row) == 1 and not row[0].strip()):
                ended = reader.line_num
                continue  # blank line
            if len(row) != len(header):
                _width_error(len(row), header, path, reader.line_num)
            records.append(row)
            # reader.line_num is the file line where this record ended (quoted newlines ok).
            lines.append(reader.line_num)
            ended = reader.line_num
    except csv.Error as exc:
        reason, line = str(exc), reader.line_num or None
        if "field larger than field limit" in reason:
            reason = f"a field longer than {MAX_FIELD_CHARS:,} characters (the csv module's limit)"
        elif "unexpected end of data" in reason:
            reason, line = "a quoted field starting on this line is never closed (an unterminated '\"')", ended + 1
        _fail(f"not a well-formed CSV: {reason}", path, line=line)
    return header, pd.DataFrame(records, columns=header, dtype=object), lines
