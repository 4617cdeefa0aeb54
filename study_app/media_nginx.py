"""Media served by nginx (``MEDIA_SERVER = "nginx"``): the redirect the app answers with, and nginx's record
of the bytes it sent, read into ``media_served``.

The app authorises a media request and records it (:mod:`study_app.media`), then answers with an empty body
and ``X-Accel-Redirect: /_evalsuite_media/<file>``; nginx serves that ``internal`` location from the stimuli
folder (Range requests included), so no application thread waits for a slow client. The app never sees the
bytes, so nginx writes one line per such response to its own access log (``log_format evalsuite_media`` in
``deploy/nginx/evalsuite.conf.template``)::

    $msec $status $body_bytes_sent $request_uri "$sent_http_content_range" $sent_http_content_length

``$request_uri`` is the participant's original URL (``/s/<session>/media/<page>/<slot>``), which the app
authorised; ``$body_bytes_sent`` is what nginx wrote to the connection, so a client that disconnects
mid-transfer is recorded with the part it got. The range recorded is ``first .. first + bytes - 1``, where
``first`` is the start of ``Content-Range`` (0 for a whole-file 200) and the file's length is the total of
``Content-Range`` or the ``Content-Length`` of a 200. ``max_ranges 1`` in that location keeps responses to a
single range, so each line is one exact range.

:func:`ingest` appends the log's new complete lines to ``media_served`` (sessions that no longer exist, e.g.
forgotten on request, are skipped). It remembers how far it read in ``<log>.offset`` (inode and byte
offset; a new inode or a shorter file is read from the start), under an exclusive lock on that file so that
gunicorn's workers do not read the same lines twice. A crash between writing rows and the offset can write
a line's range twice, which changes no coverage (the union of ranges, :func:`study_app.served.coverage`).
"""
from __future__ import annotations

import datetime as dt
import fcntl
import logging
import os
import re
import sqlite3
import urllib.parse

from sqlalchemy import select
from sqlalchemy.exc import DBAPIError

from study_app.storage.tables import ParticipantSession

__all__ = ["ACCEL_PREFIX", "accel_path", "parse_line", "parse_request", "ingest"]

log = logging.getLogger(__name__)

ACCEL_PREFIX = "/_evalsuite_media/"
LINE_RE = re.compile(r'^(\d+(?:\.\d+)?) (\d{3}) (\d+) (\S+) "([^"]*)" (\S+)$')
URI_RE = re.compile(r"^/s/([A-Za-z0-9_-]+)/media/(\d+)/(\d+)(/[0-9a-f]{32}(?:\.[a-z0-9]+)?)?(?:\?.*)?$")
SIGNED_OK = {"200", "206", "304", "416"}      # a signed request nginx answered: the participant asked for it
RANGE_RE = re.compile(r"^bytes (\d+)-(\d+)/(\d+)$")


def accel_path(file: str) -> str:
    """The internal URL nginx serves a stimulus file under (``file`` relative to the manifest's folder)."""
    return ACCEL_PREFIX + urllib.parse.quote(file.replace(os.sep, "/"))


def parse_line(line: str) -> tuple[str, int, int, int, int, int, int, dt.datetime] | None:
    """One access-log line → (session, page, slot, first byte, last byte, file length, status, time), or
    None for a line that sent no media body (HEAD, 304, 416, an error page, a foreign line)."""
    m = LINE_RE.match(line.rstrip("\n"))
    if m is None:
        return None
    msec, status, sent, uri, content_range, length = m.groups()
    u = URI_RE.match(uri)
    if u is None or int(sent) == 0:
        return None
    if status == "206":
        r = RANGE_RE.match(content_range)
        if r is None:
            return None
        first, total = int(r.group(1)), int(r.group(3))
        last = min(first + int(sent) - 1, int(r.group(2)))
    elif status == "200" and length.isdigit():
        first, total = 0, int(length)
        last = min(int(sent), total) - 1
    else:
        return None
    return u.group(1), int(u.group(2)), int(u.group(3)), first, last, total, int(status), _utc(msec)


def parse_request(line: str) -> tuple[str, int, int, dt.datetime] | None:
    """A signed URL's access-log line (``MEDIA_SERVER = "nginx-signed"``: no app request recorded it) →
    (session, page, slot, time) for ``media_requests``, or None (an unsigned URL, a refused request)."""
    m = LINE_RE.match(line.rstrip("\n"))
    u = URI_RE.match(m.group(4)) if m is not None else None
    if m is None or u is None or u.group(4) is None or m.group(2) not in SIGNED_OK:
        return None
    return u.group(1), int(u.group(2)), int(u.group(3)), _utc(m.group(1))


def _utc(msec: str) -> dt.datetime:
    """nginx's ``$msec`` (seconds since the epoch) as a naive UTC time, as the database stores times."""
    return dt.datetime.fromtimestamp(float(msec), dt.timezone.utc).replace(tzinfo=None)


def ingest(media_log, path: str) -> int:
    """Append the new lines of nginx's media log ``path`` to ``media_served``; returns the rows written."""
    try:
        with open(path + ".offset", "a+") as state:
            fcntl.flock(state, fcntl.LOCK_EX)       # released when the file is closed
            state.seek(0)
            saved = state.read().split()
            try:
                with open(path, "rb") as fh:
                    st = os.fstat(fh.fileno())
                    offset = int(saved[1]) if len(saved) == 2 and saved[0] == str(st.st_ino) else 0
                    fh.seek(offset if offset <= st.st_size else 0)
                    offset = fh.tell()
                    data = fh.read()
            except FileNotFoundError:
                return 0
            complete = data[:data.rfind(b"\n") + 1]
            lines = complete.decode("utf-8", "replace").splitlines()
            rows = [r for r in map(parse_line, lines) if r is not None]
            first: dict[tuple, tuple] = {}
            for req in map(parse_request, lines):
                if req is not None:
                    first.setdefault(req[:3], req)            # one media_requests row per slot: its first time
            asked = list(first.values())
            if rows or asked:
                with media_log.Session() as db:
                    known = set(db.scalars(select(ParticipantSession.id).where(
                        ParticipantSession.id.in_({r[0] for r in [*rows, *asked]}))))
                rows = [r for r in rows if r[0] in known]
                asked = [r for r in asked if r[0] in known]
            if asked:
                media_log.write_requests(asked)
            if rows:
                media_log.write_served(rows)
            state.seek(0)
            state.truncate()
            state.write(f"{st.st_ino} {offset + len(complete)}\n")
            return len(rows)
    except (DBAPIError, sqlite3.Error, OSError) as exc:
        log.warning("could not read nginx's media log %s (read again next time): %s", path, exc)
        return 0
