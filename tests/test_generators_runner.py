"""The generator contract's rules, enforced by the runner on every plug-in; provenance, cache, parallel runs."""
from __future__ import annotations

import json
import pathlib

import numpy as np
import pytest

from evalsuite.errors import InputError
from evalsuite.generators import GenerationRequest, GenerationResult, Generator, GeneratorError, GeneratorSpec
from evalsuite.generators.checking import tiny_corpus
from evalsuite.generators.registry import GeneratorEntry
from evalsuite.generators.requests import requests_from_corpus
from evalsuite.generators.rules import length_tolerance
from evalsuite.generators.runner import PostProcess, derive_seed, generate
from evalsuite.motion import Motion
from evalsuite.motion.io import load_motion

JOINTS = ("Hips", "Head", "RightHand", "LeftHand")


def _positions(req: GenerationRequest, n: int, fps: float, rng: np.random.Generator | None = None) -> Motion:
    rng = rng or np.random.default_rng(req.seed)
    pos = np.cumsum(rng.normal(0, 0.1, size=(n, len(JOINTS), 3)), axis=0)
    return Motion.from_positions(pos, JOINTS, fps)


class ToyPositions(Generator):
    """A positions generator with knobs that break rules on purpose."""

    spec = GeneratorSpec(name="toy", version="1", summary="test plug-in", output="positions", joints=JOINTS,
                         native_fps=20.0, stochastic=True, units="m",
                         config={"extra_frames": "frames to add", "nan": "put a NaN in", "joint": "rename a joint",
                                 "unseeded": "ignore the seed", "fps": "output rate"})
    counter = 0

    def generate(self, request: GenerationRequest) -> GenerationResult:
        fps = float(self.option("fps", 20.0))
        n = int(round(request.duration * fps)) + int(self.option("extra_frames", 0))
        rng = None
        if self.option("unseeded"):
            ToyPositions.counter += 1
            rng = np.random.default_rng(ToyPositions.counter)
        m = _positions(request, n, fps, rng)
        if self.option("nan"):
            p = m.positions().copy()
            p[5, 2, 1] = np.nan
            m = m.with_positions(p)
        if self.option("joint"):
            m = m.with_positions(m.positions(), joint_names=["Hips", "Head", "RightHand", self.option("joint")])
        return GenerationResult(m, {"note": "toy"})


ENTRY = GeneratorEntry("toy", f"{__name__}:ToyPositions", "ad hoc", None, ToyPositions.spec)


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    return tiny_corpus(tmp_path_factory.mktemp("tiny"))


@pytest.fixture(scope="module")
def requests(corpus):
    return requests_from_corpus(corpus, "all", 30.0)


def test_resampled_to_the_requested_fps_and_recorded(requests, tmp_path):
    run = generate(ENTRY, requests, tmp_path, seed=1, progress=False)
    row = run.files[0]
    assert row["fps"] == 30.0
    assert row["frames"] == requests[0].n_frames
    assert {n["rule"] for n in row["notes"]} >= {"fps"}
    assert row["notes"][0]["from_fps"] == 20.0
    m = load_motion(tmp_path / row["file"])
    assert m.fps == 30.0
    assert m.n_frames == requests[0].n_frames
    record = json.loads((tmp_path / "generation.json").read_text())
    assert record["generator"]["name"] == "toy"
    assert record["seed"] == 1
    assert "numpy" in record["packages"]
    assert record["files"][0]["sha256"] == row["sha256"]


def test_slightly_wrong_length_is_trimmed_and_logged(requests, tmp_path):
    run = generate(ENTRY, requests, tmp_path, config={"fps": 30.0, "extra_frames": 1}, progress=False)
    notes = run.files[0]["notes"]
    assert notes == [{"rule": "length", "action": "trimmed", "from_frames": requests[0].n_frames + 1,
                      "to_frames": requests[0].n_frames}]


def test_wrong_length_is_an_error_naming_plugin_and_segment(requests, tmp_path):
    extra = length_tolerance(requests[0].n_frames) + 3
    with pytest.raises(GeneratorError, match=r"generator 'toy', segment 'seg00': output has \d+ frames at 30 fps, "
                                             r"expected 120"):
        generate(ENTRY, requests, tmp_path, config={"fps": 30.0, "extra_frames": extra}, progress=False)


def test_nan_is_rejected(requests, tmp_path):
    with pytest.raises(GeneratorError, match=r"segment 'seg00': output has 1 non-finite values \(first at frame 5, "
                                             r"RightHand.y\)"):
        generate(ENTRY, requests, tmp_path, config={"nan": True}, progress=False)


def test_unknown_joints_are_rejected(requests, tmp_path):
    with pytest.raises(GeneratorError, match="output has joints the spec does not declare: Tail"):
        generate(ENTRY, requests, tmp_path, config={"joint": "Tail"}, progress=False)


def test_different_output_for_the_same_seed_is_rejected(requests, tmp_path):
    with pytest.raises(GeneratorError, match=r"two runs with the same inputs, config, model and seed .* gave "
                                             "different output"):
        generate(ENTRY, requests, tmp_path, config={"unseeded": True}, progress=False)


def test_positions_where_the_spec_promises_bvh_are_rejected(requests, tmp_path):
    class Liar(ToyPositions):
        spec = GeneratorSpec(name="liar", version="1", summary="", output="bvh")

    entry = GeneratorEntry("liar", "x:Liar", "ad hoc", None, Liar.spec)
    from evalsuite.generators import runner

    key = json.dumps(["x:Liar", {}, None], sort_keys=True, default=str)
    runner._LOADED[key] = Liar()
    with pytest.raises(GeneratorError, match="declares BVH output .* holds positions only"):
        generate(entry, requests, tmp_path, progress=False)


def test_same_seed_same_files_and_samples_named_and_seeded(requests, tmp_path):
    a = generate(ENTRY, requests, tmp_path / "a", seed=5, samples=3, progress=False)
    b = generate(ENTRY, requests, tmp_path / "b", seed=5, samples=3, progress=False)
    assert [r["sha256"] for r in a.files] == [r["sha256"] for r in b.files]
    names = sorted(r["file"] for r in a.files)
    assert names[:3] == ["seg00_0.npz", "seg00_1.npz", "seg00_2.npz"]
    assert len({r["sha256"] for r in a.files if r["segment"] == "seg00"}) == 3
    assert a.files[0]["seed"] == derive_seed(5, "seg00", 0)
    c = generate(ENTRY, requests, tmp_path / "c", seed=6, samples=3, progress=False)
    assert [r["sha256"] for r in c.files] != [r["sha256"] for r in a.files]


def test_deterministic_generators_refuse_samples(requests, tmp_path):
    from evalsuite.generators import find_generator

    with pytest.raises(InputError, match="natural is deterministic as configured: --samples 2"):
        generate(find_generator("natural"), requests, tmp_path, samples=2, progress=False)


def test_cache_hit_and_miss(requests, tmp_path):
    first = generate(ENTRY, requests, tmp_path, seed=2, progress=False)
    assert not first.cached
    again = generate(ENTRY, requests, tmp_path, seed=2, progress=False)
    assert again.cached
    # a changed output file is not trusted
    (tmp_path / first.files[0]["file"]).write_bytes(b"changed")
    assert not generate(ENTRY, requests, tmp_path, seed=2, progress=False).cached
    # another post-processing is another run
    smoothed = generate(ENTRY, requests, tmp_path, seed=2, progress=False,
                        post=[PostProcess("savgol", (("window", 9), ("order", 3)))])
    assert not smoothed.cached
    assert json.loads((tmp_path / "generation.json").read_text())["post"] == [{"method": "savgol", "window": 9,
                                                                               "order": 3}]


def test_local_processes_and_dask_give_the_same_files(requests, tmp_path):
    import distributed  # in the test extra

    from evalsuite.generators import find_generator

    entry = find_generator("gaussian_noise")
    one = generate(entry, requests, tmp_path / "one", seed=4, progress=False)
    two = generate(entry, requests, tmp_path / "two", seed=4, jobs=2, progress=False)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False, protocol="tcp",
                                  host="127.0.0.1", dashboard_address=None) as cluster:
        dask = generate(entry, requests, tmp_path / "dask", seed=4, dask_address=cluster.scheduler_address,
                        progress=False)
    assert [r["sha256"] for r in two.files] == [r["sha256"] for r in one.files]
    assert [r["sha256"] for r in dask.files] == [r["sha256"] for r in one.files]


def test_requests_carry_the_corpus_durations(corpus):
    reqs = requests_from_corpus(corpus, "test", 25.0)
    assert [r.segment_id for r in reqs] == [s.id for s in corpus.split("test")]
    assert reqs[0].n_frames == 100
    with pytest.raises(InputError, match="no segment\\(s\\) nope"):
        requests_from_corpus(corpus, "test", 25.0, segments=["nope"])


def test_file_name_of_output_follows_kind(requests, tmp_path):
    from evalsuite.generators import find_generator

    run = generate(find_generator("natural"), requests[:2], tmp_path, progress=False)
    assert [r["file"] for r in run.files] == ["seg00.bvh", "seg01.bvh"]
    assert pathlib.Path(tmp_path / "seg00.bvh").read_text().startswith("HIERARCHY")
