"""Body styles (renderers.styles): the settings name one, every render path asks it for the mesh, a plug-in
style registered at run time is drawn like a built-in."""
from __future__ import annotations

import imageio.v3 as iio
import numpy as np
import pytest
import yaml
from click.testing import CliRunner
from render_helpers import ffmpeg_stream_info, waving_motion
from test_render_stimuli import make_project

from evalsuite.cli import main
from evalsuite.errors import InputError
from evalsuite.motion.io import save_motion
from renderers.figure import FigureMesh
from renderers.render import _meshes, render_frames, view_for
from renderers.scene import RenderSettings
from renderers.stimuli import build_stimuli, load_config, plan
from renderers.styles import STYLES, BodyStyle


def test_body_setting_is_checked_against_the_registry_with_a_hint():
    assert RenderSettings().body == "stick" and RenderSettings().character is None
    with pytest.raises(InputError) as exc:
        RenderSettings(body="stik")
    assert exc.value.field == "body" and "'stick'" in str(exc.value) and "Did you mean" in str(exc.value)
    with pytest.raises(InputError, match="character"):
        RenderSettings(character=3)   # type: ignore[arg-type]


def test_body_and_character_round_trip_through_the_settings_dict():
    s = RenderSettings(body="stick", character="hero.glb")
    d = s.to_dict()
    assert d["body"] == "stick" and d["character"] == "hero.glb"
    assert RenderSettings.from_dict(d) == s


class _Box:
    """A test style's mesh: one cube around the root joint."""

    def __init__(self, size):
        self.h = 0.2 * size
        c = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
        self._c = c
        self.faces = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                               [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]], np.uint32)
        self.colors = np.full((8, 3), 0.8, np.float32)

    def vertices(self, positions):
        v = positions[:, :1] + self.h * self._c[None]
        n = np.broadcast_to(self._c / np.sqrt(3), v.shape)
        return v.astype(np.float32), n.astype(np.float32)


class _BoxStyle(BodyStyle):
    name = "test-box"
    description = "a cube at the root"

    def mesh(self, motion, settings, size):
        return _Box(size)


def test_every_render_path_goes_through_the_named_style():
    STYLES.register("test-box", _BoxStyle())
    try:
        m = waving_motion(0.2)
        stick = RenderSettings(width=96, height=72)
        box = RenderSettings(width=96, height=72, body="test-box")
        assert isinstance(_meshes([m], stick, view_for([m], stick))[0], FigureMesh)
        assert isinstance(_meshes([m], box, view_for([m], box))[0], _Box)
        a, b = render_frames([m], stick)[0], render_frames([m], box, view=view_for([m], stick))[0]
        assert (a < 200).any() and (b < 200).any() and not np.array_equal(a, b)
    finally:
        STYLES.unregister("test-box")


def test_render_cli_style_framing_face_and_floor_options(tmp_path):
    motion = tmp_path / "m.npz"
    save_motion(waving_motion(0.3), motion)
    runner = CliRunner()
    images = {}
    for args in (["--style", "mannequin"], ["--style", "mannequin", "--face", "blank"],
                 ["--style", "mannequin", "--no-floor"], ["--style", "mannequin", "--framing", "above-knees"],
                 []):
        out = tmp_path / f"{len(images)}.png"
        res = runner.invoke(main, ["render", "still", str(motion), "-o", str(out), "--width", "128", "--height", "96",
                                   *args])
        assert res.exit_code == 0, res.output
        images[" ".join(args)] = iio.imread(out)
    mannequin, blank = images["--style mannequin"], images["--style mannequin --face blank"]
    assert not np.array_equal(mannequin, blank), "the face option changes the head"
    darkest = [int(img.astype(int).sum(axis=2).min()) for img in (mannequin, blank)]
    assert darkest[0] < darkest[1] - 60, f"the visor is dark; a face mask is not ({darkest})"
    assert tuple(mannequin[-1, 0]) != (255, 255, 255), "the mannequin stands on a floor by default"
    assert tuple(images["--style mannequin --no-floor"][-1, 0]) == (255, 255, 255)
    assert tuple(images[""][-1, 0]) == (255, 255, 255), "the stick figure has no floor by default"
    res = runner.invoke(main, ["render", "still", str(motion), "-o", str(tmp_path / "x.png"), "--style", "manequin"])
    assert res.exit_code == 2 and "mannequin" in res.output and "Traceback" not in res.output
    help_text = runner.invoke(main, ["render", "compare", "--help"]).output
    for option in ("--style", "--character", "--face", "above-knees"):
        assert option in help_text


def test_conditions_are_drawn_in_the_same_colours(tmp_path):
    """Blinding: two conditions with the same motion look the same in a comparison (no per-condition colour)."""
    m = waving_motion(0.2)
    for body in ("stick", "mannequin"):
        settings = RenderSettings(width=96, height=72, body=body)
        img = render_frames([m, m], settings, captions=None)[0]
        np.testing.assert_array_equal(img[:, :96], img[:, -96:])


def test_stimuli_config_takes_the_style_face_framing_and_mute(tmp_path):
    config = make_project(tmp_path, segments=("seg01",), seconds=0.4, checks=False)
    cfg = yaml.safe_load(config.read_text())
    cfg["render"].update({"style": "mannequin", "face": "blank", "framing": "above-knees"})
    cfg["mute"] = True
    config.write_text(yaml.safe_dump(cfg))
    settings = load_config(config)["settings"]
    assert (settings.body, settings.face, settings.framing) == ("mannequin", "blank", "above-knees")
    result = build_stimuli(config, echo=lambda *a: None)
    for row in result["rows"]:
        info = ffmpeg_stream_info(tmp_path / "out" / row["file"])
        assert "Video:" in info and "Audio:" not in info, "muted: no sound even though the segment has audio"
    sound = build_stimuli(config, echo=lambda *a: None, mute=False)
    assert sound["rendered"] == 2 and "Audio:" in ffmpeg_stream_info(tmp_path / "out" / sound["rows"][0]["file"])
    cfg["attention_checks"] = [{"check": "distorted_audio", "segment": "seg01", "condition": "natural"}]
    config.write_text(yaml.safe_dump(cfg))
    with pytest.raises(InputError, match="muted"):
        plan(load_config(config))
    cfg.pop("attention_checks")
    cfg["render"]["character"] = "hero.glb"
    config.write_text(yaml.safe_dump(cfg))
    loaded = load_config(config)
    assert loaded["settings"].character == str(tmp_path / "hero.glb"), "relative to the config file"
    with pytest.raises(InputError, match="character file not found"):
        plan(loaded)
    cfg["render"]["body"] = "stick"
    config.write_text(yaml.safe_dump(cfg))
    with pytest.raises(InputError, match="disagree"):
        load_config(config)
