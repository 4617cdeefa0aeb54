"""What the Gesture2Vec re-implementation changes from the paper (torch-free, so that the plug-in's spec can list
it without importing torch)."""

__all__ = ["DEVIATIONS"]

DEVIATIONS = (
    "Word embeddings from an offline model installed with evalsuite (or a user-supplied path) instead of "
    "FastText crawl-300d-2M-subword; no GPT-3 embeddings (the original repository calls a retired paid API).",
    "Each word's position in its window (its start as a fraction of the window) is appended to its embedding, "
    "so that the translation model can place a gesture in time within a window.",
    "Decoding is generative (codes -> VQ-DVAE decoder -> frame decoder) by default; the original repository's "
    "retrieval decoding (a random training clip of the predicted code) is an option flagged in provenance.",
    "The translation decoder reads, beside its attention context, the mean (embedding, position) of the words "
    "starting in the chunk it emits and in the chunk before (aligned=true, default; aligned=false is the paper's "
    "attention alone): a monotonic alignment that small corpora do not learn from attention alone.",
    "The VQ-DVAE decoder is by default a bidirectional GRU reading the code alone; the paper's conditioned decoder "
    "(fed its own last frame) is conditioned_decoder=true (the paper preset), and it runs free from the frame "
    "before the chunk where the original code feeds the ground truth for its first frames.",
    "Rotation representation: the corpus skeleton's local rotations as 3x3 matrices (as the paper) of the "
    "modelled joints; sizes are options and the CPU preset shrinks them.",
)
