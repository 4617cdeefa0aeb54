"""The published Aud2Repr2Pose English demo model (Kucherenko et al., "Moving fast and slow", IJHCI 2021),
run in-process with numpy: no TensorFlow, no Keras.

The demo pipeline is speech windows -> speech encoder (Keras 2.2.4 HDF5) -> 112-d motion representation ->
the denoising autoencoder's decoder (TensorFlow 1 checkpoint) -> 138 values = 46 points x (x, y, z) at 20 fps,
un-normalised with ``max_val.npy`` / ``mean_pose.npy`` and smoothed with Savitzky-Golay (9, 3).

Quirks of the original that this module reproduces (facts from the golden README of the original run):

- the GRU's recurrent activation is **Keras 2's** ``hard_sigmoid`` = clip(0.2 x + 0.5, 0, 1) (Keras 3 changed it);
- the original decodes in batches of 8 and **drops the last N mod 8 frames** (``drop_tail=True``, default);
- its decoder leaves dropout on at inference (keep probability 0.8, unseeded). Here the default is the
  deterministic reference (keep probability 1.0); ``keep_prob < 1`` with a ``seed`` draws one seeded sample.

Arrays are float32 through the networks, as in the original, and float64 from the un-normalisation on. The
speech encoder's tanh and batch-norm reciprocal square roots are TensorFlow's CPU approximations
(:mod:`~evalsuite.generators.aud2repr2pose_demo.tf_arithmetic`): with them the GRU states equal the golden run's
bit for bit on a CPU of its family. The decoder's tanh stays numpy's (TensorFlow fused it into a oneDNN kernel).
"""
from __future__ import annotations

import json
import pathlib
from dataclasses import dataclass

import numpy as np
from scipy.signal import savgol_filter

from evalsuite.errors import InputError
from evalsuite.generators.aud2repr2pose_demo.tf1_checkpoint import read_tf1_checkpoint
from evalsuite.generators.aud2repr2pose_demo.tf_arithmetic import eigen_tanh, tf_rsqrt

__all__ = ["DemoModelError", "SpeechEncoder", "MotionDecoder", "Aud2Repr2PoseDemo", "POINT_NAMES", "POINT_PARENTS",
           "hard_sigmoid_keras2"]

FPS = 20.0
CONTEXT = 61          # frames per speech window (30 before, the frame, 30 after)
FEATURE_DIM = 30      # 26 MFCC + 4 prosody
LATENT_DIM = 112
MOTION_DIM = 138      # 46 points x 3
DECODE_BATCH = 8      # the original decodes in batches of 8 and drops the incomplete tail
SAVGOL_WINDOW, SAVGOL_ORDER = 9, 3

# The demo's 46 points in output order (names from the original visualiser's docstring).
_FINGERS = ("Thumb", "Index", "Middle", "Ring", "Pinky")
POINT_NAMES: tuple[str, ...] = (
    "Hips", "Spine", "Spine1", "Spine2", "Spine3", "Neck", "Neck1", "Head",
    "RightShoulder", "RightArm", "RightForeArm", "RightHand",
    *(f"RightHand{f}{i}" for f in _FINGERS for i in (1, 2, 3)),
    "LeftShoulder", "LeftArm", "LeftForeArm", "LeftHand",
    *(f"LeftHand{f}{i}" for f in _FINGERS for i in (1, 2, 3)),
)
# Parent of each point for drawing (the visualiser's chains: torso, arms from Spine3, fingers from the hands).
POINT_PARENTS: tuple[int, ...] = (
    -1, 0, 1, 2, 3, 4, 5, 6,
    4, 4, 9, 10, *(p for _ in _FINGERS for p in (11, -2, -2)),
    4, 4, 28, 29, *(p for _ in _FINGERS for p in (30, -2, -2)),
)
POINT_PARENTS = tuple(i - 1 if p == -2 else p for i, p in enumerate(POINT_PARENTS))


class DemoModelError(InputError):
    """The demo model's files are missing or do not have the published layout."""


def hard_sigmoid_keras2(x: np.ndarray) -> np.ndarray:
    """Keras 2 ``hard_sigmoid``: clip(0.2 x + 0.5, 0, 1) (Keras 3 uses x/6 + 0.5; this model needs Keras 2's)."""
    return np.clip(np.float32(0.2) * x + np.float32(0.5), 0.0, 1.0).astype(np.float32)


def _distinct_frames(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(T, W, F) windows -> (distinct frames (N, F), index (T, W) of each window position's frame). Windows that
    slide by one frame over one sequence (what the demo's recipe makes) are recognised without sorting."""
    if len(x) > 1 and np.array_equal(x[1:, :-1], x[:-1, 1:]):
        frames = np.concatenate([x[:, 0], x[-1, 1:]])
        return frames, np.arange(x.shape[0])[:, None] + np.arange(x.shape[1])[None, :]
    frames, where = np.unique(x.reshape(-1, x.shape[2]), axis=0, return_inverse=True)
    return frames, where.reshape(x.shape[:2])


def _batch_norm(x: np.ndarray, p: dict[str, np.ndarray], eps: float) -> np.ndarray:
    """Keras inference-mode batch norm in TensorFlow's order, x * inv + (beta - mean * inv) with
    inv = rsqrt(var + eps) * gamma (``tf.nn.batch_normalization``), not (x - mean) * inv + beta: the same
    formula, but float32 rounds the two differently; rsqrt as TensorFlow's CPU kernel computes it
    (:func:`~evalsuite.generators.aud2repr2pose_demo.tf_arithmetic.tf_rsqrt`)."""
    f32 = np.float32
    inv = (tf_rsqrt((p["moving_variance"] + f32(eps)).astype(f32)) * p["gamma"]).astype(f32)
    return (x * inv + (p["beta"] - (p["moving_mean"] * inv).astype(f32)).astype(f32)).astype(f32)


@dataclass
class SpeechEncoder:
    """The demo's speech encoder: (T, 61, 30) windows -> (T, 112) codes, in Keras inference mode.

    TimeDistributed Dense 256 -> BN -> ReLU -> TimeDistributed Dense 256 -> BN -> ReLU -> GRU 128 (last state)
    -> BN -> ReLU -> Dense 112. Dropout layers are identities at inference.
    """

    weights: dict[str, dict[str, np.ndarray]]
    bn_epsilon: dict[str, float]

    @classmethod
    def from_hdf5(cls, path: str | pathlib.Path) -> SpeechEncoder:
        """Read the Keras 2 HDF5 file (needs h5py). Checks the layer stack against the published model."""
        try:
            import h5py
        except ImportError:  # pragma: no cover - h5py is a dependency of the generators extra
            raise DemoModelError("reading the demo's Keras HDF5 speech encoder needs h5py: "
                                 "pip install h5py") from None
        path = pathlib.Path(path)
        if not path.is_file():
            raise DemoModelError(f"{path}: speech encoder file not found")
        try:
            with h5py.File(path, "r") as f:
                config = json.loads(f.attrs["model_config"])
                layers = config["config"]["layers"] if isinstance(config["config"], dict) else config["config"]
                group = f["model_weights"]
                weights: dict[str, dict[str, np.ndarray]] = {}
                for name in group:
                    params: dict[str, np.ndarray] = {}
                    group[name].visititems(lambda key, obj, params=params: params.__setitem__(
                        key.rsplit("/", 1)[-1].split(":")[0], np.asarray(obj, dtype=np.float32))
                        if hasattr(obj, "shape") else None)
                    if params:
                        weights[name] = params
        except (OSError, KeyError, ValueError, TypeError) as exc:
            raise DemoModelError(f"{path}: not the demo's Keras HDF5 model ({exc})") from None
        kinds = [layer["class_name"] for layer in layers]
        expected = ["TimeDistributed", "BatchNormalization", "Activation", "Dropout",
                    "TimeDistributed", "BatchNormalization", "Activation", "Dropout",
                    "GRU", "BatchNormalization", "Activation", "Dropout", "Dense", "Activation"]
        if [k for k in kinds if k != "InputLayer"] != expected:
            raise DemoModelError(f"{path}: layer stack {kinds} is not the published demo model's {expected}")
        gru = next(layer["config"] for layer in layers if layer["class_name"] == "GRU")
        if gru.get("recurrent_activation") != "hard_sigmoid" or gru.get("reset_after", False):
            raise DemoModelError(f"{path}: GRU with recurrent_activation={gru.get('recurrent_activation')!r}, "
                                 f"reset_after={gru.get('reset_after')!r}; expected 'hard_sigmoid', False")
        eps = {layer["config"]["name"]: float(layer["config"]["epsilon"])
               for layer in layers if layer["class_name"] == "BatchNormalization"}
        names = [layer["config"]["name"] for layer in layers
                 if layer["class_name"] in ("TimeDistributed", "BatchNormalization", "GRU", "Dense")]
        missing = [n for n in names if n not in weights]
        if missing:
            raise DemoModelError(f"{path}: no weights for layers {missing}")
        ordered = {n: weights[n] for n in names}
        return cls(weights=ordered, bn_epsilon=eps)

    def _layers(self) -> list[tuple[str, dict[str, np.ndarray]]]:
        return list(self.weights.items())

    def gru_states(self, windows: np.ndarray) -> np.ndarray:
        """(T, 61, 30) -> (T, 128): the GRU's last hidden state for each window (before BN/ReLU/Dense)."""
        x = np.asarray(windows, dtype=np.float32)
        if x.ndim != 3 or x.shape[2] != FEATURE_DIM:
            raise InputError(f"speech windows: expected shape (T, {CONTEXT}, {FEATURE_DIM}), got {x.shape}")
        (td1, p1), (bn1, q1), (td2, p2), (bn2, q2), (_, g) = self._layers()[:5]
        # Every layer before the recurrence works frame by frame, and each feature frame stands in up to 61
        # overlapping windows: compute those layers once per distinct frame (about 60x less work), then
        # gather. Row by row the arithmetic is the same.
        frames, where = _distinct_frames(x)
        h = np.maximum(_batch_norm(frames @ p1["kernel"] + p1["bias"], q1, self.bn_epsilon[bn1]), 0)
        h = np.maximum(_batch_norm(h @ p2["kernel"] + p2["bias"], q2, self.bn_epsilon[bn2]), 0)
        units = g["recurrent_kernel"].shape[0]
        wz, wr, wh = np.split(g["kernel"], 3, axis=1)           # Keras gate order: z, r, h
        uz, ur, uh = np.split(g["recurrent_kernel"], 3, axis=1)
        bz, br, bh = np.split(g["bias"], 3)
        xz, xr, xh = ((h @ w + b)[where] for w, b in ((wz, bz), (wr, br), (wh, bh)))   # (T, 61, units) each
        state = np.zeros((x.shape[0], units), dtype=np.float32)
        for t in range(x.shape[1]):
            z = hard_sigmoid_keras2(xz[:, t] + state @ uz)
            r = hard_sigmoid_keras2(xr[:, t] + state @ ur)
            candidate = eigen_tanh(xh[:, t] + (r * state) @ uh)
            state = (z * state + (1 - z) * candidate).astype(np.float32)
        return state

    def __call__(self, windows: np.ndarray) -> np.ndarray:
        """(T, 61, 30) float windows -> (T, 112) float32 motion codes."""
        return self.codes_from_gru_states(self.gru_states(windows))

    def codes_from_gru_states(self, state: np.ndarray) -> np.ndarray:
        """(T, 128) GRU last states -> (T, 112) codes: BN -> ReLU -> Dense."""
        (bn3, q3), (_, d) = self._layers()[5:7]
        h = np.maximum(_batch_norm(state, q3, self.bn_epsilon[bn3]), 0)
        return (h @ d["kernel"] + d["bias"]).astype(np.float32)


@dataclass
class MotionDecoder:
    """The denoising autoencoder's decoder: (T, 112) codes -> (T, 138) normalised motion, tanh(code W2 + b2)."""

    matrix: np.ndarray   # (112, 138) float32
    bias: np.ndarray     # (138,) float32

    @classmethod
    def from_checkpoint(cls, path: str | pathlib.Path) -> MotionDecoder:
        tensors = read_tf1_checkpoint(path)
        try:
            matrix = tensors["AE_Variables/Variables/matrix2"]
            bias = tensors["AE_Variables/Variables/bias2"]
        except KeyError as exc:
            raise DemoModelError(f"{path}: checkpoint has no decoder tensor {exc.args[0]!r} "
                                 f"(found {sorted(tensors)})") from None
        if matrix.shape != (LATENT_DIM, MOTION_DIM) or bias.shape != (MOTION_DIM,):
            raise DemoModelError(f"{path}: decoder shapes {matrix.shape}, {bias.shape}; "
                                 f"expected ({LATENT_DIM}, {MOTION_DIM}), ({MOTION_DIM},)")
        return cls(matrix=matrix, bias=bias)

    def __call__(self, codes: np.ndarray, *, keep_prob: float = 1.0,
                 rng: np.random.Generator | None = None) -> np.ndarray:
        z = np.asarray(codes, dtype=np.float32)
        if keep_prob < 1.0:
            # TF1 dropout: keep each value with probability keep_prob and scale kept values by 1/keep_prob.
            if rng is None:
                raise ValueError("keep_prob < 1 needs a seeded rng")
            kept = rng.random(z.shape) < keep_prob
            z = np.where(kept, z / np.float32(keep_prob), np.float32(0)).astype(np.float32)
        return np.tanh(z @ self.matrix + self.bias).astype(np.float32)


@dataclass
class Aud2Repr2PoseDemo:
    """The whole published demo model: speech windows -> 46 points x 3 at 20 fps (centimetres, y up)."""

    encoder: SpeechEncoder
    decoder: MotionDecoder
    max_val: np.ndarray    # (138,) float64
    mean_pose: np.ndarray  # (138,) float64

    @classmethod
    def from_folder(cls, folder: str | pathlib.Path) -> Aud2Repr2PoseDemo:
        """Load from a folder laid out as the demo repository's ``models/`` (or the test copy): the files
        ``Model_MFCC_Pros_Best.hdf5``, ``DAE_checkpoints/``, ``max_val.npy`` and ``mean_pose.npy``."""
        folder = pathlib.Path(folder)
        needed = ["Model_MFCC_Pros_Best.hdf5", "DAE_checkpoints", "max_val.npy", "mean_pose.npy"]
        missing = [n for n in needed if not (folder / n).exists()]
        if missing:
            raise DemoModelError(f"{folder}: the Aud2Repr2Pose demo model folder lacks {', '.join(missing)} "
                                 f"(expected the demo repository's models/ files: {', '.join(needed)})")
        norms = []
        for name in ("max_val.npy", "mean_pose.npy"):
            try:
                arr = np.load(folder / name, allow_pickle=False).astype(np.float64)
            except (OSError, ValueError) as exc:
                raise DemoModelError(f"{folder / name}: not a numpy array file ({exc})") from None
            if arr.shape != (MOTION_DIM,):
                raise DemoModelError(f"{folder / name}: shape {arr.shape}, expected ({MOTION_DIM},)")
            norms.append(arr)
        return cls(encoder=SpeechEncoder.from_hdf5(folder / "Model_MFCC_Pros_Best.hdf5"),
                   decoder=MotionDecoder.from_checkpoint(folder / "DAE_checkpoints"),
                   max_val=norms[0], mean_pose=norms[1])

    def decode(self, codes: np.ndarray, *, keep_prob: float = 1.0, seed: int | None = None,
               drop_tail: bool = True, smooth: bool = True) -> np.ndarray:
        """(T, 112) codes -> (T', 138) float64 points; T' = T - T mod 8 when ``drop_tail`` (as the original)."""
        codes = np.asarray(codes)
        if drop_tail:
            codes = codes[: len(codes) - len(codes) % DECODE_BATCH]
        rng = np.random.default_rng(seed) if keep_prob < 1.0 else None
        if keep_prob < 1.0 and seed is None:
            raise ValueError("a stochastic decode (keep_prob < 1) needs a seed")
        normalised = self.decoder(codes, keep_prob=keep_prob, rng=rng)
        motion = normalised.astype(np.float64) * (self.max_val + 1e-15) + self.mean_pose
        if smooth and len(motion) >= SAVGOL_WINDOW:
            motion = savgol_filter(motion, SAVGOL_WINDOW, SAVGOL_ORDER, axis=0, mode="interp")
        return motion

    def __call__(self, windows: np.ndarray, **decode_options: object) -> np.ndarray:
        """(T, 61, 30) speech windows -> (T', 46, 3) points (cm, y up, hips at the origin) at 20 fps."""
        motion = self.decode(self.encoder(windows), **decode_options)  # type: ignore[arg-type]
        return motion.reshape(len(motion), len(POINT_NAMES), 3)
