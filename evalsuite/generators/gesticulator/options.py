"""The options of ``gesticulator``, declared once (:mod:`evalsuite.generators.options`): the plug-in's
``_settings()`` and ``spec.config`` and the presets table derive from them. Without torch."""
from __future__ import annotations

from typing import Any

from evalsuite.generators.options import Option, Options
from evalsuite.generators.schedules import SCHEDULES

__all__ = ["OPTIONS", "SIZES"]

# sizes: the paper's (124 / 612, 256 / FiLM 512) and a CPU preset
SIZES: dict[str, dict[str, Any]] = {"paper": {"frame_dim": 124, "hidden": (612, 256), "film_dim": 512},
                                    "cpu": {"frame_dim": 32, "hidden": (256, 128), "film_dim": 256}}
G = "Kucherenko et al. 2020 (Gesticulator)"

OPTIONS = Options("gesticulator", (
    # the presets table's rows first, in its order
    Option("size", "choice", "cpu", "cpu (default) or paper (124 / 612, 256 / 512 units)", choices=tuple(SIZES),
           allowed="cpu, paper", paper="paper", source=f"{G} §5.4: frame encoding 124, layers 612, 256, FiLM 512"),
    Option("velocity_weight", "float", 7.0, "alpha of the paper's loss, MSE(pose) + alpha MSE(velocity) (default 7; "
           "the paper's 0.6; 0 is its 'no velocity penalty' ablation)",
           allowed=">= 0", paper=0.6, source=f"{G} §5.2 eq. (2): alpha = 0.6"),
    Option("text_dropout", "fraction", 0.8, "in training, each value of the text features (word vector and timing) "
           "is dropped at the input with this probability (default 0.8; not in the paper: 0)",
           allowed="[0, 1)", paper=0.0, source=f"{G}: no input text dropout"),
    Option("dropout", "float", 0.1, "dropout of the speech layers (default 0.1; the paper's 0.2)",
           allowed="[0, 1)", paper=0.2, source=f"{G} §5.4: dropout 0.2 on each layer"),
    Option("weight_decay", "float", 1e-3, "Adam weight decay (default 1e-3; the paper: none)",
           allowed=">= 0", paper=0.0, source=f"{G} §5.4: none"),
    Option("learning_rate", "float", 1e-3, "Adam (default 1e-3; paper 1e-4)",
           allowed="> 0", paper=1e-4, source=f"{G} §5.4: 0.0001"),
    Option("lr_schedule", "choice", "cosine", "cosine (default: decays to 1 % of learning_rate by the last epoch) or "
           "constant (the paper's)", choices=SCHEDULES, allowed="constant, cosine", paper="constant",
           source=f"{G} §5.4: a constant rate"),
    Option("epochs", "int", 90, "epochs of the compressed schedule (default 90)", allowed=">= 5", paper=95,
           source=f"{G} §5.3: 7 pretraining epochs, 3 teacher-forcing epochs, then free (the paper gives no total: "
                  "85 free epochs is evalsuite's choice)"),
    Option("words", "str", "minilm-static", "word vectors (default 'minilm-static': all-MiniLM-L6-v2's context-free "
           "vectors); 'minilm' (contextual, as the paper's BERT), 'hash' (no model), 'bert:FOLDER', "
           "'fasttext:FILE.vec'", allowed="minilm, minilm-static, hash, bert:DIR, fasttext:FILE", paper="minilm",
           source=f"{G} §5.1: BERT-base, contextual (offline: contextual MiniLM; words=bert:FOLDER for BERT itself)",
           code="bert-base-cased"),
    Option("frame_layers", "int_choice", 1, "layers of the per-frame speech encoder (default 1; 2: as the original "
           "code, input -> 2 x frame encoding -> frame encoding)", choices=("1", "2"), allowed="1, 2",
           source=f"{G} §5.2: one frame encoder", code="2 layers (248 -> 124)"),
    Option("film_identity", "bool", False, "false (default: FiLM as the paper's equation, x * alpha + beta, with "
           "alpha and beta from a two-layer pose encoder fed dropped-out poses); true: as the original code, "
           "x * (1 + alpha) + beta from one zero-initialised layer with dropout after it (identity at the start of "
           "training)", allowed="true, false", source=f"{G} eq. (1): x * alpha + beta", code="x * (1 + alpha) + beta"),
    Option("prev_pose_dropout", "float", 0.8, "dropout of the previous poses before FiLM (default 0.8, the paper's)",
           allowed="[0, 1)", source=f"{G} §5.4: 0.8"),
    Option("batch_size", "int", 64, "sequences per batch (default 64)", allowed=">= 1", source=f"{G} §5.4: 64"),
    # the same in both presets
    Option("inputs", "choice", "audio+text", "audio+text (default), audio or text (the paper's ablations)",
           choices=("audio+text", "audio", "text")),
    Option("autoregressive", "bool", True, "true (default); false: the paper's 'no autoregression' ablation"),
    Option("film", "bool", True, "true (default); false: concatenation instead of FiLM (ablation)"),
    Option("threads", "int", 1, "torch threads (default 1)"),
    Option("patience", "optional_int", None, "stop after this many epochs without a better validation loss (default "
           "none); the best validation epoch's weights are kept"),
    Option("past", "int", 10, "speech frames before the current one (default 10 = 0.5 s, the paper's)"),
    Option("future", "int", 20, "speech frames after the current one (default 20 = 1 s, the paper's)"),
    Option("ema", "fraction", 0.0, "decay of an exponential moving average of the weights per step (default 0: off); "
           "the average is what is validated and kept"),
    Option("scale_floor", "fraction", 0.0, "a pose dimension's standard deviation is taken as at least this fraction "
           "of the widest dimension's (default 0, the paper's unit variance; 0.1 scales idle sway as the other "
           "re-implementations do, which on the synthetic speaker raised the held-out pose error from 0.52 to 0.62 x "
           "mean pose)"),
    Option("zero_audio", "bool", False, "at generation: replace the audio features by their training mean (shows "
           "what the text path alone does)", settings=False),
))
