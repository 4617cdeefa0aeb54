"""Offscreen stick-figure rendering for ``evalsuite render`` (see docs/render.md).

Modules: :mod:`~renderers.camera` (framing and projection, pure numpy),
:mod:`~renderers.figure` (the figure's mesh and style), :mod:`~renderers.scene` (render
settings, the shared view of a segment, the pyrender renderer), :mod:`~renderers.render`
(videos and stills), :mod:`~renderers.video` (H.264 + audio), :mod:`~renderers.layout`
(side-by-side/grid, captions), :mod:`~renderers.attention` (attention checks),
:mod:`~renderers.stimuli` (batch study stimuli and the manifest). Importing this package
does not import pyrender; the modules that render do, with ``PYOPENGL_PLATFORM=egl``
unless it is set already.
"""
