"""The published Aud2Repr2Pose English demo model (Apache-2.0) run in-process with numpy, no TensorFlow.

The model's files are the user's (a clone of the demo repository's ``models/`` folder); nothing of them is
shipped with evalsuite. See :mod:`.model` for the network and the original's quirks reproduced here.
"""
