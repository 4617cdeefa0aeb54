"""Media served by nginx without an application request (``MEDIA_SERVER = "nginx-signed"``).

When the app builds a page it gives each video slot a signed URL::

    /s/<session>/media/<page>/<slot>/<key><ext>?md5=<signature>&expires=<unix time>

``key`` = HMAC-SHA256(``SECRET_KEY``, ``link|session|page|slot``), first 32 hex digits: the participant cannot
invert it, and it says nothing of the file (blinding; ``ext`` is the file's extension, as ``Content-Type``
already says). The app makes ``<MEDIA_LINKS>/<key><ext>`` a symbolic link to the stimulus file; nginx serves
that folder. ``signature`` is nginx's ``secure_link_md5 "$secure_link_expires$uri <MEDIA_LINK_SECRET>"``
(base64url of MD5, no padding), so a URL cannot be forged, moved to another session, page or slot, or used
after ``expires`` (``MEDIA_LINK_SECONDS``, default 3600; a reload of the page signs new URLs). A future page
has neither a signed URL nor a link. nginx's media log (:mod:`study_app.media_nginx`) is then the whole
playback record: the requests (``media_requests``) and the bytes sent (``media_served``).

The trade-off: a URL works for whoever holds it until it expires (no session cookie is checked). A session's
links are removed when it ends (finished or failed with its last answer, released, excluded) and when its
participant is forgotten, so its URLs then get 404 at once; links of sessions that ended otherwise (a
reservation that ran out) go with ``evalsuite study prune-links`` (docs/deploy.md). A link's name is computed
from the session's plan pages (slots per page) and the stimuli's extensions: removing one never lists the
folder, and never touches the file a link points to.
"""
from __future__ import annotations

import base64
import contextlib
import dataclasses
import hashlib
import hmac
import os
import stat
import threading
import time
from collections.abc import Iterable

from flask import current_app, url_for

from study_app.answers import n_slots
from study_app.context import get_store, get_study

__all__ = ["link_key", "sign", "signed_url", "ensure_link", "video_urls", "Links", "links_of", "link_names",
           "remove_links", "remove_session_links", "prune_links", "drop_session_links"]


def link_key(secret_key: str, sid: str, index: int, slot: int) -> str:
    """The opaque name of a page slot's link: HMAC-SHA256(secret, ``link|sid|index|slot``), 32 hex digits."""
    return hmac.new(secret_key.encode(), f"link|{sid}|{index}|{slot}".encode(), hashlib.sha256).hexdigest()[:32]


def sign(uri: str, expires: int, secret: str) -> str:
    """nginx's ``secure_link_md5 "$secure_link_expires$uri <secret>"``: base64url(MD5(...)) without ``=``."""
    digest = hashlib.md5(f"{expires}{uri} {secret}".encode()).digest()
    return base64.urlsafe_b64encode(digest).rstrip(b"=").decode()


def ensure_link(links: str, name: str, target: str) -> None:
    """Make ``links/name`` a symbolic link to ``target`` (absolute), replacing a stale one atomically."""
    path = os.path.join(links, name)
    try:
        if os.readlink(path) == target:
            return
    except OSError:
        pass
    tmp = f"{path}.{os.getpid()}.{threading.get_ident()}.tmp"     # one per thread of a gthread worker
    with contextlib.suppress(FileNotFoundError):
        os.unlink(tmp)
    os.symlink(target, tmp)
    os.replace(tmp, path)


def signed_url(config: dict, root: str, sid: str, index: int, slot: int, file: str,
               now: float | None = None) -> str:
    """The signed URL of a page slot whose stimulus is ``file`` (relative to the manifest's folder ``root``);
    its link is made in ``config["MEDIA_LINKS"]`` first."""
    ext = os.path.splitext(file)[1].lower()
    name = link_key(config["SECRET_KEY"], sid, index, slot) + ext
    ensure_link(config["MEDIA_LINKS"], name, os.path.abspath(os.path.join(root, file)))
    uri = f"/s/{sid}/media/{index}/{slot}/{name}"
    expires = int(now if now is not None else time.time()) + int(config.get("MEDIA_LINK_SECONDS") or 3600)
    return f"{uri}?md5={sign(uri, expires, config['MEDIA_LINK_SECRET'])}&expires={expires}"


def video_urls(study, kind, spec: dict, sid: str, index: int) -> list[str]:
    """A page's media URLs, one per slot: the app's, or with ``MEDIA_SERVER = "nginx-signed"`` a stimulus file's
    signed URL that nginx serves without the app (generated media, e.g. headphone-check sounds, stays the
    app's and is not generated here)."""
    slots = range(kind.n_slots(spec))
    urls = [url_for("media.video", sid=sid, index=index, slot=k) for k in slots]
    if current_app.config.get("MEDIA_SERVER") != "nginx-signed":
        return urls
    files = None
    for k in slots:
        if kind.generated_seconds(spec, k) is not None:
            continue                                  # generated media: the app's route
        media = kind.media(study, spec, k)
        files = study.manifest.by_file() if files is None else files
        if media.body is None and media.file in files:
            urls[k] = signed_url(current_app.config, str(study.manifest.root), sid, index, k, media.file)
    return urls


@dataclasses.dataclass(frozen=True)
class Links:
    """Where a server's links are (``MEDIA_LINKS``) and what their names are made of."""

    folder: str
    secret_key: str                 # the server's SECRET_KEY (link_key)
    exts: tuple[str, ...]           # the stimuli's file extensions, e.g. (".mp4",)


def links_of(config, study) -> Links | None:
    """The links of a server's config (``MEDIA_SERVER = "nginx-signed"``), or None in any other mode."""
    if config.get("MEDIA_SERVER") != "nginx-signed" or not config.get("MEDIA_LINKS"):
        return None
    exts = sorted({os.path.splitext(f)[1].lower() for f in study.manifest.by_file()})
    return Links(str(config["MEDIA_LINKS"]), config["SECRET_KEY"], tuple(exts))


def link_names(links: Links, sid: str, pages: list[dict]) -> list[str]:
    """Every name a link of the session can have: ``link_key(secret, sid, page, slot) + ext`` for each page,
    each media slot of it (its kind's ``n_slots``) and each stimulus extension."""
    return [link_key(links.secret_key, sid, i, k) + ext for i, page in enumerate(pages)
            for k in range(n_slots(page)) for ext in links.exts]


def remove_links(folder: str, names: Iterable[str]) -> int:
    """Remove ``folder/name`` for each name that is a symbolic link (the link, never its target; anything
    else is left). A missing folder or a link already gone is no error. Returns how many were removed."""
    removed = 0
    for name in names:
        path = os.path.join(folder, name)
        try:
            if stat.S_ISLNK(os.lstat(path).st_mode):
                os.unlink(path)
                removed += 1
        except OSError:                 # gone already (another process), or no folder
            continue
    return removed


def remove_session_links(links: Links, sid: str, pages: list[dict]) -> int:
    """Remove a session's links (:func:`link_names`): its signed URLs then get 404 from nginx."""
    return remove_links(links.folder, link_names(links, sid, pages))


def prune_links(links: Links, sessions: Iterable[tuple[str, list[dict]]]) -> int:
    """Remove the links of ``sessions`` (session id, plan pages) among those in the folder (listed once)."""
    try:
        with os.scandir(links.folder) as entries:
            present = {e.name for e in entries if e.is_symlink()}
    except FileNotFoundError:
        return 0
    return remove_links(links.folder, (n for sid, pages in sessions for n in link_names(links, sid, pages)
                                       if n in present))


def drop_session_links(sid: str) -> int:
    """In a request: remove the links of the session ``sid`` that has just ended (no-op unless nginx-signed)."""
    links = links_of(current_app.config, get_study())
    if links is None:
        return 0
    _sess, pages = get_store().read_session(sid)
    return remove_session_links(links, sid, pages or [])
