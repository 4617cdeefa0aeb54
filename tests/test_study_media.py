"""Stimulus serving (study_app.media): only the media slots of the session's own plan, never a path."""
from __future__ import annotations

import numpy as np
import study_helpers as h
from study_fixtures import make_app, walk_to


def test_stimulus_serving_is_limited_to_the_plan(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    p = h.Participant(app.test_client(), "ptrav0001")
    p.enter()
    data, csrf, _ = walk_to(app, p, "pairwise", np.random.default_rng(0))   # the first video page
    ok = p.client.get(data["videos"][0], headers={"Range": "bytes=0-99"})
    assert ok.status_code == 206
    assert ok.mimetype == "video/mp4"
    assert len(ok.data) == 100
    first = sorted((study_dir / "stim").glob("*.mp4"))[0].name
    bad = [f"/s/{p.sid}/media/{data['index']}/9", f"/s/{p.sid}/media/{data['index'] + 1}/0",
           f"/s/{p.sid}/media/-1/0", f"/s/{p.sid}/media/../../../etc/passwd",
           f"/s/{p.sid}/media/{data['index']}/..%2f..%2fstudy.yaml",
           f"/s/{p.sid}/media/%2e%2e/%2e%2e/study.yaml", f"/s/{p.sid}/media/{first}",
           "/static/../study.yaml", "/static/..%2f..%2fapp.py", "/static/%2e%2e/app.py",
           f"/stim/{first}", "/stim/manifest.csv", "/study.yaml"]
    for url in bad:
        r = p.client.get(url)
        assert r.status_code in (403, 404), url
        assert b"condition" not in r.data
        assert b"file,segment" not in r.data
