"""The options of ``ferstl-mogan``, declared once (:mod:`evalsuite.generators.options`): the plug-in's
``_settings()`` and ``spec.config`` and the presets table derive from them. Without torch."""
from __future__ import annotations

from evalsuite.generators.options import Option, Options
from evalsuite.generators.scaling import DEFAULT_FLOOR, FLOOR_OPTION

__all__ = ["OPTIONS", "ABLATIONS", "DISCRIMINATORS"]

DISCRIMINATORS = ("phase", "realism", "minibatch", "displacement")
ABLATIONS = {"none": DISCRIMINATORS, "mse_only": ("mse_only",),
             **{f"no_{d}": tuple(x for x in DISCRIMINATORS if x != d) for d in DISCRIMINATORS}}
F = "Ferstl et al. 2019"

OPTIONS = Options("ferstl-mogan", (
    # the presets table's rows first, in its order
    Option("width", "int", 128, "generator units (default 128; paper 256)", allowed=">= 1", paper=256,
           source=f"{F} §5.1: feed-forward 256, GRU 256"),
    Option("noise_dim", "int", 8, "noise channels (default 8)", allowed=">= 0", paper=0,
           source=f"{F} §5.1: speech is the only input"),
    Option("scale_floor", "fraction", DEFAULT_FLOOR, FLOOR_OPTION, allowed="[0, 1)", paper=0.0,
           source=f"{F} §3.1: zero mean, unit variance"),
    Option("ablation", "choice", "none", "none (default), no_phase, no_realism, no_minibatch, no_displacement or "
           "mse_only (the paper's Figure 1)", choices=tuple(ABLATIONS), allowed="none, mse_only, ...",
           source=f"{F} §7.1: phase, realism, minibatch and displacement discriminators weighted 2:4:4:1, one MSE "
                  "step per two adversarial steps"),
    # the same in both presets
    Option("phase_labels", "choice", "corpus", "corpus (default: the corpus's per-frame labels when every training "
           "segment has them, else the heuristic labeller) or heuristic", choices=("corpus", "heuristic")),
    Option("discriminator_width", "int", 64, "discriminator units (default 64)"),
    Option("classifier_epochs", "int", 30, "phase classifier epochs (default 30)"),
    Option("pretrain_epochs", "int", 30, "MSE pre-training epochs (default 30)"),
    Option("adversarial_steps", "int", 400, "adversarial steps (default 400)"),
    Option("realism_pretrain_steps", "int", 100, "steps of the realism discriminator's pre-training (default 100)"),
    Option("phase_pretrain_tries", "int", 40, "batches per generator snapshot at most in the phase discriminator's "
           "pre-training (default 40)"),
    Option("batch_size", "int", 16, "sequences of 100 frames per batch (default 16)"),
    Option("learning_rate", "float", 1e-3, "Adam, classifier and pre-training (default 1e-3)"),
    Option("adversarial_learning_rate", "float", 5e-4, "RMSprop: the generator's, and the discriminators' "
           "pre-training (default 5e-4)"),
    Option("discriminator_learning_rate", "float", 1e-4, "RMSprop of the discriminators in adversarial training "
           "(default 1e-4, a fifth of the generator's: at equal rates they won and the motion shrank below the "
           "MSE-only model's)"),
    Option("threads", "int", 1, "torch threads (default 1)"),
))
