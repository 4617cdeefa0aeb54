"""Where the re-implementations compute: ``--device auto|cpu|cuda|mps`` and ``--amp`` on ``evalsuite train`` and
``evalsuite generate``.

``auto`` is ``cuda`` when torch sees a CUDA GPU, else ``mps`` (Apple GPUs) when available, else ``cpu``. Asking for
a device torch cannot use is a one-line error naming the device and what torch reports. On ``cpu`` nothing changes:
the same code, the same weights as before the option existed. On a GPU the block runs under :func:`use_device`:

* torch's default device is the GPU, so networks and the tensors made by factory functions are created there;
* a :class:`~torch.overrides.TorchFunctionMode` moves CPU tensors (arrays turned into tensors with
  ``torch.from_numpy``) to the GPU when an operation mixes them with GPU tensors, and ``Tensor.numpy()`` copies
  back to the CPU first; random numbers drawn with a seeded CPU ``torch.Generator`` (the samples of
  ``ferstl-mogan`` and ``gesture2vec``) are drawn on the CPU, so they are the CPU's numbers;
* ``--amp`` (CUDA only) runs the block under ``torch.autocast`` with bfloat16 (no loss scaling needed).

No code path assumes CUDA: the re-implementations' own code is the same on every device. GPU kernels are not
bitwise deterministic, so on a GPU the runner's determinism check compares within a tolerance
(:data:`GPU_TOLERANCE`) and says so.
"""
from __future__ import annotations

import contextlib
import contextvars
from collections.abc import Iterator
from typing import Any

from evalsuite.errors import InputError

__all__ = ["DEVICES", "resolve_device", "use_device", "current_device", "GPU_TOLERANCE"]

DEVICES = ("auto", "cpu", "cuda", "mps")
GPU_TOLERANCE = 1e-3      # relative (to the motion's value range) difference allowed between two GPU runs
_DEVICE: contextvars.ContextVar[str] = contextvars.ContextVar("evalsuite_device", default="cpu")


def _torch() -> Any:
    try:
        import torch
    except ImportError:
        raise InputError('the re-implemented generators need PyTorch: pip install "evalsuite[learned]"',
                         field="--device") from None
    return torch


def resolve_device(name: str) -> str:
    """``auto`` -> ``cuda``/``mps``/``cpu``; an unavailable device is an :class:`InputError`."""
    if name not in DEVICES:
        raise InputError(f"unknown device {name!r}; expected one of {', '.join(DEVICES)}", field="--device")
    if name == "cpu":
        return "cpu"
    torch = _torch()
    cuda = bool(torch.cuda.is_available())
    mps = bool(getattr(torch.backends, "mps", None) and torch.backends.mps.is_available())
    if name == "auto":
        return "cuda" if cuda else "mps" if mps else "cpu"
    if name == "cuda" and not cuda:
        build = torch.version.cuda or "none (a CPU-only build)"
        raise InputError(f"--device cuda: torch {torch.__version__} sees no CUDA GPU (torch.cuda.is_available() "
                         f"is False; built with CUDA {build}); use --device cpu or --device auto",
                         field="--device")
    if name == "mps" and not mps:
        raise InputError(f"--device mps: torch {torch.__version__} sees no Apple GPU "
                         f"(torch.backends.mps.is_available() is False); use --device cpu or --device auto",
                         field="--device")
    return name


def current_device() -> str:
    """The device of the block in progress (``cpu`` outside :func:`use_device`)."""
    return _DEVICE.get()


def _mode_class(torch: Any) -> Any:
    from torch.overrides import TorchFunctionMode

    class _OnDevice(TorchFunctionMode):
        """Moves CPU tensors to ``device`` where an operation needs them there (module doc)."""

        def __init__(self, device: str):
            super().__init__()
            self.device = torch.device(device)

        def _move(self, x: Any, to: Any) -> Any:
            if isinstance(x, torch.Tensor):
                return x.to(to) if x.device != to else x
            if isinstance(x, (list, tuple)):
                return type(x)(self._move(v, to) for v in x)
            return x

        def __torch_function__(self, func: Any, types: Any, args: Any = (), kwargs: Any = None) -> Any:
            kwargs = dict(kwargs or {})
            if func is torch.Tensor.numpy:
                return args[0].detach().cpu().numpy()
            if func is torch.Tensor.__array__:            # np.asarray(tensor)
                return args[0].detach().cpu().__array__(*args[1:], **kwargs)
            if func in (torch.Tensor.to, torch.Tensor.cpu, torch.Tensor.cuda, torch.Tensor.tolist,
                        torch.Tensor.item, torch.from_numpy):
                return func(*args, **kwargs)
            gen = kwargs.get("generator")
            if gen is not None and gen.device.type == "cpu":        # seeded CPU numbers, then to the device
                cpu = torch.device("cpu")
                args, kwargs = self._move(args, cpu), {k: self._move(v, cpu) for k, v in kwargs.items()}
                if "device" in kwargs or func in (torch.randn, torch.rand, torch.randint, torch.randperm,
                                                  torch.normal):
                    kwargs["device"] = cpu
                return self._move(func(*args, **kwargs), self.device)
            tensors = [a for a in (*args, *kwargs.values()) if isinstance(a, torch.Tensor)]
            if any(t.device.type != "cpu" for t in tensors):
                args = self._move(args, self.device)
                kwargs = {k: self._move(v, self.device) for k, v in kwargs.items()}
            return func(*args, **kwargs)

    return _OnDevice


@contextlib.contextmanager
def use_device(name: str = "cpu", amp: bool = False) -> Iterator[str]:
    """Run the block on the resolved device (module doc); yields its name. ``cpu``: nothing changes."""
    device = resolve_device(name)
    if amp and device != "cuda":
        raise InputError(f"--amp needs --device cuda (mixed precision on CUDA); the device is {device}",
                         field="--amp")
    token = _DEVICE.set(device)
    try:
        if device == "cpu":
            yield device
            return
        torch = _torch()
        previous = torch.get_default_device()
        torch.set_default_device(device)
        try:
            with _mode_class(torch)(device), (torch.autocast("cuda", dtype=torch.bfloat16) if amp
                                              else contextlib.nullcontext()):
                yield device
        finally:
            torch.set_default_device(previous)
    finally:
        _DEVICE.reset(token)
