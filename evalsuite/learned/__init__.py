"""Learned-feature metrics: FGD, raw-space FGD, NSD and codebook diversity (optional extra).

Needs PyTorch (CPU build, pinned): ``pip install "evalsuite[learned]"``. Nothing else in
evalsuite imports this package, so the rest works without torch; importing it without
torch raises :class:`MissingExtraError`, which is both an :class:`~evalsuite.errors.InputError`
(the CLI prints it without a traceback) and an :class:`ImportError` (the usual
``try: import ... except ImportError`` works).

Modules: :mod:`~evalsuite.learned.network` (the GENEA-compatible convolutional
autoencoder), :mod:`~evalsuite.learned.representation` (positions / bone directions and
windows), :mod:`~evalsuite.learned.modelfile` (the self-describing model file and
:func:`encode_windows`), :mod:`~evalsuite.learned.training`, :mod:`~evalsuite.learned.fgd`,
:mod:`~evalsuite.learned.latent` (NSD, codebook), :mod:`~evalsuite.learned.sanity`,
:mod:`~evalsuite.learned.genea` (importing GENEA checkpoints).
"""
from __future__ import annotations

import importlib
import importlib.util

from evalsuite.errors import InputError

INSTALL_HINT = 'pip install "evalsuite[learned]"'


class MissingExtraError(InputError, ImportError):
    """An optional extra (here: PyTorch) is not installed."""


def _torch_available() -> bool:
    # find_spec does not import torch: `evalsuite --help` (which looks this package up) stays fast.
    try:
        return importlib.util.find_spec("torch") is not None
    except (ImportError, ValueError):  # a blocked or half-removed installation
        return False


if not _torch_available():
    raise MissingExtraError(
        f"the learned metrics (FGD, NSD, codebook) need PyTorch, which is not installed; "
        f"install the extra with: {INSTALL_HINT}")

_LAZY = {"FeatureModel": "evalsuite.learned.modelfile", "encode_windows": "evalsuite.learned.modelfile",
         "load_model": "evalsuite.learned.modelfile", "train_model": "evalsuite.learned.training",
         "score_fgd": "evalsuite.learned.fgd", "score_latent": "evalsuite.learned.latent",
         "check_model": "evalsuite.learned.sanity", "import_checkpoint": "evalsuite.learned.genea"}


def __getattr__(name: str):
    # The public functions load torch on first use, not when the package is imported.
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["INSTALL_HINT", "MissingExtraError", *_LAZY]
