"""The page-kind registry: a rating kind defined in this test (module, template, no other edits) works end
to end — a definition using it builds, a participant's page renders it, an answer is validated and stored,
the session moves on, and the export has its rows."""
from __future__ import annotations

import csv
import io
from typing import Any

import pytest
import study_helpers as h

from study_app import create_app
from study_app.context import store_of
from study_app.pages import BlockKind, Media, page_kinds, register_page_kind, unregister_page_kind
from study_app.pages.base import check_cols, export_condition, segment_for
from study_app.payload import int_in, only_keys

TOY_YAML = """\
id: toy-study
stimuli: stim/manifest.csv
platform: prolific
sessions: 2
completion_code: DONE1234
pages:
  - type: intensity
    id: loud
    conditions: [SYSALPHA, SYSBETA]
    pages: 2
    question: How energetic is the motion?
  - type: finish
    id: finish
    text: Thanks.
"""


class IntensityKind(BlockKind):
    """One video and an energy rating from 1 to 3 (a toy rating kind)."""

    name = "intensity"
    keys = BlockKind.keys + ("question",)

    def min_conditions(self, page: dict) -> int:
        return 1

    def load_options(self, chk: Any, page: dict, where: str, cfg: dict, known: list[str]) -> None:
        cfg["question"] = chk.get(page, "question", where, str, required=True)

    def attention_fits(self, stim: Any, cfg: dict) -> bool:
        return False

    def regular_page(self, block: Any, g: int, lookup: Any, segments: list[str]) -> dict:
        cond = block.cfg["conditions"][g % len(block.cfg["conditions"])]
        seg = segment_for(g, len(block.cfg["conditions"]), segments)
        return {"type": self.name, "segment": seg, "stimulus": lookup.file(cond, seg)}

    def check_page(self, block: Any, k: int, pool: list, lookup: Any) -> dict:
        return {}

    def n_slots(self, spec: dict) -> int:
        return 1

    def media(self, study: Any, spec: dict, slot: int) -> Media:
        return Media(file=spec["stimulus"])

    def parse_answer(self, study: Any, spec: dict, answer: dict, fields: dict) -> dict:
        only_keys(answer, ("energy",), "answer")
        return {"energy": int_in(answer.get("energy"), 1, 3, "answer.energy")}

    def export_rows(self, study: Any, spec: dict, answer: Any, base: dict) -> list[dict]:
        stim = study.manifest.by_file()[spec["stimulus"]]
        return [{**base, "question": "energy", "condition": export_condition(stim),
                 "answer": answer.data["energy"], **check_cols(spec, answer, "")}]


@pytest.fixture
def toy_kind(tmp_path):
    folder = tmp_path / "templates"
    (folder / "pages").mkdir(parents=True)
    (folder / "pages" / "intensity.html").write_text(
        '<p class="toy-question">{{ page.question }}</p>\n'
        '{% for k in range(1, 4) %}<label><input type="radio" name="energy" value="{{ k }}"> {{ k }}</label>'
        '{% endfor %}\n')
    kind = IntensityKind()
    type(kind).template_folder = str(folder)
    register_page_kind(kind)
    yield kind
    unregister_page_kind(kind.name)


def test_a_rating_kind_defined_in_a_test_works_end_to_end(toy_kind, tmp_path):
    study_path = h.make_study(tmp_path, yaml_text=TOY_YAML, name="toy.yaml")
    app = create_app({"STUDY": str(study_path), "DATABASE_URL": f"sqlite:///{tmp_path / 'toy.db'}",
                      "SECRET_KEY": h.SECRET, "ADMIN_TOKEN": h.ADMIN, "SESSION_COOKIE_SECURE": False,
                      "INSTANCE_PATH": str(tmp_path / "inst")})
    p = h.Participant(app.test_client(), "5f3a1c9e8b7d6a5f4e3d2c1a", study_id="toy-study")
    assert p.enter().status_code == 302
    r, data, csrf = p.page()
    html = r.get_data(as_text=True)
    assert data["type"] == "intensity"
    assert "How energetic is the motion?" in html     # its own template, from its own folder
    assert len(data["videos"]) == 1
    assert p.get(data["videos"][0]).status_code == 200   # its media hook serves the stimulus
    # its answer validation: out of range refused with the field named, nothing stored
    bad = p.submit(data, csrf, {"energy": 7})
    assert bad.status_code == 422
    assert "answer.energy" in bad.get_json()["error"]
    assert p.submit(data, csrf, {"energy": 2}).status_code == 200
    r, data, csrf = p.page()
    assert p.submit(data, csrf, {"energy": 3}).status_code == 200
    _, data, _ = p.page()
    assert data is None                                  # the finish page: session completed
    with store_of(app).Session() as db:
        from study_app.storage import ParticipantSession
        assert db.get(ParticipantSession, p.sid).status == "finished"
    export = app.test_client().get("/admin/export/results.csv", headers={"Authorization": f"Bearer {h.ADMIN}"})
    rows = list(csv.DictReader(io.StringIO(export.get_data(as_text=True))))
    assert [r["answer"] for r in rows] == ["2", "3"]
    assert {r["page_type"] for r in rows} == {"intensity"}
    assert {r["condition"] for r in rows} <= {"SYSALPHA", "SYSBETA"}


def test_unknown_page_types_name_the_registered_kinds(tmp_path):
    from study_app.errors import StudyDefinitionError

    with pytest.raises(StudyDefinitionError, match="pages\\[0\\].type.*expected one of consent"):
        h.make_study(tmp_path, yaml_text=TOY_YAML, name="toy.yaml")
    assert "intensity" not in page_kinds()
