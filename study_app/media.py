"""Media blueprint: a participant's videos (and headphone-check sounds), addressed by page
index and slot only.

The URL never carries a file name: the server looks the blinded file up in the
participant's own plan and serves it from the manifest's folder with
``send_from_directory`` (which refuses any path outside it). Range requests work, so
browsers can seek. Only pages up to the participant's current page are served.
"""
from __future__ import annotations

import hashlib
import hmac

from flask import Blueprint, Response, abort, current_app, request, send_from_directory

from study_app.context import get_store, get_study
from study_app.pages import get_kind
from study_app.participant import _own
from study_app.served import fully_served, record_served

bp = Blueprint("media", __name__)


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
