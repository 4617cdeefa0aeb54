"""Gesticulator (Kucherenko et al., ICMI 2020) re-implemented from the paper: network and training on arrays.

A re-implementation, not the published system (its code is GPL-3 and pinned to Python 3.6 / torch 1.4).
"""
