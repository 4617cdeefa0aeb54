"""TensorFlow's CPU float32 arithmetic for the two operations where it is not IEEE's: tanh and the reciprocal
square root of batch normalisation.

The demo's golden outputs were made with TensorFlow 2.15 on a CPU. Its matrix products sum each output in
order with fused multiply-adds, which numpy's BLAS does too on x86-64, and its element-wise adds, multiplies
and divisions round as numpy's float32 does. Two operations are Eigen's vectorised approximations instead
(TensorFlow's x86 wheels are compiled for AVX without FMA, so each multiply-add in them rounds twice):

- ``tanh`` is Eigen's rational approximation for float32 (13/6-degree odd/even polynomials in Horner form,
  the argument clamped to +-7.90531110763549805, ``tanh(x) = x`` below 0.0004 in magnitude);
- ``rsqrt`` (``tf.nn.batch_normalization``'s ``rsqrt(variance + epsilon)``) is the CPU's approximate
  reciprocal-square-root instruction (``rsqrtps``, about 12 correct bits, vendor-specific in its low bits)
  refined by one Newton step.

With both, the demo's GRU states equal the golden ones bit for bit (they were 44 % identical with numpy's tanh
and a correctly rounded rsqrt, which left the gestures at 1.1e-4 cm). The estimate comes from the CPU itself:
a ten-byte function run through ``ctypes`` (x86-64 only). Where that is impossible, :func:`tf_rsqrt` falls
back to the correctly rounded value and :func:`rsqrt_source` says so; TensorFlow on another CPU family would
differ from the golden outputs in the same low bits.
"""
from __future__ import annotations

import ctypes
import mmap
import platform
from functools import lru_cache

import numpy as np

__all__ = ["eigen_tanh", "tf_rsqrt", "cpu_rsqrt_estimate", "rsqrt_source"]

_F32 = np.float32
# Eigen's float tanh: numerator coefficients of x^1, x^3, ... x^13 and denominator of x^0 ... x^6 (facts from
# Eigen's generic packet math), evaluated in x^2 by Horner's rule.
_NUMERATOR = tuple(_F32(c) for c in (4.89352455891786e-03, 6.37261928875436e-04, 1.48572235717979e-05,
                                     5.12229709037114e-08, -8.60467152213735e-11, 2.00018790482477e-13,
                                     -2.76076847742355e-16))
_DENOMINATOR = tuple(_F32(c) for c in (4.89352518554385e-03, 2.26843463243900e-03, 1.18534705686654e-04,
                                       1.19825839466702e-06))
_CLAMP = _F32(7.90531110763549805)
_TINY = _F32(0.0004)


def _horner(x2: np.ndarray, coefficients: tuple[np.float32, ...]) -> np.ndarray:
    """sum_i c_i x2^i, highest first, each multiply and add rounded to float32 (no FMA)."""
    acc = np.full(x2.shape, coefficients[-1], _F32)
    for c in coefficients[-2::-1]:
        acc = (acc * x2).astype(_F32) + c
    return acc.astype(_F32)


def eigen_tanh(x: np.ndarray) -> np.ndarray:
    """float32 ``tanh`` as TensorFlow's CPU kernels compute it (Eigen's rational approximation, no FMA); shape
    kept. Agrees with the exact tanh to a few ulp, and with TensorFlow bit for bit."""
    a = np.asarray(x, _F32)
    c = np.clip(a, -_CLAMP, _CLAMP)
    x2 = (c * c).astype(_F32)
    out = ((c * _horner(x2, _NUMERATOR)).astype(_F32) / _horner(x2, _DENOMINATOR)).astype(_F32)
    return np.where(np.abs(a) < _TINY, a, out).astype(_F32)


# movups xmm0, [rdi]; rsqrtps xmm0, xmm0; movups [rsi], xmm0; ret  -- f(const float in[4], float out[4])
_RSQRTPS = bytes((0x0F, 0x10, 0x07, 0x0F, 0x52, 0xC0, 0x0F, 0x11, 0x06, 0xC3))


@lru_cache(maxsize=1)
def _rsqrtps_function() -> tuple[object, object] | None:
    if platform.machine().lower() not in ("x86_64", "amd64"):
        return None
    try:
        page = mmap.mmap(-1, mmap.PAGESIZE, prot=mmap.PROT_READ | mmap.PROT_WRITE | mmap.PROT_EXEC)
        page.write(_RSQRTPS)
        address = ctypes.addressof(ctypes.c_char.from_buffer(page))
        function = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p)(address)
    except (AttributeError, OSError, TypeError, ValueError):  # no executable mapping on this platform
        return None
    return page, function   # the page must outlive the function


def cpu_rsqrt_estimate(values: np.ndarray) -> np.ndarray | None:
    """The CPU's ``rsqrtps`` estimate of ``1 / sqrt(values)`` (float32, shape kept), or None off x86-64 or where
    no executable memory can be mapped."""
    found = _rsqrtps_function()
    if found is None:
        return None
    function = found[1]
    v = np.ascontiguousarray(values, _F32).ravel()
    padded = np.ones(-(-len(v) // 4) * 4, _F32)
    padded[:len(v)] = v
    out = np.empty_like(padded)
    for i in range(0, len(padded), 4):
        function(padded.ctypes.data + 4 * i, out.ctypes.data + 4 * i)  # type: ignore[operator]
    return out[:len(v)].reshape(np.shape(values))


def rsqrt_source() -> str:
    """Where :func:`tf_rsqrt` takes its estimate from: ``"cpu rsqrtps + Newton step"`` or ``"correctly rounded"``."""
    return "cpu rsqrtps + Newton step" if _rsqrtps_function() is not None else "correctly rounded"


def tf_rsqrt(values: np.ndarray) -> np.ndarray:
    """float32 ``1 / sqrt(values)`` as TensorFlow's CPU kernels compute it: the CPU's estimate ``y`` refined by
    one Newton step in Eigen's form, ``y + (-y/2) * (v*y*y - 1)``, each multiply and add rounded; the correctly
    rounded value where the estimate is unavailable (:func:`rsqrt_source`)."""
    v = np.asarray(values, _F32)
    y = cpu_rsqrt_estimate(v)
    if y is None:
        return (1.0 / np.sqrt(v.astype(np.float64))).astype(_F32)
    vy = (v * y).astype(_F32)
    half = (y * _F32(-0.5)).astype(_F32)
    residual = ((vy * y).astype(_F32) + _F32(-1)).astype(_F32)
    return ((half * residual).astype(_F32) + y).astype(_F32)
