"""The options of ``aud2pose``, ``aud2motion`` and ``aud2repr2pose``, declared once
(:mod:`evalsuite.generators.options`): one list with the help all three share, and per system the defaults
that differ (from :data:`~evalsuite.generators.aud2repr2pose.systems.SYSTEMS`) and the paper's values. The
plug-ins' ``_settings()`` and ``spec.config`` and the presets table derive from them. Without torch."""
from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from evalsuite.generators.aud2repr2pose.systems import SYSTEMS
from evalsuite.generators.options import Option, Options
from evalsuite.generators.scaling import DEFAULT_FLOOR, FLOOR_OPTION
from evalsuite.generators.schedules import SCHEDULES

__all__ = ["OPTIONS", "WINDOWED_BATCH"]

WINDOWED_BATCH = 2056  # windows per batch: the paper's, and the default of the windowed form
K = "Kucherenko et al. 2021 (IJHCI)"

# in the presets table's order (the rows of Aud2Pose's and Aud2Repr2Pose's tables), then the rest
_SHARED = Options("aud2", (
    Option("form", "choice", "sequence", "sequence (default; a CPU deviation: one GRU pass per 100-frame chunk) or "
           "windowed (the paper's 61-frame window per output frame)", choices=("sequence", "windowed"),
           allowed="sequence, windowed", paper="windowed",
           source=f"{K} §3.2: one 61-frame window (30 either side) per output frame"),
    Option("width", "int", 64, "units of the dense and GRU layers (default 64; paper 256)", allowed=">= 1",
           paper=256, source=f"{K} §4.3: dense and GRU layers of 256"),
    Option("past_frames", "int", 1, "sequence form: each frame's speech features with those of the frames before "
           "it, this many in all (default 5 for aud2motion: the frame and the 0.25 s before it; 1 for aud2pose and "
           "aud2repr2pose: the frame alone, the paper's)", allowed=">= 1"),
    Option("batch_size", "int", 16, "windows or chunks per batch (default 16 chunks / 2056 windows)",
           allowed=">= 1", paper=WINDOWED_BATCH, source=f"{K} §4.3: 2056 (windows)",
           code="chunks of 100 frames in the sequence form"),
    Option("epochs", "int", 300, "most epochs of the speech network (default 300)", allowed=">= 1", paper=120,
           source=f"{K} §4.3: 120 epochs", code="EPOCHS argument"),
    Option("patience", "int", 50, "stop after this many epochs without a better validation loss (default 50); the "
           "best validation epoch's weights are kept", allowed=">= 1", paper=120,
           source=f"{K} §4.3: a fixed number of epochs (patience = epochs: no early stop)"),
    Option("ema", "fraction", 0.99, "decay of an exponential moving average of the weights per optimiser step "
           "(default 0.99; 0: off, the paper's); the average is what is validated and kept", allowed="[0, 1)",
           paper=0.0, source=f"{K}: no weight average"),
    Option("scale_floor", "fraction", DEFAULT_FLOOR, FLOOR_OPTION, allowed="[0, 1)", paper=0.0,
           source=f"{K} §4.2: mean 0, max-abs 1 per dimension"),
    Option("representation", "choice", "expmap", "expmap (default: joint rotations, BVH, as the GENEA 2020 BA "
           "baseline) or positions (hip-centred joint positions, as the IVA'19 paper)",
           choices=("expmap", "positions"), allowed="expmap, positions", paper="positions",
           source=f"{K} §4.1: 3D joint positions", code="expmap on the GENEA_2020 branch"),
    Option("learning_rate", "float", 1e-3, "Adam (default 1e-3, the paper's)", allowed="> 0",
           source=f"{K} §4.3: Adam 0.001"),
    Option("velocity_target", "bool", False, "the pose's frame difference as a second training target, discarded "
           "at generation (default: on for aud2pose, off for aud2motion and aud2repr2pose, as the paper)",
           allowed="true, false"),
    Option("dae_epochs", "int", 20, "autoencoder epochs (default 20)", allowed=">= 1"),
    Option("code_dim", "int", 40, "aud2repr2pose: size of the motion representation (default 40, as GENEA 2020 BA)",
           allowed=">= 1"),
    Option("features", "choice", "mfcc", "mfcc (default: 26 MFCC, mfcc_kucherenko) or mfcc+prosody (MFCC + pitch "
           "and energy)", choices=("mfcc", "mfcc+prosody")),
    Option("lr_schedule", "choice", "constant", "constant (default, the paper's) or cosine (Adam's rate decays to "
           "1 % by epoch 'epochs')", choices=SCHEDULES),
    Option("threads", "int", 1, "torch threads (default 1)"),
    Option("dae_inputs", "choice", "poses+velocities", "aud2repr2pose: poses+velocities (default: the autoencoder "
           "codes each pose with its frame difference, as the paper's Japanese-data setup) or poses (the paper's "
           "English-data setup)", choices=("poses+velocities", "poses")),
    Option("validate_on", "choice", "poses", "poses (default: MSE of the normalised poses over whole validation "
           "segments, the representation decoded) or targets (the training loss on validation chunks: the "
           "representation for aud2repr2pose)", choices=("poses", "targets")),
))

_NOT_IN_TABLE: dict[str, Any] = {"source": "", "code": ""}


def _system(system: str, changes: Mapping[str, Mapping[str, Any]]) -> Options:
    """The shared options with ``system``'s defaults (from SYSTEMS) and its paper column (``changes``)."""
    net = SYSTEMS[system][1]
    own = {"velocity_target": {"default": net["velocity_target"]}, "past_frames": {"default": net.get("past_frames", 1)}}
    merged = {k: {**own.get(k, {}), **changes.get(k, {})} for k in (*own, *changes)}
    return _SHARED.revised(system, merged)


OPTIONS: dict[str, Options] = {
    "aud2pose": _system("aud2pose", {"velocity_target": {"source": f"{K} §3.2: pose and velocity as targets"}}),
    "aud2repr2pose": _system("aud2repr2pose", {"dae_epochs": {"source": f"{K} §4.3: 20 epochs"}, "code_dim": {
        "source": f"{K} §5.1: 325 (Japanese data, 384 inputs), 118 (English, 138 inputs); 40 for the 90 inputs here, "
                  "as the GENEA 2020 baseline"}}),
    "aud2motion": _system("aud2motion", {  # causal and sequence-level: no form, its own epochs
        "form": _NOT_IN_TABLE, "batch_size": _NOT_IN_TABLE, "learning_rate": _NOT_IN_TABLE,
        "width": {"source": f"{K} §4.3: 256"},
        "past_frames": {"paper": 1, "source": f"{K} §3.2: one frame of speech per GRU step"},
        "epochs": {"paper": 500, "source": f"{K} §4.3: 500 epochs", "code": ""},
        "patience": {"paper": 500, "source": f"{K} §4.3: a fixed number of epochs"},
        "scale_floor": {"source": f"{K} §4.2: mean 0, max-abs 1"},
        "representation": {"code": ""}}),
}
