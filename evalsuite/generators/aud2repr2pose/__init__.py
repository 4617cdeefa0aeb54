"""Aud2Pose, Aud2Motion and Aud2Repr2Pose ("Moving fast and slow", Kucherenko et al. 2019/2021),
re-implemented from the paper: networks and training on arrays. Re-implementations, not the published code."""
