"""The exports (study_app.export and ``evalsuite study export``): results.csv and the raw JSON hold exactly
the answers given, once each."""
from __future__ import annotations

import csv
import itertools
import json

import numpy as np
import study_helpers as h
from study_fixtures import export_rows, make_app

_counter = itertools.count()


def test_full_sessions_export_equals_answers(study_dir, db_url):
    app = make_app(study_dir, db_url)
    rng = np.random.default_rng(1)
    done, r = h.run_participant(app, app.test_client(), "pfinish01", rng)
    html = r.get_data(as_text=True)
    assert "DONE1234" in html
    assert "https://app.prolific.com/submissions/complete?cc=DONE1234" in html
    failed, r = h.run_participant(app, app.test_client(), "pfail0001", rng, fail_checks=2)
    assert "FAIL5678" in r.get_data(as_text=True)
    assert "cc=FAIL5678" in r.get_data(as_text=True)
    partial, _ = h.run_participant(app, app.test_client(), "ppartial1", rng, stop_after=6)
    rows = export_rows(app)
    keys = h.as_keys(rows)
    assert len(keys) == len(set(keys))                                  # no duplicated judgement
    assert set(keys) == h.expected_rows(app, [done, failed, partial])     # exactly the answers given
    status = {r["participant"]: r["session_status"] for r in rows}
    pid = h.valid_pid
    assert status == {pid("pfinish01"): "finished", pid("pfail0001"): "failed", pid("ppartial1"): "incomplete"}
    checks = [r for r in rows if r["is_attention_check"] == "1"]
    assert {(r["participant"], r["attention_passed"]) for r in checks} == {
        (pid("pfinish01"), "1"), (pid("pfail0001"), "0")}
    assert all(r["is_training"] == "1" for r in rows if r["page"].startswith("training"))
    for r in rows:
        assert int(r["rt_ms"]) >= 0
        assert r["shown_at"] <= r["answered_at"]
        assert r["shown_at"].endswith("Z")
        assert r["study"] == "gesture-test"
        assert r["platform"] == "prolific"
    # raw JSON has the questionnaire and the interaction log
    raw = json.loads(app.test_client().get("/admin/export/raw.json",
                                           headers={"Authorization": f"Bearer {h.ADMIN}"}).data)
    assert any(a["data"].get("responses", {}).get("gender") == "other" for a in raw["answers"])
    assert {e["kind"] for e in raw["events"]} == {"ended"}
    # the CLI export reads the same database
    from click.testing import CliRunner

    from evalsuite.cli import main
    out = study_dir / f"cli-{next(_counter)}.csv"
    res = CliRunner().invoke(main, ["study", "export", str(study_dir / "study.yaml"), "--db", db_url,
                                    "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert h.as_keys(csv.DictReader(out.open())) == keys
