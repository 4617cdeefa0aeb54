"""evalsuite.generators.checkpoints: a training killed with SIGKILL and resumed ends with the same weights as one
that ran through."""
from __future__ import annotations

import json
import signal
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from synth_helpers import build_corpus

from evalsuite.errors import InputError
from evalsuite.generators.checkpoints import Checkpointer, Every, check_run, parse_every

# Kills its own process with SIGKILL at the N-th checkpoint: right after writing it ("after"), or while writing it
# ("during": a partial .tmp file is left and the previous checkpoint must be used).
KILLER = textwrap.dedent("""
    import os, signal, sys
    from evalsuite.generators import checkpoints

    n, mode = int(sys.argv[1]), sys.argv[2]
    original = checkpoints.Checkpointer.step
    count = [0]

    def step(self, stage, epoch, objects, *, done=False):
        saving = self.folder is not None and (done or self.due(epoch))
        count[0] += saving
        if saving and count[0] == n and mode == "during":
            path = self._path(stage)
            path.with_name(path.name + ".tmp").write_bytes(b"half a checkpoint")
            os.kill(os.getpid(), signal.SIGKILL)
        original(self, stage, epoch, objects, done=done)
        if saving and count[0] == n:
            os.kill(os.getpid(), signal.SIGKILL)

    checkpoints.Checkpointer.step = step
    from evalsuite.cli import main
    main(sys.argv[3:])
""")

CASES = {
    "gesticulator": (["epochs=6", "words=\"hash\"", "ema=0.9", "patience=4"], 3, "after"),
    "aud2repr2pose": (["epochs=5", "dae_epochs=3", "patience=3"], 5, "during"),   # killed in the speech stage
    "aud2pose": (["epochs=5", "form=\"windowed\"", "width=16"], 2, "after"),
    # killed in the decoder-only VQ-DVAE epochs
    "gesture2vec": (["words=\"hash\"", "codebook=8", "dae_epochs=2", "vq_epochs=2", "vq_decoder_epochs=2",
                     "translation_epochs=3"], 5, "after"),
    # killed in the adversarial steps (the discriminators' pre-training is re-run on resume)
    "ferstl-mogan": (["classifier_epochs=2", "pretrain_epochs=2", "adversarial_steps=6", "batch_size=4",
                      "realism_pretrain_steps=2", "phase_pretrain_tries=2"], 7, "during"),
}


@pytest.fixture(scope="module")
def corpus_dir(tmp_path_factory):
    return build_corpus(tmp_path_factory.mktemp("speaker") / "c", minutes=1.0, seed=4)


def _train_args(name, corpus_dir, out, settings, *extra):
    args = ["train", "-g", name, "--corpus", str(corpus_dir), "-o", str(out), *extra]
    for s in settings:
        args += ["--set", s]
    return args


def _run(args, script=None, tmp_path=None):
    if script is None:
        cmd = [sys.executable, "-m", "evalsuite", *args]
    else:
        path = tmp_path / "killer.py"
        path.write_text(KILLER)
        cmd = [sys.executable, str(path), *script, *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=600)


@pytest.mark.slow
@pytest.mark.parametrize("name", list(CASES))
def test_a_training_killed_and_resumed_ends_with_the_same_weights(name, corpus_dir, tmp_path):
    settings, kill_at, mode = CASES[name]
    straight, killed = tmp_path / "straight", tmp_path / "killed"
    done = _run(_train_args(name, corpus_dir, straight, settings, "--checkpoint-every", "off"))
    assert done.returncode == 0, done.stderr
    dead = _run(_train_args(name, corpus_dir, killed, settings, "--checkpoint-every", "1"),
                script=[str(kill_at), mode], tmp_path=tmp_path)
    assert dead.returncode == -signal.SIGKILL, dead.stderr
    assert not (killed / "model.json").exists() and (killed / "checkpoints" / "run.json").exists()
    resumed = _run(_train_args(name, corpus_dir, killed, settings, "--checkpoint-every", "1", "--resume"))
    assert resumed.returncode == 0, resumed.stderr
    a = json.loads((straight / "model.json").read_text())
    b = json.loads((killed / "model.json").read_text())
    assert b["resumed_stages"]
    assert a["weights_sha256"] == b["weights_sha256"]
    strip = [{k: v for k, v in r.items() if k != "seconds"} for r in a["history"]]
    assert strip == [{k: v for k, v in r.items() if k != "seconds"} for r in b["history"]]
    assert not (killed / "checkpoints").exists()


def test_resume_refuses_other_options(corpus_dir, tmp_path):
    check_run(tmp_path, {"generator": "aud2pose", "config": {"epochs": 5}, "seed": 0, "preset": "cpu-small"}, False)
    with pytest.raises(InputError, match="same config"):
        check_run(tmp_path, {"generator": "aud2pose", "config": {"epochs": 6}, "seed": 0, "preset": "cpu-small"},
                  True)
    check_run(tmp_path, {"generator": "aud2pose", "config": {"epochs": 5}, "seed": 0, "preset": "cpu-small"}, True)


def test_checkpoint_intervals_and_states(tmp_path):
    assert parse_every("5") == Every(epochs=5) and parse_every("10m") == Every(minutes=10.0)
    assert parse_every("off") is None
    with pytest.raises(InputError, match="--checkpoint-every"):
        parse_every("often")
    ck = Checkpointer(tmp_path / "ck", Every(epochs=2), resume=True)
    rng, history = np.random.default_rng(3), [{"epoch": 1}]
    state = {"rng": rng, "history": history}
    ck.step("s", 1, state)                      # not due
    assert not (tmp_path / "ck" / "s.pt").exists()
    ck.step("s", 2, state)
    expected = rng.random(3)
    history.append({"epoch": 3})
    rng2, history2 = np.random.default_rng(99), []
    assert ck.start("s", {"rng": rng2, "history": history2}) == (2, False)
    assert np.array_equal(rng2.random(3), expected) and history2 == [{"epoch": 1}]
    assert Checkpointer(tmp_path / "ck", resume=False).start("s", state) == (0, False)
