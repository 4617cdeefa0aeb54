"""Media blueprint: a participant's videos (and headphone-check sounds), addressed by page
index and slot only.

The URL never carries a file name: the server looks the blinded file up in the
participant's own plan and serves it from the manifest's folder with
``send_from_directory`` (which refuses any path outside it). Range requests work, so
browsers can seek. Only pages up to the participant's current page are served.

Who sends a stimulus file's bytes is the app's config ``MEDIA_SERVER`` (environment
``EVALSUITE_MEDIA_SERVER``): ``app`` (the default; no front server needed) sends them from the application
thread; ``nginx`` answers the authorised request with ``X-Accel-Redirect`` and nginx sends the file
(:mod:`study_app.media_nginx`), so a slow client never holds an application worker; ``nginx-signed`` gives
the page signed URLs that nginx serves without asking the app at all (:mod:`study_app.media_signed`; this
route then answers only generated media and old unsigned URLs, as ``nginx`` does). ``MEDIA_ACCESS_LOG``
(``EVALSUITE_MEDIA_ACCESS_LOG``) is nginx's media log, read into the playback record (docs/deploy.md).
Generated media (headphone-check sounds, small) is always sent by the app.
"""
from __future__ import annotations

import hashlib
import hmac
import os

from flask import Blueprint, Response, abort, current_app, request, send_from_directory

from study_app.context import get_store, get_study, store_of
from study_app.errors import StudyStateError
from study_app.media_nginx import accel_path
from study_app.pages import get_kind
from study_app.participant import _own
from study_app.served import fully_served, record_served

bp = Blueprint("media", __name__)
MEDIA_SERVERS = ("app", "nginx", "nginx-signed")


@bp.record_once
def _configure(state) -> None:
    """Check ``MEDIA_SERVER`` once and hand ``MEDIA_ACCESS_LOG`` to the store's media log."""
    config, env = state.app.config, os.environ
    server = config.setdefault("MEDIA_SERVER", env.get("EVALSUITE_MEDIA_SERVER") or "app")
    if server not in MEDIA_SERVERS:
        raise StudyStateError(f"expected one of {', '.join(MEDIA_SERVERS)}, got {server!r}", field="MEDIA_SERVER")
    access_log = config.setdefault("MEDIA_ACCESS_LOG", env.get("EVALSUITE_MEDIA_ACCESS_LOG"))
    if server != "app" and not access_log:
        raise StudyStateError(f"MEDIA_SERVER is {server}: set nginx's media log (deploy/nginx/evalsuite.conf."
                              "template) so that the playback record knows the bytes sent", field="MEDIA_ACCESS_LOG")
    if server == "nginx-signed":
        for name in ("MEDIA_LINKS", "MEDIA_LINK_SECRET", "MEDIA_LINK_SECONDS"):
            config.setdefault(name, env.get("EVALSUITE_" + name))
            if not config[name] and name != "MEDIA_LINK_SECONDS":
                raise StudyStateError("MEDIA_SERVER is nginx-signed: set the links folder and the secret nginx "
                                      "checks signed URLs with (docs/deploy.md)", field=name)
        os.makedirs(config["MEDIA_LINKS"], exist_ok=True)
    if access_log:
        store_of(state.app).media_log.access_log = access_log


def _opaque_etag(sid: str, index: int, slot: int) -> str:
    """An ETag for range requests that says nothing about the file: a keyed hash of the page slot."""
    key = current_app.config["SECRET_KEY"].encode()
    return hmac.new(key, f"media|{sid}|{index}|{slot}".encode(), hashlib.sha256).hexdigest()[:32]


@bp.route("/s/<sid>/media/<int:index>/<int:slot>")
def video(sid, index, slot):
    _own(sid)
    study, store = get_study(), get_store()
    sess, pages = store.read_session(sid)
    if sess is None or sess.status != "active" or not 0 <= index <= sess.current_page:
        abort(404)
    page = pages[index]
    kind = get_kind(page["type"])
    if not 0 <= slot < kind.n_slots(page):
        abort(404)
    # The server's own record of what was fetched (study_app.playback), whatever the browser reports.
    store.record_media_request(sid, index, slot)
    media = kind.media(study, page, slot)
    if media.body is not None:
        # generated media (e.g. headphone-check tones), with byte ranges as for the videos; heard once:
        # a session that was already sent every byte of this trial's sound is refused it again
        if fully_served(store, sid, index, slot):
            abort(410)
        resp = Response(media.body, mimetype=media.mimetype)
        resp.headers["Cache-Control"] = "private, no-store"
        resp = resp.make_conditional(request, accept_ranges=True, complete_length=len(media.body))
        if request.method == "GET":
            record_served(store, sid, index, slot, resp)
        return resp
    if media.file not in study.manifest.by_file():
        abort(404)
    if current_app.config["MEDIA_SERVER"] != "app":
        # nginx sends the file and logs the bytes it sent (study_app.media_nginx); nothing of the file's
        # name reaches the participant: nginx drops Last-Modified and ETag there (deploy/nginx).
        resp = Response(b"", mimetype=media.mimetype)
        resp.headers["X-Accel-Redirect"] = accel_path(media.file)
        resp.headers["Cache-Control"] = "private, no-store"
        return resp
    resp = send_from_directory(study.manifest.root, media.file, mimetype=media.mimetype, conditional=True,
                               max_age=0, etag=_opaque_etag(sid, index, slot))
    # Blinding: nothing a participant receives may come from a stimulus file's name, time or render
    # order, so no file name and no modification time (file sizes still differ; docs/study_app.md).
    resp.headers.pop("Content-Disposition", None)
    resp.headers.pop("Last-Modified", None)
    resp.headers["Cache-Control"] = "private, no-store"
    if request.method == "GET":
        record_served(store, sid, index, slot, resp)      # the bytes this response sends (study_app.served)
    return resp
