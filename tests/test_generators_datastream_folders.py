"""evalsuite.generators.datastream.training_folder: every re-implementation's training keeps its memory-mapped data
in a folder named after its process, and a training killed with SIGKILL (which runs no clean-up) has its folder
removed when the next training starts."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import tempfile
import textwrap

import pytest
from synth_helpers import build_corpus

from evalsuite.corpus import load_corpus
from evalsuite.generators import datastream, find_generator
from evalsuite.generators.registry import generator_class

# Trains gesture2vec on a corpus and kills itself with SIGKILL as its three stages start: the plug-in has written
# the training split's poses and word vectors to its training folder by then.
KILLED = textwrap.dedent("""
    import os, signal, sys
    from evalsuite.generators.gesture2vec import training

    def killed(*args, data_dir=None, **kwargs):
        print(data_dir, flush=True)
        os.kill(os.getpid(), signal.SIGKILL)

    training.train_gesture2vec = killed
    from evalsuite.cli import main
    main(["train", "-g", "gesture2vec", "--corpus", sys.argv[1], "-o", sys.argv[2], "--set", 'words="hash"'])
""")

# each trainable re-implementation's training function (imported by its plug-in when fit runs)
TRAINERS = {
    "gesticulator": ("evalsuite.generators.gesticulator.training", "train_gesticulator", {"words": "hash"}),
    "aud2pose": ("evalsuite.generators.aud2repr2pose.training", "train_system", {}),
    "aud2motion": ("evalsuite.generators.aud2repr2pose.training", "train_system", {}),
    "aud2repr2pose": ("evalsuite.generators.aud2repr2pose.training", "train_system", {}),
    "gesture2vec": ("evalsuite.generators.gesture2vec.training", "train_gesture2vec", {"words": "hash"}),
    "ferstl-mogan": ("evalsuite.generators.ferstl_mogan.training", "train_mogan", {}),
}


@pytest.fixture(scope="module")
def corpus_dir(tmp_path_factory):
    return build_corpus(tmp_path_factory.mktemp("speaker") / "c", minutes=0.5, seed=4)


@pytest.fixture
def temp_root(tmp_path, monkeypatch):
    """The temporary directory (of this process and of its children) moved to ``tmp_path``."""
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    return tmp_path / f"evalsuite-training-{os.getuid()}"


def _gone_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def test_folders_of_processes_that_are_gone_are_removed_others_kept(temp_root):
    temp_root.mkdir()
    dead = temp_root / f"aud2pose-data-{_gone_pid()}-abc_12"
    alive = temp_root / f"ferstl-mogan-data-{os.getppid()}-x9"
    other = temp_root / "notes-1"
    for folder in (dead, alive, other):
        folder.mkdir()
        (folder / "poses.npy").write_bytes(b"x")
    mine = datastream.training_folder("gesture2vec")
    assert not dead.exists() and alive.exists() and other.exists()
    assert mine.name.startswith(str(temp_root / f"gesture2vec-data-{os.getpid()}-"))
    assert datastream.remove_stale_folders() == []     # its own folder is kept
    mine.cleanup()


def test_a_training_killed_with_sigkill_has_its_folder_removed_by_the_next_one(corpus_dir, temp_root, tmp_path):
    script = tmp_path / "killed.py"
    script.write_text(KILLED)
    env = {**os.environ, "TMPDIR": str(tmp_path)}
    dead = subprocess.run([sys.executable, str(script), str(corpus_dir), str(tmp_path / "model")],
                          capture_output=True, text=True, timeout=300, env=env)
    assert dead.returncode == -signal.SIGKILL, dead.stderr
    left = [p for p in temp_root.iterdir() if p.name.startswith("gesture2vec-data-")]
    assert len(left) == 1 and (left[0] / "corpus_poses.npy").is_file()
    assert dead.stdout.strip() == str(left[0])
    nxt = datastream.training_folder("aud2pose")      # what the next training's fit does first
    assert not left[0].exists()
    nxt.cleanup()


@pytest.mark.parametrize("name", list(TRAINERS))
def test_every_reimplementation_trains_in_a_training_folder(name, corpus_dir, temp_root, monkeypatch):
    module, function, config = TRAINERS[name]
    seen = []

    class Stop(Exception):
        pass

    def trainer(*args, data_dir=None, **kwargs):
        seen.append(data_dir)
        raise Stop

    monkeypatch.setattr(__import__(module, fromlist=[function]), function, trainer)
    gen = generator_class(find_generator(name).target)()
    gen.configure(config)
    with pytest.raises(Stop):
        gen.fit(load_corpus(corpus_dir), temp_root.parent / "model", seed=0)
    assert seen[0].parent == temp_root and seen[0].name.startswith(f"{name}-data-{os.getpid()}-")
