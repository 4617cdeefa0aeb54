"""evalsuite.registry end to end: one throwaway package, built and installed with pip (``--target`` a folder
in tmp, put on ``sys.path``: the shared test environment is never changed), adds one of each extension point
through entry points only — a metric family, a study page kind, a generator, a corpus layout, a transcript
format and a feature recipe — and each is used through evalsuite's own commands and functions."""
from __future__ import annotations

import csv
import importlib
import io
import json
import subprocess
import sys
import textwrap

import numpy as np
import pandas as pd
import pytest
import study_helpers as h
from click.testing import CliRunner
from corpus_helpers import WORDS, bvh, wav

from evalsuite.cli import main
from evalsuite.corpus.readers import LAYOUTS, load_corpus
from evalsuite.corpus.transcripts import FORMATS, read_transcript, transcript_suffixes, write_transcript
from evalsuite.errors import UnknownNameError
from evalsuite.features import get_recipe
from evalsuite.features.base import RECIPES
from evalsuite.generators.registry import GENERATORS, list_generators
from evalsuite.metrics.families import FAMILIES
from evalsuite.motion.io import load_motion
from study_app import create_app
from study_app.pages import KINDS

DIST = "evs-allplug 0.3"

FILES = {
    "pyproject.toml": """
        [build-system]
        requires = ["setuptools>=61"]
        build-backend = "setuptools.build_meta"

        [project]
        name = "evs-allplug"
        version = "0.3"

        [project.entry-points."evalsuite.metric_families"]
        frame_count = "evs_allplug.metrics:FrameCountFamily"

        [project.entry-points."evalsuite.page_kinds"]
        stars = "evs_allplug.pages:StarsKind"

        [project.entry-points."evalsuite.generators"]
        hop = "evs_allplug.generator:Hop"

        [project.entry-points."evalsuite.corpus_layouts"]
        takes_list = "evs_allplug.layout:read_takes_list"

        [project.entry-points."evalsuite.transcript_formats"]
        srt = "evs_allplug.srt:SRT"

        [project.entry-points."evalsuite.feature_recipes"]
        word_onsets = "evs_allplug.recipe:WORD_ONSETS"

        [tool.setuptools]
        packages = ["evs_allplug"]

        [tool.setuptools.package-data]
        evs_allplug = ["templates/pages/*.html"]
    """,
    "evs_allplug/__init__.py": "",
    "evs_allplug/metrics.py": """
        from evalsuite.metrics.families import MetricFamily, MetricInfo


        class FrameCountFamily(MetricFamily):
            name = "frame_count"
            metrics = (MetricInfo("frame_count", "frames", "closer to natural", description="frames per file"),)
            default = False

            def measure(self, ctx):
                ctx.record["frame_count"] = float(ctx.pos.shape[0])

            def reduce(self, ctx):
                ctx.mean_metric("frame_count", [ctx.recs[s]["frame_count"] for s in ctx.names])
    """,
    "evs_allplug/pages.py": """
        import pathlib

        from study_app.pages import BlockKind, Media
        from study_app.pages.base import export_condition, segment_for
        from study_app.payload import int_in, only_keys


        class StarsKind(BlockKind):
            name = "stars"
            keys = BlockKind.keys + ("question",)
            template_folder = str(pathlib.Path(__file__).parent / "templates")

            def min_conditions(self, page):
                return 1

            def load_options(self, chk, page, where, cfg, known):
                cfg["question"] = chk.get(page, "question", where, str, required=True)

            def attention_fits(self, stim, cfg):
                return False

            def regular_page(self, block, g, lookup, segments):
                cond = block.cfg["conditions"][g % len(block.cfg["conditions"])]
                seg = segment_for(g, len(block.cfg["conditions"]), segments)
                return {"type": self.name, "segment": seg, "stimulus": lookup.file(cond, seg)}

            def check_page(self, block, k, pool, lookup):
                return {}

            def n_slots(self, spec):
                return 1

            def media(self, study, spec, slot):
                return Media(file=spec["stimulus"])

            def parse_answer(self, study, spec, answer, fields):
                only_keys(answer, ("stars",), "answer")
                return {"stars": int_in(answer.get("stars"), 1, 5, "answer.stars")}

            def export_rows(self, study, spec, answer, base):
                stim = study.manifest.by_file()[spec["stimulus"]]
                return [{**base, "question": "stars", "condition": export_condition(stim),
                         "answer": answer.data["stars"]}]
    """,
    "evs_allplug/templates/pages/stars.html": """
        <p class="stars-question">{{ page.question }}</p>
        {% for k in range(1, 6) %}<input type="radio" name="stars" value="{{ k }}">{% endfor %}
    """,
    "evs_allplug/generator.py": """
        import numpy as np

        from evalsuite.audio import read_wav, to_mono
        from evalsuite.generators import GenerationResult, Generator, GeneratorSpec
        from evalsuite.motion import Motion

        JOINTS = ("Hips", "Head", "RightHand", "LeftHand")


        class Hop(Generator):
            spec = GeneratorSpec(name="hop", version="0.3", summary="hands hop with the loudness", kind="plug-in",
                                 audio="required", output="positions", joints=JOINTS, native_fps=25.0, units="m")

            def generate(self, request):
                x, rate = read_wav(request.audio)
                n = int(round(request.duration * 25.0))
                env = np.interp(np.arange(n) / 25.0, np.arange(len(x)) / rate, np.abs(to_mono(x)))
                pos = np.zeros((n, 4, 3))
                pos[:, 1, 1] = 1.6
                pos[:, 2:, 1] = 1.0 + env[:, None]
                return GenerationResult(Motion.from_positions(pos, JOINTS, 25.0))
    """,
    "evs_allplug/layout.py": """
        from evalsuite.corpus.readers import register_layout


        @register_layout("takes_list", detect=lambda root: (root / "takes.lst").is_file(),
                         description="takes.lst names the takes; <take>.wav, .bvh and .srt beside it")
        def read_takes_list(root, builder):
            for take in (root / "takes.lst").read_text().split():
                builder.add(take, audio=root / f"{take}.wav", motion=root / f"{take}.bvh",
                            transcript=root / f"{take}.srt", split="train")
    """,
    "evs_allplug/srt.py": """
        import pathlib
        import re

        from evalsuite.corpus.transcripts import TranscriptFormat
        from evalsuite.corpus.types import Transcript, Word
        from evalsuite.errors import InputError

        TIME = re.compile(r"(\\d+):(\\d\\d):(\\d\\d),(\\d{3})")


        def _seconds(text, path, line):
            m = TIME.fullmatch(text.strip())
            if m is None:
                raise InputError(f"expected HH:MM:SS,mmm, got {text.strip()!r}", path=path, line=line)
            h, mi, s, ms = map(int, m.groups())
            return h * 3600 + mi * 60 + s + ms / 1000


        def read_srt(path, **options):
            lines = pathlib.Path(path).read_text(encoding="utf-8").splitlines()
            words = [Word(lines[i + 1].strip(), *(_seconds(t, path, i + 1) for t in line.split("-->")))
                     for i, line in enumerate(lines) if "-->" in line]
            return Transcript(tuple(words), source=str(path))


        def _stamp(t):
            ms = int(round(t * 1000))
            return f"{ms // 3600000:02d}:{ms // 60000 % 60:02d}:{ms // 1000 % 60:02d},{ms % 1000:03d}"


        def write_srt(transcript, path, **options):
            cues = [f"{k}\\n{_stamp(w.start)} --> {_stamp(w.end)}\\n{w.text}\\n"
                    for k, w in enumerate(transcript.words, 1)]
            pathlib.Path(path).write_text("\\n".join(cues), encoding="utf-8")


        SRT = TranscriptFormat("srt", (".srt",), read_srt, write_srt, aliases=("subrip",),
                               description="SubRip subtitles, one word per cue")
    """,
    "evs_allplug/recipe.py": """
        import numpy as np

        from evalsuite.features import Recipe


        def onsets(audio, transcript, fps, n_frames, opts):
            n = n_frames if n_frames is not None else int(np.ceil(transcript.words[-1].end * fps))
            out = np.zeros((n, 1))
            for w in transcript.words:
                if int(w.start * fps + 1e-9) < n:
                    out[int(w.start * fps + 1e-9), 0] = 1.0
            return out


        WORD_ONSETS = Recipe(name="word_onsets", native_fps=None, dim=1, reproduces="1 on the frame a word starts",
                             quirks="none", compute=onsets, needs_audio=False, needs_transcript=True,
                             default_fps=10.0)
    """,
}
NAMES = {FAMILIES: "frame_count", KINDS: "stars", GENERATORS: "hop", LAYOUTS: "takes_list", FORMATS: "srt",
         RECIPES: "word_onsets"}


@pytest.fixture(scope="module")
def plugin(tmp_path_factory):
    """Build and install the package into a folder with pip (offline: no index, no build isolation), put that
    folder on sys.path for this module's tests, and take it all away afterwards."""
    root = tmp_path_factory.mktemp("allplug")
    for rel, text in FILES.items():
        (root / "src" / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / "src" / rel).write_text(textwrap.dedent(text).lstrip())
    subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "--no-build-isolation", "--no-index",
                    "--disable-pip-version-check", "--quiet", "--target", str(root / "site"), str(root / "src")],
                   check=True, capture_output=True, timeout=120)
    sys.path.insert(0, str(root / "site"))
    importlib.invalidate_caches()
    for registry in NAMES:
        registry.refresh()
    yield root
    sys.path.remove(str(root / "site"))
    for registry, name in NAMES.items():
        registry.unregister(name)
        registry.refresh()
    for module in [m for m in sys.modules if m == "evs_allplug" or m.startswith("evs_allplug.")]:
        del sys.modules[module]


def test_every_extension_point_sees_the_installed_package(plugin):
    for registry, name in NAMES.items():
        assert name in registry, registry.what
        entry = registry.entry(name)
        assert (entry.origin, entry.distribution) == ("entry point", DIST)
    hop = [g for g in list_generators() if g.name == "hop"][0]
    assert (hop.origin, hop.distribution, hop.target) == ("entry point", DIST, "evs_allplug.generator:Hop")
    with pytest.raises(UnknownNameError, match=r"unknown feature recipe 'word_onset'; known: .*Did you mean "
                                               r"'word_onsets'\?"):
        get_recipe("word_onset")


def test_the_metric_family_scores_a_folder(plugin, tmp_path):
    for k, seconds in enumerate((1.0, 2.0)):
        bvh(tmp_path / "natural" / f"seq{k}.bvh", seconds, seed=k)
        bvh(tmp_path / "sys" / f"seq{k}.bvh", seconds, seed=k + 5)
    res = CliRunner().invoke(main, ["score", "-r", str(tmp_path / "natural"), str(tmp_path / "sys"), "-m",
                                    "frame_count", "--no-figures", "--quiet", "-o", str(tmp_path / "out")])
    assert res.exit_code == 0, res.output
    summary = pd.read_csv(tmp_path / "out" / "summary.csv")
    assert set(summary.metric) == {"frame_count"}
    assert (summary.value == 45.0).all() and (summary.unit == "frames").all()   # (30 + 60) / 2 frames


STUDY = """\
id: stars-study
stimuli: stim/manifest.csv
platform: prolific
sessions: 2
completion_code: DONE1234
pages:
  - type: stars
    id: rate
    conditions: [SYSALPHA, SYSBETA]
    pages: 2
    question: How lively is the motion?
  - type: finish
    id: finish
    text: Thanks.
"""


def test_the_page_kind_is_served_and_answered(plugin, tmp_path):
    study = h.make_study(tmp_path, yaml_text=STUDY, name="stars.yaml")
    app = create_app({"STUDY": str(study), "DATABASE_URL": f"sqlite:///{tmp_path / 's.db'}", "SECRET_KEY": h.SECRET,
                      "ADMIN_TOKEN": h.ADMIN, "SESSION_COOKIE_SECURE": False, "INSTANCE_PATH": str(tmp_path / "i")})
    p = h.Participant(app.test_client(), "5f3a1c9e8b7d6a5f4e3d2c1b", study_id="stars-study")
    assert p.enter().status_code == 302
    for stars in (4, 5):
        r, data, csrf = p.page()
        assert data["type"] == "stars"
        assert "How lively is the motion?" in r.get_data(as_text=True)   # the package's own template
        assert p.submit(data, csrf, {"stars": 9}).status_code == 422
        assert p.submit(data, csrf, {"stars": stars}).status_code == 200
    export = app.test_client().get("/admin/export/results.csv", headers={"Authorization": f"Bearer {h.ADMIN}"})
    rows = list(csv.DictReader(io.StringIO(export.get_data(as_text=True))))
    assert [(r["page_type"], r["answer"]) for r in rows] == [("stars", "4"), ("stars", "5")]


def test_the_generator_generates_through_the_command(plugin, tmp_path):
    speech = wav(tmp_path / "hello.wav", 2.0)
    res = CliRunner().invoke(main, ["generate", "-g", "hop", "--audio", str(speech), "--fps", "30",
                                    "-o", str(tmp_path / "out")])
    assert res.exit_code == 0, res.output
    motion = load_motion(tmp_path / "out" / "hello.npz")
    assert (motion.fps, motion.n_frames) == (30.0, 60)
    record = json.loads((tmp_path / "out" / "generation.json").read_text())
    assert (record["origin"], record["distribution"]) == ("entry point", DIST)


def test_the_layout_reads_a_corpus_with_transcripts_in_the_new_format(plugin, tmp_path):
    root = tmp_path / "corpus"
    (root / "takes.lst").parent.mkdir()
    (root / "takes.lst").write_text("take1\ntake2\n")
    for take in ("take1", "take2"):
        wav(root / f"{take}.wav", 2.0)
        bvh(root / f"{take}.bvh", 2.0)
        write_transcript(WORDS, root / f"{take}.srt")            # the package's writer, chosen by suffix
    assert ".srt" in transcript_suffixes()
    assert "-->" in (root / "take1.srt").read_text()
    corpus = load_corpus(root)                                    # the package's layout, detected
    assert corpus.layout == "takes_list"
    assert [s.id for s in corpus.segments] == ["take1", "take2"]
    words = corpus.segments[0].transcript
    assert [(w.text, w.start, w.end) for w in words.words] == [(w.text, w.start, w.end) for w in WORDS.words]
    assert read_transcript(root / "take2.srt", format="subrip").words == words.words


def test_the_recipe_runs_through_the_command_on_a_transcript_in_the_new_format(plugin, tmp_path):
    write_transcript(WORDS, tmp_path / "speech.srt")
    out = tmp_path / "onsets.npy"
    res = CliRunner().invoke(main, ["features", "-r", "word_onsets", "-t", str(tmp_path / "speech.srt"),
                                    "--fps", "10", "--n-frames", "20", "--no-cache", "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert np.flatnonzero(np.load(out)[:, 0]).tolist() == [2, 6, 12]     # words start at 0.2, 0.6 and 1.2 s
    listing = CliRunner().invoke(main, ["features", "--list"])
    assert "word_onsets" in listing.output
