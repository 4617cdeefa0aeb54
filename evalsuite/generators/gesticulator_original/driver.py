"""evalsuite's driver for the original Gesticulator; it runs under the USER's interpreter, not evalsuite's.

Python 3.6 compatible, standard library only (plus what the user's clone of the original repository and its
environment provide). Nothing here imports evalsuite. Usage (the gesticulator-original plug-in builds it):

    python driver.py REQUEST_JSON --repo CLONE --checkpoint FILE.ckpt --bert BERT_FOLDER

REQUEST_JSON is the subprocess bridge's request.json (segment audio, out_dir); the plug-in has written the
segment's transcript as Google ASR JSON into ``out_dir/transcript.json``. The driver writes ``out_dir/out.bvh``
(the original's 20 fps BVH) and ``out_dir/result.json``. Errors go to stderr with a non-zero exit code.

Every use of the original's Python interface is in ``call_original`` (and ``use_local_bert``, which it calls).
The interface assumed there, from the original repository's demo (``demo/demo.py``) and its
``gesticulator/interface/gesture_predictor.py``:

* ``gesticulator.model.model.GesticulatorModel.load_from_checkpoint(path, inference_mode=True)``;
* the audio feature type follows from the speech encoder's input size minus 773 (768 BERT + 5 timing
  features): 4 Pros, 64 Spectro, 68 Spectro+Pros, 26 MFCC, 30 MFCC+Pros;
* ``gesticulator.interface.gesture_predictor.GesturePredictor(model, feature_type).predict_gestures(wav,
  json_path)`` returns the motion (1, T, 45) at 20 fps; it builds BERT with
  ``BertTokenizer/BertModel.from_pretrained('bert-base-cased')`` (names looked up in that module), which this
  driver redirects to the local folder so that nothing is downloaded;
* ``motion_visualizer.convert2bvh.write_bvh((data_pipe_path,), motion, bvh_path, 20)`` with
  ``gesticulator/utils/data_pipe.sav`` writes the BVH.

If a clone's interface differs (older clones embed text with the mxnet ``bert-embedding`` package instead of
``transformers``), the driver stops with a message saying which piece is missing.
"""
import argparse
import json
import os
import sys
import traceback

FPS = 20
TEXT_DIM = 773  # 768 (BERT-base) + 5 word timing features
FEATURE_TYPES = {4: "Pros", 64: "Spectro", 68: "Spectro+Pros", 26: "MFCC", 30: "MFCC+Pros"}
BERT_NAME = "bert-base-cased"


class DriverError(Exception):
    pass


class _LocalPretrained:
    """Stands in for a transformers class in the original's module: from_pretrained('bert-base-cased') loads
    the local folder instead (other names go through unchanged)."""

    def __init__(self, cls, folder):
        self.cls = cls
        self.folder = folder

    def from_pretrained(self, name, *args, **kwargs):
        target = self.folder if name == BERT_NAME else name
        return self.cls.from_pretrained(target, *args, **kwargs)

    def __getattr__(self, attr):
        return getattr(self.cls, attr)


def add_repo_to_path(repo):
    # the package 'gesticulator' lives at the clone's root; 'motion_visualizer' and 'pymo' in
    # gesticulator/visualization (the original installs both with pip -e; this works without that too)
    for folder in (os.path.join(repo, "gesticulator", "visualization"), repo):
        if folder not in sys.path:
            sys.path.insert(0, folder)


def use_local_bert(predictor_module, bert_dir):
    for name in ("BertTokenizer", "BertModel"):
        cls = getattr(predictor_module, name, None)
        if cls is None or not hasattr(cls, "from_pretrained"):
            raise DriverError(
                f"gesticulator/interface/gesture_predictor.py has no transformers {name} to point at the local "
                "BERT folder; this clone seems to predate the switch to transformers (it embeds text with the "
                "bert-embedding/mxnet packages): update the clone")
        setattr(predictor_module, name, _LocalPretrained(cls, bert_dir))


def feature_type_of(model):
    try:
        in_dim = int(model.encode_speech[0].weight.shape[1])
    except (AttributeError, IndexError, TypeError):
        raise DriverError("cannot read the speech encoder's input size (model.encode_speech[0].weight): "
                          "only the feed-forward speech encoder of the demo model is supported") from None
    audio_dim = in_dim - TEXT_DIM
    if audio_dim not in FEATURE_TYPES:
        raise DriverError(f"unknown audio feature size {audio_dim} (speech encoder input {in_dim} minus "
                          f"{TEXT_DIM} text features); known: {FEATURE_TYPES}")
    return FEATURE_TYPES[audio_dim]


def as_nested_array(motion):
    """The predictor's output as a numpy array when torch/numpy are there (the real code), else unchanged."""
    if hasattr(motion, "detach"):
        motion = motion.detach()
    if hasattr(motion, "cpu"):
        motion = motion.cpu()
    if hasattr(motion, "numpy"):
        motion = motion.numpy()
    return motion


def call_original(repo, checkpoint, bert_dir, audio_path, transcript_path, bvh_path):
    """THE CALL POINT: everything that touches the original's interface. Returns notes for result.json."""
    add_repo_to_path(repo)
    try:
        import gesticulator.interface.gesture_predictor as predictor_module
        from gesticulator.model.model import GesticulatorModel
        from motion_visualizer.convert2bvh import write_bvh
    except ImportError as exc:
        raise DriverError(f"cannot import the original's modules from {repo} with {sys.executable} ({exc}); "
                          "is this the interpreter of the environment the original's requirements were "
                          "installed into?") from None
    use_local_bert(predictor_module, bert_dir)
    model = GesticulatorModel.load_from_checkpoint(checkpoint, inference_mode=True)
    feature_type = feature_type_of(model)
    predictor = predictor_module.GesturePredictor(model, feature_type)
    torch = sys.modules.get("torch")  # imported by the original's modules; absent in a stub
    if torch is not None and hasattr(torch, "no_grad"):
        with torch.no_grad():
            motion = predictor.predict_gestures(audio_path, transcript_path)
    else:
        motion = predictor.predict_gestures(audio_path, transcript_path)
    motion = as_nested_array(motion)
    data_pipe = os.path.join(repo, "gesticulator", "utils", "data_pipe.sav")
    write_bvh((data_pipe,), motion, bvh_path, FPS)
    return {"feature_type": feature_type, "frames": len(motion[0])}


def main(argv=None):
    parser = argparse.ArgumentParser(description="Run the original Gesticulator on one bridge request.")
    parser.add_argument("request")
    parser.add_argument("--repo", required=True)
    parser.add_argument("--checkpoint", required=True)
    parser.add_argument("--bert", required=True)
    args = parser.parse_args(argv)
    # the original reports its errors with print() and exit(-1): send everything to stderr, which the
    # plug-in shows when the driver fails (the driver talks to the plug-in through result.json only)
    sys.stdout = sys.stderr
    try:
        with open(args.request, encoding="utf-8") as f:
            request = json.load(f)
        out_dir = request["out_dir"]
        audio = request.get("audio")
        if not audio:
            raise DriverError("the request has no audio; Gesticulator needs the segment's wav")
        transcript = os.path.join(out_dir, "transcript.json")
        if not os.path.isfile(transcript):
            raise DriverError("no transcript.json in " + out_dir)
        bvh = os.path.join(out_dir, "out.bvh")
        notes = call_original(os.path.abspath(args.repo), os.path.abspath(args.checkpoint),
                              os.path.abspath(args.bert), audio, transcript, bvh)
        if not os.path.isfile(bvh):
            raise DriverError("the original's write_bvh wrote no " + bvh)
        with open(os.path.join(out_dir, "result.json"), "w", encoding="utf-8") as f:
            json.dump({"motion": "out.bvh", "fps": FPS, "meta": notes}, f)
    except DriverError as exc:
        sys.stderr.write(f"gesticulator-original driver: {exc}\n")
        return 2
    except Exception:
        traceback.print_exc()
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
