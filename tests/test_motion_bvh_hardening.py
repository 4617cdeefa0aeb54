"""BVH input that used to escape as another exception, be read silently although invalid, be refused
although valid, or take very long (issue 11's fuzzing classes): each now gives one BVHError with the place,
or is read correctly."""
from __future__ import annotations

import time

import numpy as np
import pytest

import evalsuite
from evalsuite.errors import BVHError
from evalsuite.motion.bvh import parse_bvh
from evalsuite.motion.motion import _clean_fps

GOOD = """HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Spine
  {
    OFFSET 0 10 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 0 5 0
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.03333
0 1 2 3 4 5 6 7 8
1 2 3 4 5 6 7 8 9
"""


def with_frame_line(line: str) -> str:
    lines = GOOD.splitlines()
    return "\n".join(lines[:-1] + [line]) + "\n"


def test_a_utf8_byte_order_mark_is_accepted():
    skeleton, values, _ = parse_bvh(b"\xef\xbb\xbf" + GOOD.encode())
    assert skeleton.names == ["Hips", "Spine"]
    assert values.shape == (2, 9)


@pytest.mark.parametrize("token", ["nan", "True", "1_0", '"1.0"', "\u0661\u0662", "0x10", "1e", "--1", "1.2.3"])
def test_frame_values_are_plain_decimal_or_exponent_notation(token):
    with pytest.raises(BVHError) as err:
        parse_bvh(with_frame_line(f"1 2 3 4 5 6 7 8 {token}"), "t.bvh")
    message = str(err.value)
    assert "t.bvh:20" in message
    assert repr(token) in message
    assert "column 17" in message
    assert "channel 'Spine Yrotation'" in message


@pytest.mark.parametrize("token", ["+1.5", "-0", ".5", "5.", "1e-3", "1E+3"])
def test_the_spellings_bvh_writers_use_are_read(token):
    _, values, _ = parse_bvh(with_frame_line(f"1 2 3 4 5 6 7 8 {token}"))
    assert values[1, 8] == float(token)


@pytest.mark.parametrize("field, bad", [("Frames:", "Frames: \u00b3"), ("CHANNELS", "CHANNELS \u00b3 Zrotation Xrotation Yrotation"),
                                        ("OFFSET", "OFFSET 0 1_0 0")])
def test_non_ascii_digits_and_underscores_in_the_header_are_refused(field, bad):
    text = GOOD.replace("Frames: 2", bad) if field == "Frames:" else (
        GOOD.replace("CHANNELS 3 Zrotation Xrotation Yrotation", bad) if field == "CHANNELS" else
        GOOD.replace("OFFSET 0 10 0", bad))
    with pytest.raises(BVHError, match="expected a (whole|number)"):
        parse_bvh(text, "h.bvh")


@pytest.mark.parametrize("frame_time", ["1e-320", "0", "-0.1", "inf", "1e-9"])
def test_frame_times_no_file_has_are_refused(frame_time):
    with pytest.raises(BVHError, match="expected a positive frame time"):
        parse_bvh(GOOD.replace("Frame Time: 0.03333", f"Frame Time: {frame_time}"), "f.bvh")


def test_a_huge_declared_frame_count_is_checked_against_the_data_before_allocating():
    start = time.perf_counter()
    with pytest.raises(BVHError, match="'Frames: 1000000000' but the file has only 2 lines"):
        parse_bvh(GOOD.replace("Frames: 2", "Frames: 1000000000"), "big.bvh")
    assert time.perf_counter() - start < 1.0


def test_a_deeply_nested_hierarchy_fails_fast_with_the_limit():
    depth = 1000
    text = "HIERARCHY\nROOT j0\n{\n OFFSET 0 0 0\n CHANNELS 0\n"
    for i in range(1, depth):
        text += f"JOINT j{i}\n{{\nOFFSET 0 1 0\nCHANNELS 0\n"
    text += "}\n" * depth + "MOTION\nFrames: 0\nFrame Time: 0.0333333\n"
    with pytest.raises(BVHError, match="nested 257 levels deep.*limit 256"):
        parse_bvh(text, "deep.bvh")


def test_a_hierarchy_with_100000_joints_fails_fast():
    body = "".join(f"JOINT j{i}\n{{\nOFFSET 0 0 0\nCHANNELS 0\n}}\n" for i in range(100_000))
    text = "HIERARCHY\nROOT r\n{\nOFFSET 0 0 0\nCHANNELS 0\n" + body + "}\nMOTION\nFrames: 0\nFrame Time: 0.1\n"
    start = time.perf_counter()
    with pytest.raises(BVHError, match="more than 10,000 joints"):
        parse_bvh(text, "many.bvh")
    assert time.perf_counter() - start < 5.0


def test_a_ten_million_character_line_fails_fast():
    start = time.perf_counter()
    with pytest.raises(BVHError, match="line of 10,000,000 characters"):
        parse_bvh(with_frame_line("1" * 10_000_000), "long.bvh")
    assert time.perf_counter() - start < 2.0


@pytest.mark.parametrize("printed, fps", [(0.03333, 30.0), (0.0333333, 30.0), (0.0416667, 24.0), (0.008333, 120.0),
                                          (0.04, 25.0), (0.1, 10.0)])
def test_frame_times_written_rounded_give_the_whole_rate(printed, fps):
    assert _clean_fps(printed) == fps


def test_genea_style_frame_time_is_30_fps_when_loaded(tmp_path):
    path = tmp_path / "genea.bvh"
    path.write_text(GOOD)
    motion = evalsuite.load_motion(path)
    assert motion.fps == 30.0
    assert np.isclose(motion.duration, 2 / 30)


from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

_PIECES = ["nan", "True", "1_0", '"', "\u00b3", "\u0661", "{", "}", "JOINT", "End Site", "CHANNELS 3", "OFFSET",
           "\n", " ", "\t", "-", ".", "e", "0", "9", "\x00", "\ufeff", "Frames: 3", "Frame Time: 0", "MOTION", "ROOT"]


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(st.integers(0, len(GOOD)), st.integers(0, 8), st.sampled_from(_PIECES)), max_size=4))
def test_mutated_files_raise_only_bvh_errors(edits):
    """Random splices of BVH-ish pieces: the reader either reads the file or raises BVHError (never another
    exception type, never a value that is not finite)."""
    text = GOOD
    for pos, cut, piece in edits:
        pos = min(pos, len(text))
        text = text[:pos] + piece + text[pos + cut:]
    try:
        skeleton, values, frame_time = parse_bvh(text.encode("utf-8", errors="replace"), "fuzz.bvh")
    except BVHError as exc:
        assert str(exc).startswith("fuzz.bvh")
        return
    assert np.isfinite(values).all()
    assert frame_time > 0
    assert values.shape == (values.shape[0], skeleton.n_channels)


@pytest.mark.parametrize("good, bad, line, expected", [
    ("OFFSET 0 10 0", "OFFSTE 0 10 0", 8, "'OFFSET'"),
    ("CHANNELS 3 Z", "CHANNLES 3 Z", 9, "'CHANNELS'"),
    ("JOINT Spine", "JOIN Spine", 6, "'JOINT'"),
    ("End Site", "EndSite", 10, "'End Site'"),
    ("End Site", "End Sit", 10, "expected 'Site', found 'Sit'"),
    ("ROOT Hips", "ROOTT Hips", 2, "'ROOT'"),
    ("MOTION", "MOTOIN", 16, "'MOTION'"),
])
def test_a_misspelt_keyword_is_refused_with_its_line_and_the_keyword_meant(good, bad, line, expected):
    with pytest.raises(BVHError) as info:
        parse_bvh(GOOD.replace(good, bad), "typo.bvh")
    assert info.value.line == line, str(info.value)
    assert expected in str(info.value)


def test_blank_lines_before_motion_are_read_and_other_tokens_refused():
    _, values, _ = parse_bvh(GOOD.replace("}\nMOTION", "}\n\n  \t\nMOTION"), "blank.bvh")
    assert values.shape == (2, 9)
    with pytest.raises(BVHError, match=r"trail.bvh:16: expected MOTION or another ROOT after the hierarchy, found '}'"):
        parse_bvh(GOOD.replace("}\nMOTION", "}\n}\nMOTION"), "trail.bvh")


def test_a_file_without_frames_is_refused():
    text = GOOD.replace("Frames: 2", "Frames: 0").replace("0 1 2 3 4 5 6 7 8\n1 2 3 4 5 6 7 8 9\n", "")
    with pytest.raises(BVHError, match=r"none.bvh:17: Frames: expected at least 1 frame"):
        parse_bvh(text, "none.bvh")
