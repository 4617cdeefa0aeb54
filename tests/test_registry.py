"""evalsuite.registry.Registry: registration, lookups with "did you mean", lazy targets, and entry points read
from package metadata (a hand-written ``.dist-info`` on sys.path) and imported only when needed."""
from __future__ import annotations

import importlib
import sys
import textwrap
from dataclasses import dataclass

import pytest

from evalsuite.errors import InputError, PluginError, UnknownNameError
from evalsuite.registry import Registry

GROUP = "evalsuite_test.widgets"


@dataclass(frozen=True)
class Widget:
    name: str = "plain"


def widgets(**kw) -> Registry[Widget]:
    return Registry("widget", GROUP, base=Widget, name_of=lambda w: w.name, field="widget", **kw)


@pytest.fixture
def site(tmp_path, monkeypatch):
    """An installed distribution ``evs-widgets 1.2`` with five entry points in GROUP (one of them broken)."""
    root = tmp_path / "site"
    (root / "evs_widgets").mkdir(parents=True)
    (root / "evs_widgets" / "__init__.py").write_text("")
    (root / "evs_widgets" / "things.py").write_text(textwrap.dedent("""
        from test_registry import Widget

        GOOD = Widget("good")
        MISNAMED = Widget("other")
        NOT_A_WIDGET = 42
        TAKEN = Widget("taken")

        class Round(Widget):
            def __init__(self):
                super().__init__("round")
    """))
    (root / "evs_widgets" / "broken.py").write_text("raise RuntimeError('the plug-in is broken')\n")
    dist = root / "evs_widgets-1.2.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: evs-widgets\nVersion: 1.2\n")
    (dist / "entry_points.txt").write_text(textwrap.dedent(f"""
        [{GROUP}]
        good = evs_widgets.things:GOOD
        round = evs_widgets.things:Round
        misnamed = evs_widgets.things:MISNAMED
        number = evs_widgets.things:NOT_A_WIDGET
        broken = evs_widgets.broken:X
        taken = evs_widgets.things:TAKEN
    """))
    monkeypatch.syspath_prepend(str(root))
    importlib.invalidate_caches()
    yield root
    for name in [m for m in sys.modules if m.startswith("evs_widgets")]:
        del sys.modules[name]


def test_register_get_and_unknown_names_with_suggestions():
    reg = widgets()
    blue = reg.register("blue", Widget("blue"))
    reg.register("bluish", Widget("bluish"))
    assert reg.get("blue") is blue and reg["blue"] is blue
    assert list(reg) == ["blue", "bluish"] and len(reg) == 2 and "blue" in reg and "red" not in reg
    with pytest.raises(ValueError, match="a widget named 'blue' is registered already"):
        reg.register("blue", Widget("blue"))
    with pytest.raises(ValueError, match="a widget named 'red' cannot be registered as 'green'"):
        reg.register("green", Widget("red"))
    with pytest.raises(UnknownNameError, match=r"^widget: unknown widget 'blu'; known: blue, bluish. Did you mean "
                                               r"'blue' or 'bluish'\?$") as info:
        reg.get("blu")
    assert isinstance(info.value, InputError) and isinstance(info.value, KeyError)
    assert info.value.field == "widget"
    with pytest.raises(UnknownNameError, match=r"unknown widget 'zzz'; known: blue, bluish$"):
        reg["zzz"]
    reg.register("blue", Widget("blue"), replace=True)
    assert list(reg) == ["blue", "bluish"]                # replacing keeps the place
    reg.unregister("blue")
    assert reg.names() == ["bluish"] and reg.pop("nothing") is None


def test_a_check_refuses_a_registration():
    def no_vowel_start(name, item):
        if name[0] in "aeiou":
            raise ValueError(f"{name!r} starts with a vowel")

    reg = widgets(check=no_vowel_start)
    with pytest.raises(ValueError, match="'apple' starts with a vowel"):
        reg.register("apple", Widget("apple"))
    assert "apple" not in reg


def test_lazy_targets_are_imported_on_first_use(site):
    reg = widgets()
    reg.register_lazy("good", "evs_widgets.things:GOOD")
    assert reg.entry("good").loaded is False
    assert "evs_widgets.things" not in sys.modules
    assert reg.get("good") == Widget("good")
    assert reg.entry("good").loaded is True and reg.entry("good").origin == "builtin"


def test_entry_points_are_listed_without_import_and_loaded_on_lookup(site):
    reg = widgets()
    reg.register("taken", Widget("taken"))
    assert reg.names() == ["taken", "good", "round", "misnamed", "number", "broken"]
    assert "good" in reg and "evs_widgets.things" not in sys.modules          # metadata only
    entry = reg.entry("good")
    assert (entry.origin, entry.target, entry.distribution, entry.loaded) == \
        ("entry point", "evs_widgets.things:GOOD", "evs-widgets 1.2", False)
    assert reg.get("good") == Widget("good")
    round_ = reg.get("round")                                               # a subclass is instantiated
    assert (type(round_).__name__, round_.name) == ("Round", "round")
    assert reg.entry("good").loaded and reg.entry("taken").origin == "registered"   # a registered name wins
    with pytest.raises(UnknownNameError, match=r"unknown widget 'goood'; known: broken, good, .*Did you mean 'good'"):
        reg.get("goood")


def test_broken_plugins_raise_on_lookup_and_are_left_out_of_listings(site):
    reg = widgets()
    with pytest.raises(PluginError, match=r"widget: cannot load widget 'broken' from 'evs_widgets.broken:X' "
                                          r"\(entry point of evs-widgets 1.2\): RuntimeError: the plug-in is broken"):
        reg.get("broken")
    with pytest.raises(PluginError, match=r"'evs_widgets.things:NOT_A_WIDGET' .* gives an object of type int, not a Widget"):
        reg.get("number")
    with pytest.raises(PluginError, match=r"a widget named 'other' cannot be registered as 'misnamed'"):
        reg.get("misnamed")
    with pytest.warns(RuntimeWarning) as record:
        loaded = reg.loaded()
    assert sorted(str(w.message).split("'")[1] for w in record) == ["broken", "misnamed", "number"]
    assert all(" left out: " in str(w.message) for w in record)
    assert sorted(loaded) == ["good", "round", "taken"]
    with pytest.warns(RuntimeWarning):
        assert dict(reg.items()).keys() == loaded.keys()
    with pytest.raises(PluginError, match="the plug-in is broken"):   # the failure is remembered
        reg["broken"]


def test_refresh_reads_newly_installed_packages(tmp_path, monkeypatch):
    reg = widgets()
    assert reg.names() == []
    dist = tmp_path / "late-0.1.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: late\nVersion: 0.1\n")
    (dist / "entry_points.txt").write_text(f"[{GROUP}]\nlate = test_registry:Widget\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    importlib.invalidate_caches()
    assert reg.names() == []                       # read once
    reg.refresh()
    assert reg.names() == ["late"]


def test_the_extension_points_share_the_error():
    from evalsuite.corpus.readers import load_corpus
    from evalsuite.corpus.transcripts import read_transcript
    from evalsuite.features import get_recipe
    from evalsuite.generators import GeneratorError, find_generator
    from evalsuite.metrics.families import get_family
    from study_app.pages import get_kind

    cases = [(lambda: get_family("kinematic"), "metric family 'kinematic'", "'kinematics'"),
             (lambda: get_kind("likret"), "page kind 'likret'", "'likert'"),
             (lambda: find_generator("mismatch"), "generator 'mismatch'", "'mismatched'"),
             (lambda: load_corpus(".", layout="genea2021"), "layout 'genea2021'", "'genea2020'"),
             (lambda: read_transcript("a.txt", format="textgird"), "transcript format 'textgird'", "'textgrid'"),
             (lambda: get_recipe("mfcc_kucherenk"), "feature recipe 'mfcc_kucherenk'", "'mfcc_kucherenko'")]
    for call, unknown, suggestion in cases:
        with pytest.raises(UnknownNameError) as info:
            call()
        assert f"unknown {unknown}; known: " in str(info.value)
        assert suggestion in str(info.value).split("Did you mean ")[1]
    with pytest.raises(GeneratorError):
        find_generator("mismatch")
