"""Videos by signed URL (study_app.media_signed, MEDIA_SERVER=nginx-signed): Debian's nginx with the shipped site
file serves them without an application request; forged, moved, expired and future-page URLs are refused; the
playback record (requests and bytes) comes from nginx's media log alone."""
from __future__ import annotations

import time

import pytest
import requests
from deploy_helpers import SECRET, WebParticipant, app_env, make_study

from study_app.errors import StudyStateError
from study_app.media_frontend import Gunicorn, Nginx
from study_app.media_nginx import parse_request
from study_app.media_signed import link_key, sign
from study_app.storage import Store, make_engine

LINK_SECRET = "signed-media-test-secret"


def test_signature_is_nginx_secure_link_md5_and_keys_are_opaque():
    # echo -n '2147483647/s/a/media/1/0/x secret' | openssl md5 -binary | base64 | tr +/ -_ | tr -d =
    assert sign("/s/a/media/1/0/x", 2147483647, "secret") == "Gv1ShJFZmWWDT3QqPsC5zw"
    keys = {link_key(SECRET, "sid", i, k) for i in range(3) for k in range(2)}
    assert len(keys) == 6 and all(len(k) == 32 for k in keys)
    assert link_key(SECRET, "sid", 1, 0) != link_key("other", "sid", 1, 0)


def test_parse_request_reads_only_answered_signed_urls():
    key = "0123456789abcdef" * 2
    signed = f"/s/AbCd/media/3/1/{key}.mp4?md5=x-_Y&expires=9"
    assert parse_request(f'1700000000.5 206 100 {signed} "bytes 0-99/900" 100')[:3] == ("AbCd", 3, 1)
    assert parse_request(f'1700000000.5 304 0 {signed} "-" -') is not None       # asked, nothing new sent
    for line in (f'1700000000.5 403 153 {signed} "-" 153', f'1700000000.5 410 153 {signed} "-" 153',
                 '1700000000.5 206 100 /s/AbCd/media/3/1 "bytes 0-99/900" 100'):   # the app recorded this one
        assert parse_request(line) is None, line


def test_signed_mode_needs_links_and_secret(tmp_path):
    from test_study_media_nginx import _app
    with pytest.raises(StudyStateError, match="MEDIA_LINKS"):
        _app(tmp_path, MEDIA_SERVER="nginx-signed", MEDIA_ACCESS_LOG=str(tmp_path / "m.log"))
    with pytest.raises(StudyStateError, match="MEDIA_LINK_SECRET"):
        _app(tmp_path, MEDIA_SERVER="nginx-signed", MEDIA_ACCESS_LOG=str(tmp_path / "m.log"),
             MEDIA_LINKS=str(tmp_path / "links"))


def test_nginx_serves_signed_urls_without_the_app_and_records_them(tmp_path):
    db = f"sqlite:///{tmp_path / 'study.db'}"
    study = make_study(tmp_path, db)
    log, links = tmp_path / "media.log", tmp_path / "links"
    app = Gunicorn(app_env(study, db, EVALSUITE_MEDIA_SERVER="nginx-signed", EVALSUITE_MEDIA_ACCESS_LOG=str(log),
                           EVALSUITE_MEDIA_LINKS=str(links), EVALSUITE_MEDIA_LINK_SECRET=LINK_SECRET),
                   workers=1, threads=4)
    nginx = Nginx(f"127.0.0.1:{app.port}", tmp_path / "stim", log, links=links, link_secret=LINK_SECRET)
    try:
        app.start()
        nginx.start()
        p = WebParticipant(nginx.url, "5a1e" * 6)
        p.enter()
        p.consent()
        _, data, _ = p.page()
        assert data is not None and data["type"] == "pairwise"
        index, url0, url1 = data["index"], data["videos"][0], data["videos"][1]
        assert "?md5=" in url0 and not any(n.stem in url0 for n in (tmp_path / "stim").glob("*.mp4"))
        a = p.video(url0, 0, 999)
        assert a.status_code == 206 and len(a.content) == 1000 and a.headers["Content-Type"] == "video/mp4"
        assert a.headers["Cache-Control"] == "private, no-store"
        for header in ("Last-Modified", "ETag", "Content-Disposition"):
            assert header not in a.headers, header                    # blinding: nothing of the file
        total0 = int(a.headers["Content-Range"].split("/")[1])
        b = requests.get(nginx.url + url0, headers={"Range": "bytes=500-"}, timeout=30)   # no cookie needed
        assert b.status_code == 206 and len(b.content) == total0 - 500 and b.content[:500] == a.content[500:]
        p.video(url1, 0, 99)
        path, query = url0.split("?")
        expires = int(query.split("expires=")[1])
        name = path.rsplit("/", 1)[1]
        refused = {
            "forged": (path + "?md5=AAAAAAAAAAAAAAAAAAAAAA&expires=" + str(expires), 403),
            "unsigned": (path, 403),
            "other slot": (path.replace(f"/{index}/0/", f"/{index}/1/") + "?" + query, 403),
            "other session": (path.replace(p.sid, "x" * len(p.sid)) + "?" + query, 403),
            "expired": (f"{path}?md5={sign(path, int(time.time()) - 5, LINK_SECRET)}&expires={int(time.time()) - 5}",
                        410)}
        future_key = link_key(SECRET, p.sid, index + 1, 0) + ".mp4"       # signed, but the app made no link
        future = f"/s/{p.sid}/media/{index + 1}/0/{future_key}"
        refused["future page"] = (f"{future}?md5={sign(future, expires, LINK_SECRET)}&expires={expires}", 404)
        for what, (url, status) in refused.items():
            assert requests.get(nginx.url + url, timeout=10).status_code == status, what
        assert not (links / future_key).exists() and (links / name).is_symlink()
        # no application request for a video: with the app stopped, the signed URL still plays
        app.stop()
        c = p.video(url1, 100, 199)
        assert c.status_code == 206 and len(c.content) == 100
        time.sleep(0.2)
        assert sum(parse_request(x) is not None for x in log.read_text().splitlines()) == 4
        store = Store(make_engine(db))
        store.media_log.access_log = str(log)            # what the app does on its next export
        dump = store.dump("deploy-test")
        assert dump["media_requests"][(p.sid, index)] == {0, 1}
        assert dump["media_served"][(p.sid, index)] == {0: (total0, total0), 1: (200, int(c.headers["Content-Range"].split("/")[1]))}
    finally:
        app.stop()
        nginx.stop()
