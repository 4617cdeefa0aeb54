"""The report of a MUSHRA-only study: notes collapsed, only the settings that apply, the decisive
columns on screen, a legend on the significance matrix."""
import re

import numpy as np
import pandas as pd
import pytest
from browser_helpers import ARGS, chromium
from click.testing import CliRunner

from evalsuite.analysis.report import fig_significance
from evalsuite.analysis.sections import collapse_notes, display_order
from evalsuite.cli import main

CONDS = ["NA", "S1", "S2", "S3", "S4", "S5", "S6", "BL"]


def mushra_study(path, participants=21, pages=10, seed=5):
    """A MUSHRA-only study like a real one: ratings in steps of 5, so equal paired ratings are common."""
    rng = np.random.default_rng(seed)
    quality = dict(zip(CONDS, [95, 70, 66, 60, 55, 50, 45, 20]))
    rows = []
    for p in range(participants):
        for k in range(pages):
            for slot, c in enumerate(rng.permutation(CONDS)):
                v = quality[c] + rng.normal(0, 12)
                rows.append({"study": "hl", "participant": f"P{p:02d}", "session": f"S{p:02d}",
                             "session_status": "finished", "page": f"page{k}", "page_type": "mushra",
                             "question": "human_likeness", "condition": c, "condition_a": "", "condition_b": "",
                             "answer": str(int(np.clip(5 * round(v / 5), 0, 100))), "is_training": "0",
                             "is_attention_check": "0", "attention_passed": "", "position_a": str(slot),
                             "role": "", "shown_at": f"2026-03-02T10:{k:02d}:00Z"})
    pd.DataFrame(rows).to_csv(path, index=False)
    return path


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("mushra")
    src = mushra_study(tmp / "results.csv")
    r = CliRunner().invoke(main, ["analyze", str(src), "-o", str(tmp / "o")], catch_exceptions=False)
    assert r.exit_code == 0, r.output
    html = re.sub(r'src="data:image/png;base64,[^"]*"', 'src=""', (tmp / "o" / "report.html").read_text())
    return tmp / "o", html, r.output


def section(html, heading):
    m = re.search(rf"<h2>{heading}</h2>(.*?)(<h2>|</body>)", html, re.S)
    return m.group(1) if m else ""


def test_repeated_notes_are_one_line_with_a_count(report):
    out, html, console = report
    pairs = pd.read_csv(out / "ratings_pairwise.csv", keep_default_na=False)
    zero_notes = (pairs["note"].str.contains("zero difference")).sum()
    assert zero_notes > 10                                  # the situation of the review: many such notes
    notes = re.findall(r"<li>(.*?)</li>", section(html, "Notes"))
    zero_lines = [n for n in notes if "zero difference" in n]
    assert len(zero_lines) == 1
    assert f"{zero_notes} times" in zero_lines[0]
    assert len([ln for ln in console.splitlines() if "zero difference" in ln]) == 1


def test_only_settings_that_apply_to_a_mushra_only_study(report):
    _, html, _ = report
    settings = section(html, "Settings")
    for absent in ("tie policy", "preference CI", "bootstrap", "Elo", "attention checks", "Likert"):
        assert absent not in settings, absent
    for present in ("Wilcoxon zero differences", "multiple comparisons"):
        assert present in settings


def test_decisive_columns_come_right_after_the_identifiers(report):
    _, html, _ = report
    tables = re.findall(r"<table.*?</table>", html, re.S)
    heads = [re.findall(r"<th>(.*?)</th>", t) for t in tables]
    wil = next(h for h in heads if "condition_1" in h and "better" in h)
    assert wil[:6] == ["question", "condition_1", "condition_2", "better", "significant", "p_holm"]
    df = pd.DataFrame(columns=["question", "condition_a", "condition_b", "n_a", "n_b", "n_tie", "pref_a", "ci_low",
                               "ci_high", "p_value", "p_holm", "k", "significant", "note"])
    assert list(display_order(df).columns[:8]) == ["question", "condition_a", "condition_b", "significant",
                                                     "p_holm", "pref_a", "ci_low", "ci_high"]


@pytest.mark.browser
def test_decisive_columns_visible_at_1300_px(report):
    from playwright.sync_api import sync_playwright

    out, _, _ = report
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=chromium(), args=ARGS)
        try:
            page = browser.new_page(viewport={"width": 1300, "height": 900})
            page.goto((out / "report.html").as_uri())
            right = page.evaluate("""() => Array.from(document.querySelectorAll('th'))
                .filter(th => ['p_holm', 'significant', 'better'].includes(th.textContent))
                .map(th => th.getBoundingClientRect().right)""")
        finally:
            browser.close()
    assert len(right) >= 3
    assert max(right) <= 1300


def test_significance_matrix_has_a_legend_for_every_colour():
    m = pd.DataFrame([[np.nan, 1, 0], [-1, np.nan, np.nan], [0, np.nan, np.nan]], index=list("ABC"),
                     columns=list("ABC"))
    fig = fig_significance(m, "q")
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert any(lab == "not significant" for lab in labels)
    assert any("higher" in lab for lab in labels) and any("lower" in lab for lab in labels)
    assert any("no test" in lab for lab in labels)


def test_collapse_keeps_single_notes_and_ranges_varying_numbers():
    items = [("Wilcoxon", f"q / A / B{i}", f"{i} zero difference(s) dropped (zero_method=wilcox)",
              "ratings_pairwise") for i in (3, 7, 12)]
    items.append(("ranking", "q", "a single participant: no bootstrap CI", "elo"))
    lines = collapse_notes(items)
    assert lines[1] == "ranking q: a single participant: no bootstrap CI"
    assert lines[0].startswith("Wilcoxon, 3 times: N zero difference(s) dropped (zero_method=wilcox) (N = 3 to 12)")
    assert "ratings_pairwise.csv" in lines[0]


def test_collapse_keeps_numbers_with_thousands_separators():
    items = [("Barnard", f"q / A / B{i}", f"{n} and {n} judgements: above the exact test's limit (250,000 tables)",
              "mismatch_barnard") for i, n in enumerate((24314, 1200))]
    (line,) = collapse_notes(items)
    assert "(250,000 tables)" in line and "N = 1200 to 24314" in line


def test_long_tables_are_cut_in_the_report_with_a_pointer_to_the_csv():
    from evalsuite.analysis.report import HTML_MAX_ROWS, html_table

    df = pd.DataFrame({"participant": [f"P{i}" for i in range(HTML_MAX_ROWS + 100)], "reason": "x"})
    out = html_table(df, "exclusions")
    assert out.count("<tr>") == HTML_MAX_ROWS               # the first rows (the header row is "<tr style=...")
    assert "... and 100 more rows (all in exclusions.csv)" in out
