"""The links of signed video URLs (study_app.media_signed, MEDIA_SERVER=nginx-signed) are removed when they are no
longer needed: when a session ends with its answer, when it is released or excluded, when its participant is
forgotten (admin page and CLI), and by ``evalsuite study prune-links`` for every session that has ended; never
another session's links, never the stimulus files they point to."""
from __future__ import annotations

import os
import re

import numpy as np
import study_helpers as h
from click.testing import CliRunner
from deploy_helpers import ADMIN, SECRET, make_study
from sqlalchemy import select

from study_app.app import create_app
from study_app.cli import study as study_cli
from study_app.context import store_of, study_of
from study_app.media_signed import Links, link_names, links_of, remove_links
from study_app.storage import Plan

LINK_SECRET = "links-test-link-secret"


def _app(tmp_path):
    db = f"sqlite:///{tmp_path / 'study.db'}"
    study = make_study(tmp_path, db)
    app = create_app({"STUDY": str(study), "DATABASE_URL": db, "SECRET_KEY": SECRET, "ADMIN_TOKEN": ADMIN,
                      "SESSION_COOKIE_SECURE": False, "INSTANCE_PATH": str(tmp_path / "inst"),
                      "MEDIA_SERVER": "nginx-signed", "MEDIA_ACCESS_LOG": str(tmp_path / "media.log"),
                      "MEDIA_LINKS": str(tmp_path / "links"), "MEDIA_LINK_SECRET": LINK_SECRET})
    return app, study, db


def _on_video_page(app, name):
    """A participant who consented and was shown their first video page (its links made)."""
    p = h.Participant(app.test_client(), name, study_id="deploy-test")
    p.enter()
    p.consent()
    _, data, _ = p.page()
    assert data["type"] == "pairwise" and "?md5=" in data["videos"][0]
    return p


def _links(app, sid):
    """The session's links now in the folder (names computed from its plan, as the app removes them)."""
    links = links_of(app.config, study_of(app))
    assert links is not None
    return [n for n in link_names(links, sid, h.plan_pages(app, sid)) if os.path.islink(os.path.join(links.folder, n))]


def _stimuli_intact(tmp_path):
    clips = sorted((tmp_path / "stim").glob("*.mp4"))
    assert clips and all(c.is_file() and c.stat().st_size > 0 for c in clips)


def _cli(*args, env=None):
    r = CliRunner().invoke(study_cli, [str(a) for a in args], env=env)
    assert r.exit_code == 0, r.output
    return r.output


def test_remove_links_unlinks_the_link_never_its_target_and_ignores_what_is_gone(tmp_path):
    target = tmp_path / "clip.mp4"
    target.write_bytes(b"video")
    folder = tmp_path / "links"
    folder.mkdir()
    (folder / "a.mp4").symlink_to(target)
    (folder / "plain.mp4").write_bytes(b"not a link")
    assert remove_links(str(folder), ["a.mp4", "a.mp4", "gone.mp4", "plain.mp4"]) == 1
    assert not os.path.lexists(folder / "a.mp4") and target.read_bytes() == b"video"
    assert (folder / "plain.mp4").read_bytes() == b"not a link"
    assert remove_links(str(tmp_path / "no-such-folder"), ["a.mp4"]) == 0
    names = link_names(Links(str(folder), SECRET, (".mp4", ".webm")), "sid",
                       [{"type": "consent"}, {"type": "pairwise", "a": "x", "b": "y"}])
    assert len(names) == 4 and len(set(names)) == 4         # 2 slots of page 1 x 2 extensions


def test_finishing_a_session_removes_its_links(tmp_path):
    app, _, _ = _app(tmp_path)
    p, other = _on_video_page(app, "fin00001"), _on_video_page(app, "fin00002")
    study, rng = study_of(app), np.random.default_rng(0)
    seen = _links(app, p.sid)
    assert len(seen) == 2 and len(_links(app, other.sid)) == 2
    while True:
        _, data, csrf = p.page()
        if data is None:
            break
        assert _links(app, p.sid), "each video page has its links while the session is active"
        spec = h.plan_pages(app, p.sid)[data["index"]]
        assert p.submit(data, csrf, h.make_answer(study, spec, rng)).status_code == 200
    assert store_of(app).load(p.sid)[0].status == "finished"
    assert _links(app, p.sid) == [] and not any(os.path.lexists(tmp_path / "links" / n) for n in seen)
    assert len(_links(app, other.sid)) == 2                    # the other participant's stay
    _stimuli_intact(tmp_path)


def _admin_op(app, name, **form):
    client = app.test_client()
    page = client.get("/admin/login").get_data(as_text=True)
    csrf = re.search(r'name="csrf_token" value="([^"]+)"', page).group(1)
    assert client.post("/admin/login", data={"token": ADMIN, "csrf_token": csrf}).status_code == 302
    csrf = re.search(r'name="csrf_token" value="([^"]+)"', client.get("/admin/").get_data(as_text=True)).group(1)
    assert client.post(f"/admin/op/{name}", data={"csrf_token": csrf, **form}).status_code == 302


def test_forget_removes_that_participants_links_and_no_one_elses(tmp_path):
    app, study, db = _app(tmp_path)
    a, b, c = (_on_video_page(app, f"forget0{i}") for i in range(3))
    a_names, c_names = _links(app, a.sid), _links(app, c.sid)
    assert len(a_names) == 2 and len(c_names) == 2
    _admin_op(app, "forget", participant=a.pid, confirm=a.pid)             # the admin page
    assert store_of(app).load(a.sid)[0] is None
    assert not any(os.path.lexists(tmp_path / "links" / n) for n in a_names)
    assert len(_links(app, b.sid)) == 2 and len(_links(app, c.sid)) == 2
    env = {"EVALSUITE_MEDIA_LINKS": str(tmp_path / "links"), "EVALSUITE_SECRET_KEY": SECRET}
    _cli("forget", study, "--db", db, c.pid, "--yes", env=env)              # the CLI, links from the environment
    assert not any(os.path.lexists(tmp_path / "links" / n) for n in c_names)
    assert len(_links(app, b.sid)) == 2
    _stimuli_intact(tmp_path)


def test_excluding_a_session_removes_its_links(tmp_path):
    app, _, _ = _app(tmp_path)
    a, b = _on_video_page(app, "excl0001"), _on_video_page(app, "excl0002")
    _admin_op(app, "exclude", session=a.sid, reason="bot")
    assert _links(app, a.sid) == [] and len(_links(app, b.sid)) == 2


def test_prune_links_removes_links_of_ended_sessions_only(tmp_path):
    app, study, db = _app(tmp_path)
    active, released, excluded = (_on_video_page(app, f"prune00{i}") for i in range(3))
    store = store_of(app)
    with store.ReadSession() as db_session:
        plan_key = db_session.scalar(select(Plan.key).where(Plan.session_id == released.sid))
    # ended outside the app's requests (the CLI without --links): their links are left behind
    _cli("release", study, "--db", db, plan_key)
    _cli("exclude", study, "--db", db, excluded.sid, "--reason", "duplicate")
    assert len(_links(app, released.sid)) == 2 and len(_links(app, excluded.sid)) == 2
    (tmp_path / "links" / "unrelated.txt").write_text("kept")
    out = _cli("prune-links", study, "--db", db, "--links", tmp_path / "links", "--secret-key", SECRET)
    assert out.startswith("4 links of ended sessions removed")
    assert _links(app, released.sid) == [] and _links(app, excluded.sid) == []
    assert len(_links(app, active.sid)) == 2 and (tmp_path / "links" / "unrelated.txt").read_text() == "kept"
    assert _cli("prune-links", study, "--db", db, "--links", tmp_path / "links", "--secret-key", SECRET
                ).startswith("0 links")
    _stimuli_intact(tmp_path)
    r = CliRunner().invoke(study_cli, ["prune-links", str(study), "--db", db], env={"EVALSUITE_MEDIA_LINKS": ""})
    assert r.exit_code != 0 and "--links" in r.output
