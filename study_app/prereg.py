"""A pre-registration draft for a study definition (``evalsuite study prereg``), as Markdown.

The items follow the OSF Preregistration template (Study information, Design plan, Sampling plan,
Variables, Analysis plan). Every item is filled from what the definition, its session plans, the sample-size
plan (:mod:`study_app.planning`) and ``evalsuite analyze``'s settings (:class:`~evalsuite.analysis.pipeline.
AnalysisOptions`) already say; what only the researcher can say (the hypotheses and their direction, the
authors, existing data, exploratory analyses) is marked ``TO COMPLETE`` with what to write.
"""
from __future__ import annotations

from evalsuite.analysis.pipeline import AnalysisOptions
from study_app.design import balance_report, position_spread
from study_app.model import Study
from study_app.planning import Effects, study_power

__all__ = ["ITEMS", "prereg_markdown"]

TODO = "**TO COMPLETE**"

# (section, item) in the order of the OSF Preregistration template.
ITEMS = [
    ("Study information", "Title"), ("Study information", "Authors"), ("Study information", "Description"),
    ("Study information", "Hypotheses"),
    ("Design plan", "Study type"), ("Design plan", "Blinding"), ("Design plan", "Study design"),
    ("Design plan", "Randomization"),
    ("Sampling plan", "Existing data"), ("Sampling plan", "Data collection procedures"),
    ("Sampling plan", "Sample size"), ("Sampling plan", "Sample size rationale"), ("Sampling plan", "Stopping rule"),
    ("Variables", "Manipulated variables"), ("Variables", "Measured variables"), ("Variables", "Indices"),
    ("Analysis plan", "Statistical models"), ("Analysis plan", "Inference criteria"),
    ("Analysis plan", "Data exclusion"), ("Analysis plan", "Missing data"), ("Analysis plan", "Exploratory analysis"),
]


def _blocks(study: Study) -> list[str]:
    lines = []
    for b in study.blocks.values():
        c = b.cfg
        what = f"- `{b.id}` ({b.type}{', muted' if c['muted'] else ', with sound'}): {c['pages']} trial pages per " \
               f"participant over segments {', '.join(c['segments'])}"
        if b.type == "pairwise":
            what += ("; each condition's matched video against the same speech with another segment's motion "
                     f"(conditions {', '.join(c['conditions'])})" if c["mismatched"] else
                     "; each condition's video with its own speech against the same motion with another segment's "
                     f"speech of the same speaker (conditions {', '.join(c['conditions'])})" if c["audio_mismatch"] else
                     "; comparisons " + ", ".join(f"{x} vs {y}" for x, y in c["pairs"]))
            what += f"; {c['levels']}-level answers"
        elif b.type == "mushra":
            hidden = [f"hidden {r} {c[r]}" for r in ("reference", "anchor") if c.get(r)]
            what += f"; every page rates {', '.join(c['conditions'] + hidden)} on 0-100 sliders ({c['layout']} layout)"
        else:
            what += f"; one video per page of {', '.join(c['conditions'])}, {c['points']}-point items"
        if c["attention_checks"]:
            what += f"; {len(c['attention_checks'])} attention check(s) near page(s) {c['attention_checks']}"
        lines.append(what + ".")
    return lines


def _adaptive_rule(study: Study) -> str:
    """The stopping-rule sentence for adaptive pairwise blocks (study_app.adaptive), or no interim analysis."""
    blocks = [b for b in study.blocks.values() if b.cfg.get("adaptive")]
    if not blocks:
        return " No interim analysis."
    names = ", ".join(f"`{b.id}` (exploration {b.cfg['exploration']:g})" for b in blocks)
    return (f" Adaptive pairwise blocks {names}: the server chooses each page's pair from the Bradley-Terry "
            "estimate of the answers so far (the most informative pair, or a uniform one at the exploration rate), "
            "so their comparisons are not balanced. It reports when every two neighbours in the estimated ranking "
            "are separated (95 % intervals of their differences exclude 0; `evalsuite study status`), an interim "
            f"look without correction. {TODO}: state whether data collection stops there or at the planned sessions.")


def _measures(study: Study) -> list[str]:
    out = []
    for b in study.blocks.values():
        c = b.cfg
        if b.type == "pairwise":
            for q in c["questions"]:
                out.append(f"- `{q['id']}` (`{b.id}`): \"{q['text']}\" answered left / equal / right"
                           + (" with clearly / slightly" if c["levels"] == 5 else "")
                           + (f"; reasons: {', '.join(r['id'] for r in c['reasons'])}" if c["reasons"] else ""))
        elif b.type == "mushra":
            out.append(f"- `{c['question']['id']}` (`{b.id}`): \"{c['question']['text']}\" rated 0-100, bands "
                       f"{' / '.join(c['bands'])}")
        else:
            for s in c["statements"]:
                out.append(f"- `{s['id']}` (`{b.id}`, scale `{s['scale']}`): \"{s['text']}\", 1-{c['points']}")
    return out


def _analysis(opt: AnalysisOptions, kinds: set[str]) -> list[str]:
    out = []
    if "pairwise" in kinds:
        out.append(f"- Pairwise preferences: two-sided exact binomial test against 50 % per comparison and question, "
                   f"ties {dict(exclude='left out', split='split equally', half='counted as half a win')[opt.tie_policy]}"
                   f" (`--tie-policy {opt.tie_policy}`), {opt.ci_method} {100 * (1 - opt.alpha):g} % CIs; a ranking "
                   f"by Bradley-Terry/Elo (prior {opt.elo_prior:g}) with {opt.n_boot} participant-bootstrap rounds "
                   f"(seed {opt.seed}); matched vs mismatched: share preferring the matched video, Barnard's exact "
                   "test between conditions; audio mismatch: per system the share preferring the video with its own "
                   "speech, exact binomial test against 50 % (Holm over the systems), systems ranked by that share.")
    if "mushra" in kinds:
        out.append(f"- Ratings 0-100: medians with order-statistic CIs; two-sided Wilcoxon signed-rank tests on pages "
                   f"rating both conditions (zero differences: `{opt.zero_method}`).")
    if "likert" in kinds:
        out.append("- Likert: scale score = mean of a scale's statements; Cronbach's alpha per scale; one-way and "
                   "repeated-measures ANOVA, post-hoc Welch and paired t-tests with Bonferroni correction.")
    out.append("- Software: `evalsuite analyze results.csv` with these settings"
               + (f" (`--preset {opt.preset}`)" if opt.preset else "") + ".")
    return out


def _exclusions(study: Study, opt: AnalysisOptions) -> list[str]:
    fails = "any failed attention check" if opt.attention_fails == 1 else f"{opt.attention_fails} or more failed " \
                                                                          "attention checks"
    out = [f"- Sessions with {fails} (the server ends a session at {study.max_failed_attention_checks} failures).",
           "- Sessions that did not finish" + (" (kept: `--keep-incomplete`)." if opt.keep_incomplete else "."),
           "- A participant id with several sessions: "
           + ("only the first is kept." if opt.duplicates == "keep-first" else "all are dropped."),
           (f"- Sessions with at least {opt.implausible_playback} page(s) the study server flagged for implausible "
            "playback (a video never fetched, or less time on the page than its clips last)."
            if opt.implausible_playback else "- Playback is not used to exclude."),
           "- Practice pages and the attention-check trials themselves are not analysed."]
    if any(b.type == "mushra" and b.cfg.get("reference") for b in study.blocks.values()):
        out.append("- BS.1534-3 post-screening on the hidden reference: " + (
            "on (rated below 90 on more than 15 % of items)." if opt.mushra_screening else
            "off (natural motion is no ceiling in a gesture study); the number it would exclude is reported."))
    return out


def prereg_markdown(study: Study, plans: dict, options: AnalysisOptions | None = None,
                    effects: Effects | None = None) -> str:
    """The draft (module docstring); ``plans``: the study's session plans (``design.build_plans``)."""
    opt, eff = options or AnalysisOptions(), effects or Effects()
    power = study_power(study, plans, eff)
    report = balance_report(plans, study)
    kinds = {b.type for b in study.blocks.values()}
    needed = max((r["participants"] or 0) for r in power) if power else 0
    conditions = sorted({c for b in study.blocks.values() for c in study.kind_of(b).shown_conditions(b.cfg)})
    spread = {k: position_spread(report[k]) for k in ("page_positions", "mushra_slots", "pairs")}
    worst = max((v for d in spread.values() for v in d.values()), default=0.0)
    text = {
        "Title": f"{study.title} (study `{study.id}`)",
        "Authors": f"{TODO}: names and affiliations.",
        "Description": f"A crowd perceptual study of speech-driven gesture generation on {study.platform}: "
                       f"participants watch short videos of an animated character and judge its motion. Pages in "
                       f"order: {', '.join(f'{p.id} ({p.type})' for p in study.pages)}.",
        "Hypotheses": f"{TODO}: for each comparison below, the expected direction and why (or state that it is "
                      "exploratory).\n\n" + "\n".join(
                          f"- H{i + 1} ({r['block']}, {r['design']}): {x} vs {y}: {TODO}"
                          for i, (r, (x, y)) in enumerate((r, p) for r in power for p in r["pairs"])),
        "Study type": "Experiment: participants are shown conditions in a within-participant design; assignment "
                      "to pre-built, balanced session plans.",
        "Blinding": "Participants do not know which system made a video: file names are blinded "
                    "(no condition name appears), nothing on a page differs between conditions, and attention-check "
                    "pages look like the others. The analysis can be run blind (`evalsuite analyze --blind`).",
        "Study design": f"Conditions: {', '.join(conditions)}. Blocks:\n\n" + "\n".join(_blocks(study)),
        "Randomization": f"{study.sessions} session plans built by `evalsuite study build` from seed {study.seed} "
                         "(the same plans on every build); each participant is given the next free plan. MUSHRA slot "
                         "orders are rows of random Latin squares, pairwise sides are dealt at random per comparison, "
                         "and page order is balanced so each item takes each position about equally often; attention "
                         f"checks move by up to a few pages per session. Largest distance of a position count from "
                         f"equal over the plans: {worst:.2g} (1 = equal within one).",
        "Existing data": f"{TODO}: e.g. \"Registration prior to creation of data\".",
        "Data collection procedures": f"Recruited on {study.platform}"
                                      + (f" (completion code on finishing, failure code {study.failure_code!r} on "
                                         "failing)" if study.completion_code else "")
                                      + f"; screens narrower than {study.min_width} px"
                                      + (" and phones" if study.block_mobile else "") + " are turned away; a plan is "
                                      f"reserved for {study.reservation_minutes:g} minutes; a session ends at "
                                      f"{study.max_failed_attention_checks} failed attention checks"
                                      + ("; videos must be watched to the end" if study.require_full_playback else "")
                                      + ".",
        "Sample size": f"{study.sessions} sessions are planned; reaching the stated power needs {needed} participants "
                       "(largest over the blocks, see the rationale)" + (
                           f". {TODO}: raise the definition's `sessions` to at least {needed}, or state why fewer "
                           "suffice" if needed > study.sessions else "") + ".",
        "Sample size rationale": f"`evalsuite study power` at alpha {eff.alpha:g}, power {eff.power:g}, "
                                 f"{eff.exclusion_rate:g} of sessions expected to be excluded; each comparison at "
                                 "Holm's strictest step alpha/K:\n\n" + "\n".join(
                                     f"- `{r['block']}` ({r['effect']}): family of {r['family']}, needs {r['needed']} "
                                     f"{r['unit']} per comparison -> {r['participants']} participants; "
                                     f"{study.sessions} sessions give power {r['achieved']:.2f}" for r in power),
        "Stopping rule": f"Data collection stops when {study.sessions} sessions have finished (every plan used once; "
                         + ("plans of failed sessions are released to new participants" if study.release_failed
                            else "plans of failed sessions are not reused") + ")." + _adaptive_rule(study),
        "Manipulated variables": f"The system that generated the motion (conditions {', '.join(conditions)}), within "
                                 "participants; the speech segment; for matched/mismatched blocks whether motion and "
                                 "speech belong together.",
        "Measured variables": "\n".join(_measures(study)),
        "Indices": "Preference share per comparison (ties as set below), Elo rating per condition; median rating "
                   "per condition; Likert scale score = mean of the scale's statements.",
        "Statistical models": "\n".join(_analysis(opt, kinds)),
        "Inference criteria": f"Two-sided tests at alpha = {opt.alpha:g}, Holm-Bonferroni per {opt.holm_scope} "
                              "(Bonferroni for Likert post-hoc tests).",
        "Data exclusion": "\n".join(_exclusions(study, opt)),
        "Missing data": "A comparison with no judgement left after the exclusions is reported without a test; "
                        "pages not answered are absent from results.csv (no imputation).",
        "Exploratory analysis": f"{TODO}: analyses beyond the above (e.g. correlations of objective metrics with "
                                "the ratings, `evalsuite correlate`).",
    }
    out = [f"# Pre-registration draft: {study.title}", "",
           f"Written by `evalsuite study prereg` from `{study.path.name}` (sha256 {study.sha256[:12]}). Items marked "
           f"{TODO} need the researcher; check the rest.", ""]
    section = ""
    for sec, item in ITEMS:
        if sec != section:
            out += [f"## {sec}", ""]
            section = sec
        out += [f"### {item}", "", text[item], ""]
    return "\n".join(out)
