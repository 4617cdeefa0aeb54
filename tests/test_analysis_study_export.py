"""The study app's real results.csv export goes through `evalsuite analyze` unchanged."""
import csv
from collections import Counter

import numpy as np
import pandas as pd
import pytest
import study_helpers as h
from click.testing import CliRunner

from evalsuite.cli import main


@pytest.mark.slow
def test_study_app_export_is_analysed(tmp_path):
    from study_app import create_app

    h.make_study(tmp_path, sessions=6)
    app = create_app({"STUDY": str(tmp_path / "study.yaml"), "DATABASE_URL": f"sqlite:///{tmp_path / 's.db'}",
                      "SECRET_KEY": h.SECRET, "ADMIN_TOKEN": h.ADMIN, "SESSION_COOKIE_SECURE": False,
                      "INSTANCE_PATH": str(tmp_path / "inst")})
    rng = np.random.default_rng(5)
    for i in range(4):
        h.run_participant(app, app.test_client(), f"pfinish{i}", rng)
    h.run_participant(app, app.test_client(), "pfail0001", rng, fail_checks=2)
    r = app.test_client().get("/admin/export/results.csv", headers={"Authorization": f"Bearer {h.ADMIN}"})
    assert r.status_code == 200
    path = tmp_path / "results.csv"
    path.write_bytes(r.data)

    out = tmp_path / "analysis"
    # The simulated clients rate at random, so BS.1534 post-screening would drop everyone; they fetch no
    # video and answer in milliseconds, so the server flags their playback (tested in test_study_abuse.py).
    res = CliRunner().invoke(main, ["analyze", str(path), "-o", str(out), "--bootstrap", "50",
                                    "--no-mushra-screening", "--implausible-playback", "off"])
    assert res.exit_code == 0, res.output

    # Independent count from the export: finished sessions, no training, no checks.
    rows = [x for x in csv.DictReader(path.open()) if x["session_status"] == "finished"
            and x["is_training"] == "0" and x["is_attention_check"] == "0" and x["page_type"] == "pairwise"]
    expect = Counter()
    for x in rows:
        a, b, ans = x["condition_a"], x["condition_b"], x["answer"]
        if a > b:
            a, b, ans = b, a, {"a": "b", "b": "a", "tie": "tie"}[ans]
        expect[(x["question"], a, b, ans)] += 1
    table = pd.read_csv(out / "pairwise.csv", keep_default_na=False)
    got = Counter()
    for t in table.itertuples(index=False):
        for ans, n in (("a", t.n_a), ("b", t.n_b), ("tie", t.n_tie)):
            if n:
                got[(t.question, t.condition_a, t.condition_b, ans)] = n
    assert got == expect
    mismatch = pd.read_csv(out / "mismatch.csv", keep_default_na=False)
    assert set(mismatch["condition"]) == {"SYSALPHA", "SYSBETA"}
    excl = pd.read_csv(out / "exclusions.csv", keep_default_na=False)
    assert set(excl.loc[excl["participant"] == h.valid_pid("pfail0001"), "reason"]) == {"session_failed", "attention_checks"}
    assert (out / "ratings.csv").is_file()
    assert (out / "likert_means.csv").is_file()
