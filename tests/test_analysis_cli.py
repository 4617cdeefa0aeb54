"""`evalsuite analyze` end to end: outputs, report with every figure, blinding, errors."""
import base64
import re

import pandas as pd
import pytest
from browser_helpers import ARGS, chromium
from click.testing import CliRunner

from evalsuite.analysis.demo import run as demo_run
from evalsuite.analysis.demo import sample_results_path
from evalsuite.cli import main

SAMPLE = sample_results_path()
REAL_NAMES = ["SysA", "SysB", "Jitter", "NA:mismatched"]
STABLE = ["question", "condition_a", "condition_b", "n_a", "n_b", "n_tie", "pref_a", "ci_low", "ci_high",
          "p_value", "p_holm"]


def invoke(*args):
    return CliRunner().invoke(main, ["analyze", *map(str, args)], catch_exceptions=False)


@pytest.fixture(scope="module")
def analysed(tmp_path_factory):
    out = tmp_path_factory.mktemp("analysis")
    r = invoke(SAMPLE, "-o", out, "--bootstrap", "300")
    assert r.exit_code == 0, r.output
    return out, r.output


def text_outputs(out):
    return [p for p in out.rglob("*") if p.suffix in {".csv", ".md", ".tex", ".html", ".json"}]


def html_without_images(path):
    return re.sub(r'src="data:image/png;base64,[^"]*"', 'src=""', path.read_text())


def test_all_outputs_written(analysed):
    out, output = analysed
    for name in ["pairwise", "ratings", "ratings_pairwise", "exclusions", "elo", "mismatch", "mismatch_barnard",
                 "likert_reliability", "likert_means", "likert_anova", "likert_posthoc"]:
        for ext in ("csv", "md", "tex"):
            assert (out / f"{name}.{ext}").is_file(), f"{name}.{ext}"
    assert list(pd.read_csv(out / "pairwise.csv").columns[:11]) == STABLE
    assert (out / "report.html").is_file()
    assert "Report:" in output
    excl = pd.read_csv(out / "exclusions.csv")
    # BS.1534-3 post-screening is off for gesture studies; the output says whom it would exclude
    assert set(excl["reason"]) == {"attention_checks", "session_failed", "duplicate_participant"}
    assert "post-screening (--preset mushra-itu) is off; it would exclude 1 session(s)" in output
    assert "\\begin{tabular}" in (out / "pairwise.tex").read_text()
    assert (out / "pairwise.md").read_text().startswith("| question | condition_a |")


def test_mushra_itu_preset_turns_post_screening_on(tmp_path):
    r = invoke(SAMPLE, "-o", tmp_path, "--bootstrap", "0", "--no-figures", "--preset", "mushra-itu")
    assert r.exit_code == 0, r.output
    excl = pd.read_csv(tmp_path / "exclusions.csv")
    assert list(excl.loc[excl["reason"] == "mushra_post_screening", "participant"]) == ["P09"]
    assert "it would exclude" not in r.output
    assert "on: excludes 1 session(s)" in (tmp_path / "report.html").read_text()
    explicit = invoke(SAMPLE, "-o", tmp_path / "off", "--bootstrap", "0", "--no-figures", "--preset", "mushra-itu",
                      "--no-mushra-screening")
    assert "mushra_post_screening" not in (tmp_path / "off" / "exclusions.csv").read_text()
    assert "it would exclude 1 session(s)" in explicit.output


def test_no_nan_text_anywhere(analysed):
    out, output = analysed
    for p in text_outputs(out):
        text = html_without_images(p) if p.suffix == ".html" else p.read_text()
        assert not re.search(r"\bnan\b", text, re.IGNORECASE), p.name
    assert not re.search(r"\bnan\b", output, re.IGNORECASE)


def test_html_embeds_every_figure_as_base64_png(analysed):
    out, _ = analysed
    html = (out / "report.html").read_text()
    figures = sorted((out / "figures").glob("*.png"))
    names = {p.stem.split("_")[0] for p in figures}
    assert {"preference", "ratings", "significance", "elo", "mismatch", "likert"} <= names
    imgs = re.findall(r'<img[^>]*src="data:image/png;base64,([^"]+)"', html)
    assert len(imgs) == len(figures)
    embedded = {base64.b64decode(s) for s in imgs}
    for p in figures:
        assert p.read_bytes() in embedded, p.name
    assert all(b.startswith(b"\x89PNG\r\n\x1a\n") for b in embedded)
    assert "<h2>Exclusions</h2>" in html
    assert "off (would exclude 1 session(s))" in html
    assert "<script" not in html and "http" not in html.replace("http-equiv", "")  # self-contained


def test_report_renders_every_figure_in_a_browser(analysed, tmp_path):
    from playwright.sync_api import sync_playwright

    out, _ = analysed
    n_fig = len(list((out / "figures").glob("*.png")))
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=chromium(), args=ARGS)
        try:
            page = browser.new_page(viewport={"width": 1200, "height": 3000})
            page.goto((out / "report.html").as_uri())
            sizes = page.evaluate("Array.from(document.images).map(i => [i.complete, i.naturalWidth])")
            page.screenshot(path=str(tmp_path / "report.png"), full_page=True)
        finally:
            browser.close()
    assert len(sizes) == n_fig
    assert all(ok and w > 100 for ok, w in sizes)
    assert (tmp_path / "report.png").stat().st_size > 50_000


@pytest.mark.slow
def test_blind_then_reveal(tmp_path):
    out = tmp_path / "blind"
    r = invoke(SAMPLE, "-o", out, "--blind", "--bootstrap", "50")
    assert r.exit_code == 0
    assert "Blind analysis" in r.output
    for p in text_outputs(out):
        text = html_without_images(p) if p.suffix == ".html" else p.read_text()
        for name in REAL_NAMES:
            assert name not in text, (p.name, name)
    assert name not in r.output
    blinded = pd.read_csv(out / "pairwise.csv")
    conds = set(blinded["condition_a"]) | set(blinded["condition_b"])
    assert all(re.fullmatch(r"B\d\d(:mismatched)?", c) for c in conds)
    # Still blind without the flag, and the codes are stable.
    r2 = invoke(SAMPLE, "-o", out, "--bootstrap", "50")
    assert r2.exit_code == 0
    pd.testing.assert_frame_equal(pd.read_csv(out / "pairwise.csv"), blinded)
    assert not (out / "blind_key.csv").exists()
    # Both flags: refused.
    r3 = CliRunner().invoke(main, ["analyze", str(SAMPLE), "-o", str(out), "--blind", "--reveal"])
    assert r3.exit_code == 1
    assert "exclude each other" in r3.output
    # Reveal: real names and a key that maps the blinded rows onto the revealed ones.
    r4 = invoke(SAMPLE, "-o", out, "--reveal", "--bootstrap", "50")
    assert r4.exit_code == 0
    assert "Revealed" in r4.output
    # keep_default_na=False: the natural-motion condition is called "NA".
    key = dict(pd.read_csv(out / "blind_key.csv", keep_default_na=False).itertuples(index=False))
    revealed = pd.read_csv(out / "pairwise.csv", keep_default_na=False)
    assert "SysA" in set(revealed["condition_a"]) | set(revealed["condition_b"])

    def canon(df, names):
        rows = set()
        for r in df.itertuples(index=False):
            a, b, na, nb = names(r.condition_a), names(r.condition_b), r.n_a, r.n_b
            if a > b:
                a, b, na, nb = b, a, nb, na
            rows.add((r.question, a, b, na, nb, r.n_tie))
        return rows
    assert canon(blinded, key.__getitem__) == canon(revealed, lambda c: c)
    # After --reveal the folder is no longer blind.
    r5 = invoke(SAMPLE, "-o", out, "--bootstrap", "50")
    assert "Blind analysis" not in r5.output


def test_bad_csv_gives_error_without_traceback(tmp_path):
    lines = SAMPLE.read_text().splitlines()
    header = lines[0].split(",")
    row = lines[5].split(",")
    row[header.index("session_status")] = "done"
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join(lines[:5] + [",".join(row)] + lines[6:]) + "\n")
    r = CliRunner().invoke(main, ["analyze", str(bad), "-o", str(tmp_path / "o")])
    assert r.exit_code == 1
    assert "Error:" in r.output
    assert "bad.csv:6: session_status: unknown value 'done'" in r.output
    assert "Traceback" not in r.output
    r = CliRunner().invoke(main, ["analyze", str(tmp_path / "missing.csv")])
    assert r.exit_code == 1
    assert "file not found" in r.output


def test_comparison_with_no_data_gets_a_message(tmp_path):
    # C is only compared by a participant whose session failed.
    rows = []
    for p, status, pairs in (("P1", "finished", [("A", "B", "a")] * 6 + [("A", "B", "b")]),
                             ("P2", "failed", [("A", "C", "a")] * 3)):
        for i, (a, b, ans) in enumerate(pairs):
            rows.append({"study": "s", "participant": p, "session": "S" + p, "session_status": status,
                         "page": f"p{i}", "page_type": "pairwise", "question": "hl", "condition": "",
                         "condition_a": a, "condition_b": b, "answer": ans, "is_training": 0,
                         "is_attention_check": 0, "attention_passed": ""})
    path = tmp_path / "r.csv"
    pd.DataFrame(rows).to_csv(path, index=False)
    r = invoke(path, "-o", tmp_path / "o", "--bootstrap", "20")
    assert r.exit_code == 0, r.output
    assert "pairwise hl / A / C: no judgements for this comparison (after exclusions)" in r.output
    t = pd.read_csv(tmp_path / "o" / "pairwise.csv", keep_default_na=False).set_index("condition_b")
    assert t.loc["C", "p_value"] == ""
    assert t.loc["C", "p_holm"] == ""
    assert "no judgements" in t.loc["C", "note"]
    assert float(t.loc["B", "p_holm"]) == pytest.approx(float(t.loc["B", "p_value"]))  # family of one
    html = html_without_images(tmp_path / "o" / "report.html")
    assert "no judgements for this comparison" in html
    assert not re.search(r"\bnan\b", html, re.I)


def test_battles_csv_through_cli(tmp_path):
    lines = ["participant,item,condition_a,condition_b,winner,strength"]
    for u in range(6):
        lines += [f"u{u},c1,A,B,a,strong", f"u{u},c2,B,C,a,weak", f"u{u},c3,A,C,a,weak", f"u{u},c4,C,A,tie,"]
    path = tmp_path / "battles.csv"
    path.write_text("\n".join(lines) + "\n")
    r = invoke(path, "-o", tmp_path / "o", "--bootstrap", "100", "--tie-policy", "split")
    assert r.exit_code == 0, r.output
    elo = pd.read_csv(tmp_path / "o" / "elo.csv")
    assert list(elo["condition"]) == ["A", "B", "C"]
    assert (tmp_path / "o" / "figures" / "elo_preference.png").is_file()


def test_demo_step(tmp_path):
    said = []
    demo_run(tmp_path, said.append)
    assert (tmp_path / "analysis" / "report.html").is_file()
    assert any("simulated" in s for s in said)
    assert "SIMULATED" in SAMPLE.read_text().splitlines()[1]


def test_sample_is_regenerated_exactly_by_the_simulator(tmp_path):
    from evalsuite.analysis.simulate import main as simulate_main

    simulate_main([str(tmp_path / "s.csv")])
    assert (tmp_path / "s.csv").read_text() == SAMPLE.read_text()


def test_everyone_excluded_gives_messages_and_no_nan(tmp_path):
    bad = tmp_path / "all_failed.csv"
    bad.write_text(SAMPLE.read_text().replace(",finished,", ",failed,"))
    r = invoke(bad, "-o", tmp_path / "o", "--bootstrap", "20")
    assert r.exit_code == 0, r.output
    assert "no judgements left after exclusions" in r.output
    ratings = pd.read_csv(tmp_path / "o" / "ratings.csv", keep_default_na=False)
    assert (ratings["n"] == 0).all()
    assert (ratings["note"] == "no ratings (after exclusions)").all()
    for p in text_outputs(tmp_path / "o"):
        text = html_without_images(p) if p.suffix == ".html" else p.read_text()
        assert not re.search(r"\bnan\b", text, re.IGNORECASE), p.name


def test_no_figures_still_writes_every_table(tmp_path):
    """--no-figures skips the PNGs only: the significance matrices are tables (docs/analysis.md)."""
    with_figs, without = tmp_path / "with", tmp_path / "without"
    assert CliRunner().invoke(main, ["analyze", str(SAMPLE), "-o", str(with_figs)]).exit_code == 0
    res = CliRunner().invoke(main, ["analyze", str(SAMPLE), "-o", str(without), "--no-figures"])
    assert res.exit_code == 0, res.output
    tables = sorted(p.name for p in with_figs.glob("*.csv"))
    assert any(name.startswith("significance_") for name in tables)
    assert sorted(p.name for p in without.glob("*.csv")) == tables
    assert not list(without.glob("figures/*.png"))
