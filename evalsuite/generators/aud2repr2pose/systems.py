"""The three systems of "Moving fast and slow" as settings of one speech network. Without torch, so that the
plug-ins read their defaults (e.g. ``velocity_target``) without importing it."""
from __future__ import annotations

__all__ = ["SYSTEMS"]

# system name -> (uses the autoencoder's representation?, speech network settings); velocity_target as the paper:
# Aud2Pose's multitask velocity output, omitted for Aud2Motion ("no performance improvements") and Aud2Repr2Pose.
# past_frames: the causal Aud2Motion reads each frame with the 4 before it (0.25 s), a deviation measured in
# docs/generators.md (it lowered the held-out pose error on two corpora); the paper feeds one frame per step
SYSTEMS: dict[str, tuple[bool, dict]] = {
    "aud2pose": (False, {"velocity_target": True}),
    "aud2motion": (False, {"bidirectional": False, "form": "sequence", "velocity_target": False,
                           "past_frames": 5}),
    "aud2repr2pose": (True, {"velocity_target": False}),
}
