"""Media blueprint: a participant's videos (and headphone-check sounds), addressed by page
index and slot only.

The URL never carries a file name: the server looks the blinded file up in the
participant's own plan and serves it from the manifest's folder with
``send_from_directory`` (which refuses any path outside it). Range requests work, so
browsers can seek. Only pages up to the participant's current page are served.
"""
from __future__ import annotations

from flask import Blueprint, Response, abort, current_app, request, send_from_directory

from study_app.answers import n_slots
from study_app.headphones import trial_wav
from study_app.participant import _own

bp = Blueprint("media", __name__)


@bp.route("/s/<sid>/media/<int:index>/<int:slot>")
def video(sid, index, slot):
    _own(sid)
    study, store = current_app.extensions["study"], current_app.extensions["store"]
    sess, pages = store.read_session(sid)
    if sess is None or sess.status != "active" or not 0 <= index <= sess.current_page:
        abort(404)
    page = pages[index]
    if not 0 <= slot < n_slots(page):
        abort(404)
    if page["type"] == "headphone_check":
        # generated tones, with byte ranges as for the videos (browsers ask for them)
        body = trial_wav(page["trials"][slot])
        resp = Response(body, mimetype="audio/wav")
        resp.headers["Cache-Control"] = "private, no-store"
        return resp.make_conditional(request, accept_ranges=True, complete_length=len(body))
    file = page["slots"][slot] if page["type"] == "mushra" else (
        page["stimulus"] if page["type"] == "likert" else
        page["a"] if (slot == 0) == (page["position_a"] == "left") else page["b"])
    if file not in study.manifest.by_file():
        abort(404)
    resp = send_from_directory(study.manifest.root, file, mimetype="video/mp4", conditional=True,
                               max_age=0)
    resp.headers["Cache-Control"] = "private, no-store"
    return resp
