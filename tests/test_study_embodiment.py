"""The stimuli's embodiment (study_app.embodiment): render stimuli writes style, character, framing and face into
the manifest; the study's admin page, raw export and ``study export`` say it, so a paper can report it."""
from __future__ import annotations

import csv
import json

import study_helpers as h
from click.testing import CliRunner
from study_fixtures import make_app

from evalsuite.contracts.manifest import EMBODIMENT
from study_app.cli import study as study_cli
from study_app.embodiment import describe_embodiment, embodiment_columns
from study_app.samples import make_sample_stimuli


def test_columns_and_description():
    rows = [{"style": "mannequin", "framing": "above-knees", "face": "blank", "character": ""},
            {"style": "mannequin", "framing": "upper", "face": "blank"}, {"file": "x"}]
    emb = embodiment_columns(rows)
    assert emb == {"style": ["mannequin"], "framing": ["above-knees", "upper"], "face": ["blank"]}
    assert describe_embodiment(emb) == "mannequin body; framing above-knees/upper; face blank"
    assert describe_embodiment({"style": ["character"], "character": ["genea.glb"]}) == \
        "character body; character genea.glb"
    assert "not recorded" in describe_embodiment({})


def test_admin_page_and_exports_say_the_embodiment(tmp_path, sqlite_url):
    manifest = make_sample_stimuli(tmp_path / "stim", h.CONDITIONS, h.SEGMENTS, mismatched=True,
                                   attention=h.ATTENTION)
    with open(manifest, newline="") as fh:
        reader = csv.DictReader(fh)
        fields, rows = list(reader.fieldnames or []) + list(EMBODIMENT), list(reader)
    for r in rows:
        r.update(style="mannequin", character="", framing="above-knees", face="blank")
    with open(manifest, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=fields)
        w.writeheader()
        w.writerows(rows)
    study_file = h.make_study(tmp_path)
    app = make_app(tmp_path, sqlite_url)
    said = "mannequin body; framing above-knees; face blank"
    client = app.test_client()
    auth = {"Authorization": f"Bearer {h.ADMIN}"}
    assert f"Stimuli: {said}" in client.get("/admin/", headers=auth).get_data(as_text=True)
    raw = json.loads(client.get("/admin/export/raw.json", headers=auth).get_data(as_text=True))
    assert raw["embodiment"] == {"style": ["mannequin"], "framing": ["above-knees"], "face": ["blank"]}
    res = CliRunner().invoke(study_cli, ["export", str(study_file), "--db", sqlite_url,
                                         "-o", str(tmp_path / "results.csv")])
    assert res.exit_code == 0, res.output
    assert f"stimuli: {said}" in res.output


def test_render_stimuli_writes_the_embodiment_columns(tmp_path):
    import yaml
    from test_render_stimuli import make_project, read_rows

    from renderers.stimuli import build_stimuli

    config = make_project(tmp_path, segments=("seg01",), seconds=0.4, checks=False)
    cfg = yaml.safe_load(config.read_text())
    cfg["render"].update(body="mannequin", framing="above-knees", face="blank")
    config.write_text(yaml.safe_dump(cfg))
    build_stimuli(config, echo=lambda *a: None)
    rows = read_rows(tmp_path / "out" / "manifest.csv")
    assert rows and all((r["style"], r["character"], r["framing"], r["face"]) == ("mannequin", "", "above-knees",
                                                                                  "blank") for r in rows)


def test_the_character_style_names_its_character_even_the_shipped_one():
    from renderers.scene import RenderSettings
    from renderers.stimuli import embodiment_of

    assert embodiment_of(RenderSettings(body="character"))["character"] == "mpfb2_neutral.glb"
    assert embodiment_of(RenderSettings(body="character", character="/x/hero.glb"))["character"] == "hero.glb"
    assert embodiment_of(RenderSettings(body="mannequin"))["character"] == ""
