"""The options of ``gesture2vec``, declared once (:mod:`evalsuite.generators.options`): the plug-in's
``_settings()`` and ``spec.config`` and the presets table derive from them. Without torch."""
from __future__ import annotations

from evalsuite.generators.options import Option, Options
from evalsuite.generators.scaling import DEFAULT_FLOOR, FLOOR_OPTION

__all__ = ["OPTIONS", "SIZES"]

# the paper's sizes (§4) and a CPU preset (fewer recurrent units and layers)
SIZES: dict[str, dict[str, int]] = {
    "paper": {"latent_dim": 40, "vq_hidden": 200, "vq_layers": 2, "text_hidden": 200},
    "cpu": {"latent_dim": 40, "vq_hidden": 96, "vq_layers": 1, "text_hidden": 96},
}
Y = "Yazdian et al. 2022 (Gesture2Vec)"

OPTIONS = Options("gesture2vec", (
    # the presets table's rows first, in its order
    Option("size", "choice", "cpu", "cpu (default: 96 units, 1 layer) or paper (200 units, 2 layers)",
           choices=tuple(SIZES), allowed="cpu, paper", paper="paper",
           source=f"{Y} §4.2: 2-layer BiGRU encoder and decoder of 200 units"),
    Option("aligned", "bool", True, "true (default): the translation decoder also reads the words of its chunk and "
           "the one before; false: attention alone (the paper's)", allowed="true, false", paper=False,
           source=f"{Y} §3.3: attention alone"),
    Option("weakened_decoder", "bool", False, "false (default): the VQ-DVAE's first stage trains encoder, codebook "
           "and decoder together; true: the decoder is frozen in that stage (the paper's weakened decoder, §4.3), "
           "then trained alone in the second", allowed="true, false", paper=True,
           source=f"{Y} §4.3: the decoder frozen while the encoder and codebook learn, then trained alone",
           code="autoencoder_fixed_weight: False in the configs"),
    Option("conditioned_decoder", "bool", False, "false (default): the VQ-DVAE decoder is a bidirectional GRU that "
           "reads the code alone; true: a GRU fed the code and its own last output frame at every step, starting "
           "from the frame before the chunk (the paper's conditioned decoder, §4.3; at generation each chunk starts "
           "from the last frame of the one before)", allowed="true, false", paper=True,
           source=f"{Y} §4.3: the decoder conditioned on its last output (autoencoder_conditioned in the code)"),
    Option("dae_epochs", "int", 10, "frame autoencoder epochs (default 10; paper 20)", allowed=">= 1", paper=20,
           source=f"{Y} §4.1: 20 epochs"),
    Option("vq_epochs", "int", 15, "VQ-DVAE epochs (default 15; paper 20)", allowed=">= 1", paper=20,
           source=f"{Y} §4.3: 20 epochs with the decoder weakened", code="3000"),
    Option("vq_decoder_epochs", "int", 10, "VQ-DVAE decoder-only epochs (default 10; paper 20)", allowed=">= 0",
           paper=20, source=f"{Y} §4.3: then the decoder alone for 20 epochs"),
    Option("translation_epochs", "int", 60, "translation epochs (default 60; repository 250)", allowed=">= 1",
           paper=250, source="not in the paper: the original repository's 250"),
    Option("codebook", "int", 300, "K, codes in the codebook (default 300, the paper's)", minimum=1,
           allowed=">= 2", source=f"{Y} §4.2: K = 300", code="100 / 400 / 512"),
    Option("reset_dead_codes", "bool", True, "true (default) or false: restart unused codes in VQ-DVAE training",
           allowed="true, false", paper=False, source=f"{Y}: no code restarts"),
    Option("scale_floor", "fraction", DEFAULT_FLOOR, FLOOR_OPTION, allowed="[0, 1)", paper=0.0,
           source=f"{Y} §4.1: mean 0, max-abs 1"),
    # the same in both presets
    Option("words", "str", "minilm-static", "word vectors: 'minilm-static' (default: all-MiniLM-L6-v2 static word "
           "vectors, offline from the text extra), 'minilm' (contextual), 'hash' (no model, no meaning), "
           "'bert:FOLDER', 'fasttext:FILE.vec' (the paper's FastText crawl-300d-2M vectors in .vec form)"),
    Option("decoding", "str", "generative", "generative (default: codes -> VQ-DVAE decoder -> frame decoder, "
           "deterministic) or retrieval (the original repository's: a random training clip of each code, seeded; "
           "flagged in generation.json)", choices=("generative", "retrieval")),
    Option("temperature", "float", 0.0, "sampling temperature of the translation decoder (default 0: greedy)",
           minimum=0.0),
    Option("chunk", "int", 30, "frames per VQ-DVAE chunk (default 30, the paper's)", minimum=1),
    Option("stride", "int", 10, "frames between training chunks (default 10, the paper's)", minimum=1),
    Option("batch_size", "int", 128, "chunks / windows per batch (default 128, the repository's)", minimum=1),
    Option("learning_rate", "float", 1e-3, "Adam, all stages (default 1e-3, the paper's for the DAE)"),
    Option("threads", "int", 1, "torch threads (default 1)", minimum=1),
))
