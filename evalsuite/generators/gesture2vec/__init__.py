"""Gesture2Vec (Yazdian, Chen and Lim, IROS 2022) re-implemented from the paper: networks and training on
arrays. A re-implementation, not the published code (which has hard-coded paths and no checkpoints)."""
