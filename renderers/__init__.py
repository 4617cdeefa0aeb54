"""Offscreen rendering of motion for ``evalsuite render`` (see docs/render.md).

Modules: :mod:`~renderers.camera` (cameras and projection, pure numpy),
:mod:`~renderers.framing` (the shared view of a segment: camera aimed at the mean root, framings, floor),
:mod:`~renderers.styles` (body styles: stick figure, mannequin, character, plug-ins),
:mod:`~renderers.figure` (the stick figure's mesh and style), :mod:`~renderers.scene` (render
settings and the pyrender renderer), :mod:`~renderers.render`
(videos and stills), :mod:`~renderers.video` (H.264 + audio), :mod:`~renderers.layout`
(side-by-side/grid, captions), :mod:`~renderers.attention` (attention checks),
:mod:`~renderers.stimuli` (batch study stimuli and the manifest). Importing this package
does not import pyrender; the modules that render do, with ``PYOPENGL_PLATFORM=egl``
unless it is set already.
"""
