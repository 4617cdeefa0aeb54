"""BVH reading, writing and forward kinematics against external data and a slow reference."""
from __future__ import annotations

import pathlib
import re

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

import evalsuite
from evalsuite.errors import BVHError
from evalsuite.motion.bvh import format_bvh, parse_bvh
from evalsuite.motion.fk import forward_kinematics
from evalsuite.motion.skeleton import Skeleton

# The real fixtures (MIT, see ATTRIBUTION.md): the BVH files ship in the package as samples,
# the external oracle CSV lives in tests/data.
SAMPLES = pathlib.Path(evalsuite.__file__).resolve().parent / "data" / "samples"
ORACLE_CSV = pathlib.Path(__file__).parent / "data" / "walk01_pos.csv"


def fixture(name: str) -> pathlib.Path:
    return SAMPLES / name


# --- the external oracle -------------------------------------------------------------------

def test_walk01_matches_bvhtoolbox_world_positions():
    """Every joint and End Site of every frame within 1e-4 of bvh-toolbox's positions."""
    csv = ORACLE_CSV
    motion = evalsuite.load_motion(fixture("walk01.bvh"))
    positions = motion.positions(end_sites=True)
    names = motion.position_names(end_sites=True)
    ref = pd.read_csv(csv, skipinitialspace=True)
    ref.columns = [c.strip() for c in ref.columns]
    assert len(names) == (len(ref.columns) - 1) // 3 == 24
    expected = np.stack([ref[[f"{n}.x", f"{n}.y", f"{n}.z"]].to_numpy() for n in names], axis=1)
    assert positions.shape == expected.shape == (101, 24, 3)
    assert np.abs(positions - expected).max() <= 1e-4
    np.testing.assert_allclose(ref["time"].to_numpy(), np.arange(101) / motion.fps, atol=1e-5)


def test_root_offset_convention_is_an_option():
    """walk01's root OFFSET equals its frame-0 position: 'add' double counts it."""
    ignore = evalsuite.load_motion(fixture("walk01.bvh"))
    add = evalsuite.load_motion(fixture("walk01.bvh"), root_offset="add")
    shift = add.positions() - ignore.positions()
    np.testing.assert_allclose(shift, np.broadcast_to(ignore.skeleton.offsets[0], shift.shape), atol=1e-9)


@pytest.mark.parametrize("name,joints,frames,fps", [
    ("walk01.bvh", 19, 101, 24.0), ("mocapbank.bvh", 19, 455, 30.0), ("bvhio_example.bvh", 18, 2, 30.0)])
def test_fixtures_parse(name, joints, frames, fps):
    motion = evalsuite.load_motion(fixture(name))
    assert (motion.n_joints, motion.n_frames, motion.fps) == (joints, frames, fps)
    assert motion.positions().shape == (frames, joints, 3)
    assert np.isfinite(motion.positions()).all()


@pytest.mark.parametrize("name", ["walk01.bvh", "mocapbank.bvh", "bvhio_example.bvh"])
def test_round_trip_keeps_channels_names_order_and_end_sites(name, tmp_path):
    first = evalsuite.load_motion(fixture(name))
    out = tmp_path / name
    evalsuite.save_motion(first, out)
    second = evalsuite.load_motion(out)
    assert second.skeleton == first.skeleton
    assert second.skeleton.channels == first.skeleton.channels
    assert second.skeleton.end_site_names == first.skeleton.end_site_names
    assert np.abs(second.values - first.values).max() <= 1e-6
    assert second.fps == first.fps
    np.testing.assert_allclose(second.positions(end_sites=True), first.positions(end_sites=True), atol=1e-4)


# --- tokenizer robustness ------------------------------------------------------------------

ODD_BVH = (
    "HIERARCHY\r\n"
    "ROOT\tmixamorig:Hips\r\n{\r\n\tOFFSET\t+1.5 1e-3 -0\r\n"
    "\tCHANNELS 6 Xposition Yposition Zposition Yrotation Xrotation Zrotation   \r\n"
    "\tJOINT L-Arm.001\r\n\t{\r\n\t\tOFFSET 10 0 0\r\n"
    "\t\tCHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\r\n"
    "\t\tEnd Site\r\n\t\t{\r\n\t\t\tOFFSET 5 0 0\r\n\t\t}\r\n\t}\r\n}\r\n"
    "MOTION\r\nFrames:\t2\r\nFrame Time: .0333333\r\n"
    "0 0 0 90 0 0 +1.5 0 0 0 0 0\r\n"
    "1e1\t2 3 0 0 0   0 0 0 90 -0 0 \r\n"
)


def test_odd_but_valid_syntax():
    skeleton, values, frame_time = parse_bvh(ODD_BVH, "odd.bvh")
    assert skeleton.names == ["mixamorig:Hips", "L-Arm.001"]
    assert skeleton.channels[0] == ("Xposition", "Yposition", "Zposition", "Yrotation", "Xrotation", "Zrotation")
    np.testing.assert_allclose(skeleton.offsets[0], [1.5, 1e-3, 0.0])
    assert values.shape == (2, 12)
    assert values[1, 0] == 10.0
    assert values[0, 6] == 1.5
    assert abs(frame_time - 0.0333333) < 1e-12


def test_non_root_position_channels_conventions(tmp_path):
    path = tmp_path / "odd.bvh"
    path.write_text(ODD_BVH)
    replace = evalsuite.load_motion(path)
    pymo = evalsuite.load_motion(path, convention="pymo")
    ignore = evalsuite.load_motion(path, convention="pymotion")
    # Frame 0: root rotated 90 degrees about Y; the child's channels (1.5, 0, 0) are its translation.
    ry = Rotation.from_euler("Y", 90, degrees=True).as_matrix()
    np.testing.assert_allclose(replace.positions()[0, 1], ry @ [1.5, 0, 0], atol=1e-9)
    np.testing.assert_allclose(pymo.positions()[0, 1], ry @ [11.5, 0, 0], atol=1e-9)
    np.testing.assert_allclose(ignore.positions()[0, 1], ry @ [10.0, 0, 0], atol=1e-9)
    assert replace.fps == 30.0


# --- bad input: one clear error type -------------------------------------------------------

GOOD = fixture("bvhio_example.bvh").read_text()


def _frames_part(text):
    head, _, tail = text.partition("MOTION")
    return head, tail


def _bad_cases():
    assert re.search(r"Frames:\s*2", GOOD)
    head, tail = _frames_part(GOOD)
    lines = GOOD.splitlines()
    n = len(lines)
    return {
        "empty": ("", "empty"),
        "whitespace only": ("  \n\t\n", "empty"),
        "binary garbage": (bytes(range(256)) * 4, "binary"),
        "random bytes without NUL": (bytes(b % 255 + 1 for b in range(900)), "HIERARCHY"),
        "truncated hierarchy": (GOOD[: GOOD.index("JOINT") + 40], "end of the hierarchy"),
        "truncated frames": ("\n".join(lines[:-1]) + "\n", "truncated"),
        "too many frames": (GOOD + lines[-1] + "\n", "more frame lines"),
        "wrong value count": ("\n".join(lines[:-1] + [lines[-1] + " 1.0"]) + "\n", "values; expected"),
        "frames header wrong": (re.sub(r"Frames:\s*2", "Frames: 5", GOOD), "truncated"),
        "frames not a number": (re.sub(r"Frames:\s*2", "Frames: two", GOOD), "whole number of frames"),
        "bad frame time": (GOOD.replace("Frame Time:", "Frame Time: -1 #"), "frame time"),
        "missing frame time": (GOOD.replace("Frame Time", "Frame Rate"), "Frame Time"),
        "unknown channel": (GOOD.replace("Xrotation", "Wrotation", 1), "unknown channel 'Wrotation'"),
        "duplicate joint": (GOOD.replace("JOINT LeftCollar", "JOINT Neck", 1), "duplicate joint name"),
        "nan value": (head + "MOTION" + tail.replace(tail.split()[-1], "nan", 1), "finite number"),
        "inf value": ("\n".join(lines[:-1] + [lines[-1].replace(lines[-1].split()[0], "inf", 1)]) + "\n",
                      "finite number"),
        "text in frames": ("\n".join(lines[:-1] + [lines[-1].replace(lines[-1].split()[3], "abc", 1)]) + "\n",
                           "expected a number, found 'abc'"),
        "no MOTION": (head, "MOTION"),
        "no HIERARCHY": (GOOD.replace("HIERARCHY", "HIERARCHIE"), "HIERARCHY"),
        "bad offset": (GOOD.replace("OFFSET", "OFFSET x", 1), "number for OFFSET"),
        "bad channel count": (GOOD.replace("CHANNELS 6", "CHANNELS six", 1), "channel count"),
        "too few channel names": (GOOD.replace("CHANNELS 3", "CHANNELS 4", 1), "unknown channel"),
        "missing brace": (GOOD.replace("{", "", 1), "expected '{'"),
        "nul in frames": (GOOD[:-5] + "\x00" + GOOD[-4:], "binary"),
        f"only {n} lines, no ROOT": ("HIERARCHY\nMOTION\nFrames: 0\nFrame Time: 0.1\n", "expected ROOT"),
    }


@pytest.mark.parametrize("case", list(_bad_cases()))
def test_bad_input_raises_one_clear_error(case, tmp_path):
    content, fragment = _bad_cases()[case]
    path = tmp_path / "bad.bvh"
    path.write_bytes(content if isinstance(content, bytes) else content.encode())
    with pytest.raises(BVHError) as info:
        evalsuite.load_motion(path)
    message = str(info.value)
    assert str(path) in message
    assert fragment.lower() in message.lower(), message
    assert isinstance(info.value, ValueError)


@pytest.mark.parametrize("sep", [" ", "\t", "  "])
def test_compensating_value_counts_are_caught(sep, tmp_path):
    """One frame line with a value too many and the next with one too few: same total, still an error."""
    head, _, _ = GOOD.partition("MOTION")
    n_ch = parse_bvh(GOOD)[0].n_channels
    rows = [[f"{(r * n_ch + c) % 97}.5" for c in range(n_ch)] for r in range(3)]
    rows[0].append("1.0")
    rows[1].pop()
    text = head + "MOTION\nFrames: 3\nFrame Time: 0.04\n" + "\n".join(sep.join(r) for r in rows) + "\n"
    path = tmp_path / "shifted.bvh"
    path.write_text(text)
    with pytest.raises(BVHError, match=f"frame 0 has {n_ch + 1} values; expected {n_ch}") as info:
        evalsuite.load_motion(path)
    assert info.value.line == head.count("\n") + 4


def test_error_names_the_line_and_channel(tmp_path):
    lines = GOOD.splitlines()
    last = len(lines)
    bad = lines[:-1] + [lines[-1].replace(lines[-1].split()[4], "oops", 1)]
    path = tmp_path / "bad.bvh"
    path.write_text("\n".join(bad) + "\n")
    with pytest.raises(BVHError) as info:
        evalsuite.load_motion(path)
    assert info.value.line == last
    assert f"{path}:{last}:" in str(info.value)
    assert "frame 1, channel 'Hips Xrotation'" in str(info.value)


def test_missing_file_is_an_input_error(tmp_path):
    with pytest.raises(evalsuite.InputError, match="no such file"):
        evalsuite.load_motion(tmp_path / "nope.bvh")


def test_fuzzed_real_files_only_raise_bvherror(tmp_path):
    """Random mutations of real files either parse or raise BVHError: nothing else escapes."""
    rng = np.random.default_rng(1234)
    sources = [fixture("bvhio_example.bvh").read_bytes(), fixture("walk01.bvh").read_bytes()[:6000]]
    junk_tokens = [b"nan", b"{", b"}", b"JOINT", b"End Site", b"CHANNELS 7", b"OFFSET", b"-", b"1e999",
                   b"\xff\xfe", b"\x00", b"MOTION", b"Frames: 3", b"\r\n", b"\t", b"ROOT x"]
    outcomes = {"ok": 0, "error": 0}
    for i in range(400):
        data = bytearray(sources[i % 2])
        for _ in range(rng.integers(1, 4)):
            op = rng.integers(0, 5)
            pos = int(rng.integers(0, len(data)))
            if op == 0:  # truncate
                data = data[:pos]
            elif op == 1:  # delete a span
                del data[pos:pos + int(rng.integers(1, 40))]
            elif op == 2:  # insert a junk token
                data[pos:pos] = junk_tokens[rng.integers(0, len(junk_tokens))]
            elif op == 3:  # flip a byte
                if data:
                    data[min(pos, len(data) - 1)] = int(rng.integers(0, 256))
            else:  # duplicate a span
                data[pos:pos] = data[pos:pos + int(rng.integers(1, 80))]
        path = tmp_path / f"fuzz{i}.bvh"
        path.write_bytes(bytes(data))
        try:
            motion = evalsuite.load_motion(path)
        except BVHError:
            outcomes["error"] += 1
            continue
        assert motion.positions().shape == (motion.n_frames, motion.n_joints, 3)
        outcomes["ok"] += 1
    assert outcomes["error"] > 100  # the mutations really do break files


# --- fast FK against a slow per-frame reference (property based) ---------------------------

def slow_fk(skeleton: Skeleton, values: np.ndarray, root_offset: str, joint_translation: str) -> np.ndarray:
    """Per-frame, per-joint 4x4 transforms with scipy's intrinsic Euler rotations."""
    starts = skeleton.channel_starts
    out = np.zeros((len(values), skeleton.n_joints + len(skeleton.end_site_parents), 3))
    for t, frame in enumerate(values):
        world = []
        for j, chans in enumerate(skeleton.channels):
            vals = frame[starts[j]:starts[j] + len(chans)]
            axes = "".join(c[0] for c in chans if c.endswith("rotation"))
            angles = [v for v, c in zip(vals, chans) if c.endswith("rotation")]
            rot = Rotation.from_euler(axes, angles, degrees=True).as_matrix() if axes else np.eye(3)
            trans = skeleton.offsets[j].copy()
            is_root = skeleton.parents[j] < 0
            mode = ("replace" if root_offset == "ignore" else "add") if is_root else joint_translation
            for v, c in zip(vals, chans):
                if c.endswith("position") and mode != "ignore":
                    axis = "XYZ".index(c[0])
                    trans[axis] = v if mode == "replace" else trans[axis] + v
            local = np.eye(4)
            local[:3, :3] = rot
            local[:3, 3] = trans
            world.append(local if is_root else world[skeleton.parents[j]] @ local)
            out[t, j] = world[j][:3, 3]
        for e, (p, off) in enumerate(zip(skeleton.end_site_parents, skeleton.end_site_offsets)):
            out[t, skeleton.n_joints + e] = (world[p] @ np.append(off, 1.0))[:3]
    return out


@st.composite
def skeletons_and_motion(draw):
    n = draw(st.integers(1, 7))
    # Depth-first order, as in every BVH file: a joint's parent is on the path from the
    # previous joint up to its root (or it starts a new root now and then).
    parents = [-1]
    for j in range(1, n):
        path = [j - 1]
        while parents[path[-1]] >= 0:
            path.append(parents[path[-1]])
        parents.append(-1 if draw(st.integers(0, 9)) == 0 else draw(st.sampled_from(path)))
    floats = st.integers(-50000, 50000).map(lambda v: v / 1000)  # exactly representable in 6 decimals
    offsets = [[draw(floats) for _ in range(3)] for _ in range(n)]
    channels = []
    for _ in range(n):
        rot = draw(st.permutations(["Xrotation", "Yrotation", "Zrotation"]))[: draw(st.integers(0, 3))]
        pos = draw(st.permutations(["Xposition", "Yposition", "Zposition"]))[: draw(st.sampled_from([0, 1, 3]))]
        chans = list(rot) + list(pos)
        channels.append(tuple(draw(st.permutations(chans))))
    leaves = [j for j in range(n) if j not in parents[1:]]
    end_parents = [j for j in leaves if draw(st.booleans())]
    end_offsets = [[draw(floats) for _ in range(3)] for _ in end_parents]
    skeleton = Skeleton([f"j{i}" for i in range(n)], parents, offsets, channels, end_parents, end_offsets)
    frames = draw(st.integers(1, 4))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    values = rng.uniform(-180, 180, size=(frames, skeleton.n_channels)).round(4)
    return skeleton, values


@settings(max_examples=150, deadline=None)
@given(skeletons_and_motion(), st.sampled_from(["ignore", "add"]), st.sampled_from(["replace", "add", "ignore"]),
       st.sampled_from([1, 2, 2048]))
def test_fast_fk_matches_slow_reference(case, root_offset, joint_translation, block):
    skeleton, values = case
    # Through the writer and the reader, so the text path is exercised on odd skeletons too.
    parsed, parsed_values, _ = parse_bvh(format_bvh(skeleton, values, 1 / 30))
    assert parsed == skeleton
    np.testing.assert_allclose(parsed_values, values, atol=1e-6)
    fast = forward_kinematics(parsed, parsed_values, root_offset=root_offset, joint_translation=joint_translation,
                              end_sites=True, block_frames=block)
    slow = slow_fk(parsed, parsed_values, root_offset, joint_translation)
    np.testing.assert_allclose(fast, slow, atol=1e-8)


def test_world_rotations_match_reference():
    motion = evalsuite.load_motion(fixture("walk01.bvh"))
    rot = motion.world_rotations()
    sk = motion.skeleton
    starts = sk.channel_starts
    t = 37
    world = []
    for j, chans in enumerate(sk.channels):
        axes = "".join(c[0] for c in chans if c.endswith("rotation"))
        angles = [motion.values[t, starts[j] + i] for i, c in enumerate(chans) if c.endswith("rotation")]
        r = Rotation.from_euler(axes, angles, degrees=True).as_matrix()
        world.append(r if sk.parents[j] < 0 else world[sk.parents[j]] @ r)
    np.testing.assert_allclose(rot[t], np.stack(world), atol=1e-12)


NUMBER_FORMATS = [
    lambda v: f"{v:.6f}", lambda v: f"{v:+.3f}", lambda v: f"{v:.4e}", lambda v: f"{v:.2E}",
    lambda v: f"{v:g}", lambda v: (f"{v:.5f}".replace("0.", ".", 1) if 0 <= v < 1 else f"{v:.5f}"),
    lambda v: "-0" if v == 0 else repr(v),
]


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(-1e4, 1e4, allow_nan=False), st.integers(0, len(NUMBER_FORMATS) - 1)),
                min_size=6, max_size=6), st.integers(1, 5), st.sampled_from([" ", "\t", "  ", " \t "]))
def test_number_formats_parse_like_python(cells, n_frames, sep):
    """Every number spelling real files use parses to Python's float() of the token, on both fast paths."""
    header = ("HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition "
              "Zrotation Xrotation Yrotation\n End Site\n {\n  OFFSET 0 1 0\n }\n}\n")
    rows = []
    expected = []
    for f in range(n_frames):
        tokens = [NUMBER_FORMATS[k](v * (f + 1)) for v, k in cells]
        rows.append(sep.join(tokens))
        expected.append([float(t) for t in tokens])
    text = header + f"MOTION\nFrames: {n_frames}\nFrame Time: 0.05\n" + "\n".join(rows) + "\n"
    _, values, _ = parse_bvh(text)
    np.testing.assert_allclose(values, np.array(expected), rtol=1e-15, atol=0)
