"""Named configurations of the re-implementations: ``cpu-small`` (evalsuite's variant) and ``paper``.

``cpu-small`` is what the plug-ins do with no option: narrower networks, shorter schedules and the regularisation
chosen on the synthetic speaker so that a CPU trains each system in minutes (docs/generators.md). It is
evalsuite's variant, not the published system. ``paper`` gives each system as its paper describes it (widths,
windows, losses and weights, features, schedule); where the paper is silent the original code's value is used and
the table says so. ``evalsuite train --preset NAME`` merges the preset's values under the user's own options
(``--set`` and ``--config`` win), and ``model.json`` / ``generation.json`` name the preset.

Each row of a system's table is one option: its ``cpu-small`` value (the plug-in's default), its ``paper`` value,
where the paper gives it (``source``), the original code's value where it differs (``code``), and the allowed
range (``allowed``). A test checks that every ``cpu-small`` value is the plug-in's default.
"""
from __future__ import annotations

import json
import pathlib
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from evalsuite.errors import InputError

__all__ = ["PresetOption", "PRESETS", "DEFAULT_PRESET", "SYSTEM_OPTIONS", "preset_values", "apply_preset",
           "model_preset", "markdown_table"]

PRESETS = ("cpu-small", "paper")
DEFAULT_PRESET = "cpu-small"


@dataclass(frozen=True)
class PresetOption:
    """One option of one system under both presets."""

    name: str
    cpu_small: Any       # evalsuite's variant: the plug-in's default
    paper: Any           # the paper's value (or the original code's where the paper gives none; see ``source``)
    source: str          # where the paper (or code) gives it
    allowed: str = ""    # the range or the choices
    code: str = ""       # the original code's value, where it differs from the paper's

    def value(self, preset: str) -> Any:
        return self.cpu_small if preset == "cpu-small" else self.paper


G = "Kucherenko et al. 2020 (Gesticulator)"
K = "Kucherenko et al. 2021 (IJHCI)"
Y = "Yazdian et al. 2022 (Gesture2Vec)"
F = "Ferstl et al. 2019"

_GESTICULATOR = (
    PresetOption("size", "cpu", "paper", f"{G} §5.4: frame encoding 124, layers 612, 256, FiLM 512", "cpu, paper"),
    PresetOption("velocity_weight", 7.0, 0.6, f"{G} §5.2 eq. (2): alpha = 0.6", ">= 0"),
    PresetOption("text_dropout", 0.8, 0.0, f"{G}: no input text dropout", "[0, 1)"),
    PresetOption("dropout", 0.1, 0.2, f"{G} §5.4: dropout 0.2 on each layer", "[0, 1)"),
    PresetOption("weight_decay", 1e-3, 0.0, f"{G} §5.4: none", ">= 0"),
    PresetOption("learning_rate", 1e-3, 1e-4, f"{G} §5.4: 0.0001", "> 0"),
    PresetOption("lr_schedule", "cosine", "constant", f"{G} §5.4: a constant rate", "constant, cosine"),
    PresetOption("epochs", 90, 95, f"{G} §5.3: 7 pretraining epochs, 3 teacher-forcing epochs, then free "
                 "(the paper gives no total: 85 free epochs is evalsuite's choice)", ">= 5"),
    PresetOption("words", "minilm-static", "minilm", f"{G} §5.1: BERT-base, contextual (offline: contextual MiniLM; "
                 "words=bert:FOLDER for BERT itself)", "minilm, minilm-static, hash, bert:DIR, fasttext:FILE",
                 code="bert-base-cased"),
    PresetOption("frame_layers", 1, 1, f"{G} §5.2: one frame encoder", "1, 2", code="2 layers (248 -> 124)"),
    PresetOption("film_identity", False, False, f"{G} eq. (1): x * alpha + beta", "true, false",
                 code="x * (1 + alpha) + beta"),
    PresetOption("prev_pose_dropout", 0.8, 0.8, f"{G} §5.4: 0.8", "[0, 1)"),
    PresetOption("batch_size", 64, 64, f"{G} §5.4: 64", ">= 1"),
)

_AUD2_COMMON = (
    PresetOption("form", "sequence", "windowed", f"{K} §3.2: one 61-frame window (30 either side) per output frame",
                 "sequence, windowed"),
    PresetOption("width", 64, 256, f"{K} §4.3: dense and GRU layers of 256", ">= 1"),
    PresetOption("batch_size", 16, 2056, f"{K} §4.3: 2056 (windows)", ">= 1", code="chunks of 100 frames in the sequence form"),
    PresetOption("epochs", 300, 120, f"{K} §4.3: 120 epochs", ">= 1", code="EPOCHS argument"),
    PresetOption("patience", 50, 120, f"{K} §4.3: a fixed number of epochs (patience = epochs: no early stop)",
                 ">= 1"),
    PresetOption("ema", 0.99, 0.0, f"{K}: no weight average", "[0, 1)"),
    PresetOption("scale_floor", 0.1, 0.0, f"{K} §4.2: mean 0, max-abs 1 per dimension", "[0, 1)"),
    PresetOption("representation", "expmap", "positions", f"{K} §4.1: 3D joint positions", "expmap, positions",
                 code="expmap on the GENEA_2020 branch"),
    PresetOption("learning_rate", 1e-3, 1e-3, f"{K} §4.3: Adam 0.001", "> 0"),
)
_AUD2POSE = (*_AUD2_COMMON,
             PresetOption("velocity_target", True, True, f"{K} §3.2: pose and velocity as targets", "true, false"))
_AUD2REPR2POSE = (*_AUD2_COMMON,
                  PresetOption("dae_epochs", 20, 20, f"{K} §4.3: 20 epochs", ">= 1"),
                  PresetOption("code_dim", 40, 40, f"{K} §5.1: 325 (Japanese data, 384 inputs), 118 (English, 138 "
                               "inputs); 40 for the 90 inputs here, as the GENEA 2020 baseline", ">= 1"))
_AUD2MOTION = (
    PresetOption("width", 64, 256, f"{K} §4.3: 256", ">= 1"),
    PresetOption("past_frames", 5, 1, f"{K} §3.2: one frame of speech per GRU step", ">= 1"),
    PresetOption("epochs", 300, 500, f"{K} §4.3: 500 epochs", ">= 1"),
    PresetOption("patience", 50, 500, f"{K} §4.3: a fixed number of epochs", ">= 1"),
    PresetOption("ema", 0.99, 0.0, f"{K}: no weight average", "[0, 1)"),
    PresetOption("scale_floor", 0.1, 0.0, f"{K} §4.2: mean 0, max-abs 1", "[0, 1)"),
    PresetOption("representation", "expmap", "positions", f"{K} §4.1: 3D joint positions", "expmap, positions"),
)

_GESTURE2VEC = (
    PresetOption("size", "cpu", "paper", f"{Y} §4.2: 2-layer BiGRU encoder and decoder of 200 units", "cpu, paper"),
    PresetOption("aligned", True, False, f"{Y} §3.3: attention alone", "true, false"),
    PresetOption("weakened_decoder", False, True, f"{Y} §4.3: the decoder frozen while the encoder and codebook "
                 "learn, then trained alone", "true, false", code="autoencoder_fixed_weight: False in the configs"),
    PresetOption("dae_epochs", 10, 20, f"{Y} §4.1: 20 epochs", ">= 1"),
    PresetOption("vq_epochs", 15, 20, f"{Y} §4.3: 20 epochs with the decoder weakened", ">= 1", code="3000"),
    PresetOption("vq_decoder_epochs", 10, 20, f"{Y} §4.3: then the decoder alone for 20 epochs", ">= 0"),
    PresetOption("translation_epochs", 60, 250, "not in the paper: the original repository's 250", ">= 1"),
    PresetOption("codebook", 300, 300, f"{Y} §4.2: K = 300", ">= 2", code="100 / 400 / 512"),
    PresetOption("reset_dead_codes", True, False, f"{Y}: no code restarts", "true, false"),
    PresetOption("scale_floor", 0.1, 0.0, f"{Y} §4.1: mean 0, max-abs 1", "[0, 1)"),
)

_FERSTL = (
    PresetOption("width", 128, 256, f"{F} §5.1: feed-forward 256, GRU 256", ">= 1"),
    PresetOption("noise_dim", 8, 0, f"{F} §5.1: speech is the only input", ">= 0"),
    PresetOption("scale_floor", 0.1, 0.0, f"{F} §3.1: zero mean, unit variance", "[0, 1)"),
    PresetOption("ablation", "none", "none", f"{F} §7.1: phase, realism, minibatch and displacement "
                 "discriminators weighted 2:4:4:1, one MSE step per two adversarial steps", "none, mse_only, ..."),
)

SYSTEM_OPTIONS: dict[str, tuple[PresetOption, ...]] = {
    "gesticulator": _GESTICULATOR, "aud2pose": _AUD2POSE, "aud2repr2pose": _AUD2REPR2POSE,
    "aud2motion": _AUD2MOTION, "gesture2vec": _GESTURE2VEC, "ferstl-mogan": _FERSTL,
}


def preset_values(generator: str, preset: str) -> dict[str, Any]:
    """The options ``preset`` sets for ``generator``: nothing for ``cpu-small`` (the plug-in's defaults are that
    preset), the table's ``paper`` column for ``paper``."""
    if preset not in PRESETS:
        raise InputError(f"unknown preset {preset!r}; presets: {', '.join(PRESETS)}", field="--preset")
    if preset == DEFAULT_PRESET:
        return {}
    if generator not in SYSTEM_OPTIONS:
        raise InputError(f"{generator} has no '{preset}' preset (presets exist for "
                         f"{', '.join(SYSTEM_OPTIONS)})", field="--preset")
    return {o.name: o.paper for o in SYSTEM_OPTIONS[generator]}


def apply_preset(generator: str, preset: str, config: Mapping[str, Any]) -> dict[str, Any]:
    """``config`` over the preset's values (the user's options win)."""
    return {**preset_values(generator, preset), **dict(config)}


def model_preset(model_dir: str | pathlib.Path | None) -> str | None:
    """The preset a model folder was trained with (``model.json``), or None (no folder, or not trained here)."""
    if model_dir is None:
        return None
    try:
        record = json.loads((pathlib.Path(model_dir) / "model.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return record.get("preset") if isinstance(record, dict) else None


def markdown_table(generator: str) -> str:
    """The docs' table of one system: option, the paper's value (with its source), the original code's where it
    differs, and each preset's."""
    lines = ["| option | paper (source) | original code | `paper` | `cpu-small` |", "|---|---|---|---|---|"]
    for o in SYSTEM_OPTIONS[generator]:
        lines.append(f"| `{o.name}` | {o.source} | {o.code or 'same'} | {o.paper} | {o.cpu_small} |")
    return "\n".join(lines)
