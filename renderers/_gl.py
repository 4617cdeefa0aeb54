"""pyrender for offscreen rendering on a machine without a display or GPU.

``PYOPENGL_PLATFORM`` must be set before OpenGL is first imported; we default it to
``egl`` (Mesa's llvmpipe through EGL works with the PyOpenGL version pyrender pins) and
respect a value the user set. Under ``osmesa`` (which needs PyOpenGL >= 3.1.4) pyrender's
shader cache misses on every draw because the context key is a fresh ctypes object each
call; the patch below keys it by the context's address instead.

pyrender imports trimesh at the top of its modules, and trimesh imports scipy (spatial, sparse, ndimage,
optimize): about a second of a rendering command's start, though drawing our meshes needs none of it.
:func:`import_pyrender` therefore imports pyrender with a stand-in ``trimesh`` module that loads the real
package the first time anything asks for one of its attributes (the stick figure's templates, a glTF
character, pyrender's shadow pass); only ``trimesh.transformations`` (numpy only), which pyrender's nodes use
directly, is loaded at once. pyrender's scene graph is a tree, kept without networkx
(:mod:`renderers._scene_tree`).

Also here: the cached offscreen contexts, our colour-only framebuffer read (of the redrawn rectangle only),
the shader cache that draws meshes with the cheap ``shaders/stick.*`` program, and the replay of a clip's draw
calls that spares pyrender's per-frame set-up after the first frame.
"""
from __future__ import annotations

import atexit
import contextlib
import ctypes
import importlib
import importlib.util
import os
import pathlib
import sys
import threading
import types

import numpy as np

_PATCHED = False


def import_pyrender():
    """Return the ``pyrender`` module, configured for headless rendering."""
    global _PATCHED
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    if os.environ["PYOPENGL_PLATFORM"] == "osmesa" and not _PATCHED:
        import OpenGL.contextdata as contextdata

        original = contextdata.getContext

        def get_context(context=None):
            ctx = original(context)
            return ctx if isinstance(ctx, int) else ctypes.cast(ctx, ctypes.c_void_p).value

        contextdata.getContext = get_context
        _PATCHED = True
    if "pyrender" not in sys.modules:
        _defer_trimesh()
        _defer_viewer()
        with _node_tree_for_networkx():
            import pyrender
    import pyrender
    import pyrender.renderer

    _install_samples_hook(pyrender.renderer)
    return pyrender


@contextlib.contextmanager
def _node_tree_for_networkx():
    """While pyrender imports, ``networkx`` is :data:`renderers._scene_tree.NETWORKX` (unless networkx is
    imported already); afterwards ``sys.modules`` has no stand-in, so other importers get the real package."""
    if "networkx" in sys.modules:
        yield
        return
    from renderers._scene_tree import NETWORKX

    sys.modules["networkx"] = NETWORKX
    try:
        yield
    finally:
        if sys.modules.get("networkx") is NETWORKX:
            del sys.modules["networkx"]


class _DeferredTrimesh(types.ModuleType):
    """Stands in for the ``trimesh`` package until one of its attributes is first asked for."""

    def __getattr__(self, name):
        return getattr(_load_trimesh(self), name)


_TRIMESH_LOCK = threading.Lock()


def _load_trimesh(stand_in: types.ModuleType) -> types.ModuleType:
    """Import the real trimesh in place of ``stand_in`` (once) and return it."""
    with _TRIMESH_LOCK:
        if sys.modules.get("trimesh") is stand_in:
            del sys.modules["trimesh"]
            try:
                real = importlib.import_module("trimesh")
            except BaseException:
                sys.modules["trimesh"] = stand_in
                raise
            # submodules imported under the stand-in become attributes of the real package too
            for name, module in list(sys.modules.items()):
                if name.count(".") == 1 and name.startswith("trimesh.") and not hasattr(real, name[8:]):
                    setattr(real, name[8:], module)
        return sys.modules["trimesh"]


def _defer_trimesh() -> None:
    """Put a :class:`_DeferredTrimesh` in ``sys.modules`` unless trimesh is imported already or missing."""
    if "trimesh" in sys.modules:
        return
    spec = importlib.util.find_spec("trimesh")
    if spec is None or spec.submodule_search_locations is None:
        return
    stand_in = _DeferredTrimesh("trimesh", "trimesh, loaded on first use (renderers._gl)")
    stand_in.__path__ = list(spec.submodule_search_locations)   # submodules import without the package
    sys.modules["trimesh"] = stand_in
    importlib.import_module("trimesh.transformations")


_SAMPLES = threading.local()


class _DeferredViewerModule(types.ModuleType):
    """Stands in for ``pyrender.viewer`` (an interactive window: pyglet, tkinter; about 70 ms of a rendering
    command's start, which never opens one) until one of its names is asked for."""

    def __getattr__(self, name):
        if name.startswith("__"):   # the import system's probes (``__path__``: is it a package?)
            raise AttributeError(name)
        return getattr(_load_viewer(), name)


class _DeferredViewer:
    """``pyrender.Viewer`` while the viewer module is deferred: opening one imports the real module."""

    def __new__(cls, *args, **kwargs):
        return _load_viewer().Viewer(*args, **kwargs)


def _load_viewer() -> types.ModuleType:
    """Import the real ``pyrender.viewer`` in place of the stand-in (once) and return it."""
    with _TRIMESH_LOCK:
        if isinstance(sys.modules.get("pyrender.viewer"), _DeferredViewerModule):
            del sys.modules["pyrender.viewer"]
            real = importlib.import_module("pyrender.viewer")
            package = sys.modules["pyrender"]
            vars(package).update(viewer=real, Viewer=real.Viewer)
        return sys.modules["pyrender.viewer"]


def _defer_viewer() -> None:
    """Put a :class:`_DeferredViewerModule` in ``sys.modules`` before pyrender's package imports its viewer."""
    if "pyrender.viewer" in sys.modules or importlib.util.find_spec("pyrender") is None:
        return
    stand_in = _DeferredViewerModule("pyrender.viewer", "pyrender's viewer, loaded on first use (renderers._gl)")
    vars(stand_in)["Viewer"] = _DeferredViewer
    sys.modules["pyrender.viewer"] = stand_in


def _install_samples_hook(module):
    """pyrender hard-codes 4 MSAA samples; route its one call through a per-thread setting."""
    original = module.glRenderbufferStorageMultisample
    if getattr(original, "_evalsuite_hook", False):
        return

    def storage_multisample(target, samples, fmt, width, height):
        return original(target, getattr(_SAMPLES, "value", samples), fmt, width, height)

    storage_multisample._evalsuite_hook = True
    module.glRenderbufferStorageMultisample = storage_multisample


def set_samples(samples: int) -> None:
    """MSAA samples for framebuffers pyrender creates next in this thread."""
    _SAMPLES.value = int(samples)


def _read_colour_only(self, scene, flags):
    """Replacement for pyrender's framebuffer read: colour only (its depth read costs more
    than drawing a stick figure), and only the rectangle ``self._evalsuite_read_rect`` (``(x, y, w, h)``, GL
    rows from the bottom; None: all) that this frame redrew, into a frame kept on the context: outside it
    the framebuffer, and so the kept frame, still hold what the last read saw (see ``FigureRenderer._scissor``).
    Returns ``(H, W, 3)`` uint8, top row first: a read-only view of that kept frame, valid until the next read
    (copy to keep; the compositor and the encoder copy it once anyway)."""
    from OpenGL import GL

    width, height = self._main_fb_dims
    rect = getattr(self, "_evalsuite_read_rect", None)
    frame = getattr(self, "_evalsuite_frame", None)
    if rect is None or frame is None or frame.shape != (height, width, 3):
        rect = (0, 0, width, height)
        frame = self._evalsuite_frame = np.empty((height, width, 3), dtype=np.uint8)
    x, y, w, h = rect
    if w > 0 and h > 0:
        GL.glBindFramebuffer(GL.GL_READ_FRAMEBUFFER, self._main_fb_ms)
        # Without multisampling the 'multisample' buffer is a plain one and is read directly
        # (a blit on llvmpipe is a full-screen draw, ~2 ms at 640x480).
        if getattr(self, "samples", 4) != 0:
            GL.glBindFramebuffer(GL.GL_DRAW_FRAMEBUFFER, self._main_fb)
            GL.glBlitFramebuffer(x, y, x + w, y + h, x, y, x + w, y + h, GL.GL_COLOR_BUFFER_BIT, GL.GL_LINEAR)
            GL.glBindFramebuffer(GL.GL_READ_FRAMEBUFFER, self._main_fb)
        GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
        buf = GL.glReadPixels(x, y, w, h, GL.GL_RGB, GL.GL_UNSIGNED_BYTE)
        frame[y:y + h, x:x + w] = np.frombuffer(buf, dtype=np.uint8).reshape(h, w, 3)
    view = frame[::-1]
    view.flags.writeable = False
    return view, None


def capture_draws(pr, inner, scene, flags):
    """``(program id, [(vertex array, mode, index count), ...])`` of the pass pyrender just drew, or None.

    pyrender's forward pass sets every uniform, texture and GL flag again for each primitive of each frame:
    about 2 ms of Python per frame, more than llvmpipe takes to draw a stick figure. Within one
    :class:`~renderers.scene.FigureRenderer` they are the same in every frame (one camera, one light rig, one
    material, identity node poses, no texture), and a GL program keeps its uniforms, so the next frames can
    be drawn from this list by :func:`replay_draws` after the vertex buffers were overwritten. None where
    that does not hold (a texture, a second material, a posed node, instancing, another program): pyrender
    then draws every frame.
    """
    from pyrender.constants import ProgramFlags

    program_id, material, draws = None, None, []
    for node in inner._sorted_mesh_nodes(scene):
        if not node.mesh.is_visible:
            continue
        if not np.array_equal(scene.get_pose(node), np.eye(4)):
            return None
        for prim in node.mesh.primitives:
            if prim.indices is None or prim.poses is not None or prim.material.tex_flags:
                return None
            if material is not None and prim.material is not material:
                return None
            material = prim.material
            program = inner._get_primitive_program(prim, flags | pr.RenderFlags.OFFSCREEN, ProgramFlags.USE_MATERIAL)
            if program_id is not None and program._program_id != program_id:
                return None
            program_id = program._program_id
            draws.append((prim._vaid, prim.mode, prim.indices.size))
    return (program_id, draws) if draws else None


def replay_draws(offscreen, captured, clear_color, scissor) -> np.ndarray:
    """Draw ``captured`` (see :func:`capture_draws`) again into the offscreen framebuffer and read the colour:
    a clear and one draw call per primitive, with the GL state pyrender's last pass left (depth test, culling,
    blending, the program's uniforms). ``scissor``: the ``(x, y, w, h)`` to redraw, or None for all."""
    from OpenGL import GL

    inner = offscreen._renderer
    program_id, draws = captured
    offscreen._platform.make_current()
    GL.glBindFramebuffer(GL.GL_DRAW_FRAMEBUFFER, inner._main_fb_ms)
    if scissor is not None:
        GL.glEnable(GL.GL_SCISSOR_TEST)
        GL.glScissor(*scissor)
    try:
        GL.glClearColor(*clear_color)
        GL.glClear(GL.GL_COLOR_BUFFER_BIT | GL.GL_DEPTH_BUFFER_BIT)
        GL.glUseProgram(program_id)
        for vertex_array, mode, count in draws:
            GL.glBindVertexArray(vertex_array)
            GL.glDrawElements(mode, count, GL.GL_UNSIGNED_INT, ctypes.c_void_p(0))
        GL.glBindVertexArray(0)
        GL.glUseProgram(0)
        color, _ = _read_colour_only(inner, None, None)
    finally:
        if scissor is not None:
            GL.glDisable(GL.GL_SCISSOR_TEST)
    return color


_CONTEXTS: dict = {}
SHADER_DIR = pathlib.Path(__file__).resolve().parent / "shaders"


def _shader_cache(pr):
    """pyrender's shader cache, but drawing meshes with our cheap Lambert/Blinn-Phong shader
    (``shaders/stick.*``) unless ``full_shading`` is set (shadows need pyrender's PBR shader)."""

    class StickShaderCache(pr.shader_program.ShaderProgramCache):
        full_shading = False

        def get_program(self, vertex_shader, fragment_shader, geometry_shader=None, defines=None):
            if not self.full_shading and (vertex_shader, fragment_shader) == ("mesh.vert", "mesh.frag"):
                vertex_shader = str(SHADER_DIR / "stick.vert")      # absolute: os.path.join keeps it
                fragment_shader = str(SHADER_DIR / "stick.frag")
            return super().get_program(vertex_shader, fragment_shader, geometry_shader, defines)

    return StickShaderCache()


def offscreen_renderer(pr, width: int, height: int, samples: int):
    """A pyrender OffscreenRenderer per (thread, size, MSAA samples), reused across clips.

    Creating one is cheap but deleting one runs a full garbage collection in pyrender
    (about 0.2 s), which dominated short study clips; contexts are freed at exit instead.
    """
    # samples are part of the key: pyrender creates its framebuffers once per size
    key = (threading.get_ident(), int(width), int(height), int(samples))
    renderer = _CONTEXTS.get(key)
    if renderer is None:
        renderer = pr.OffscreenRenderer(width, height)
        inner = renderer._renderer
        inner._read_main_framebuffer = types.MethodType(_read_colour_only, inner)
        inner._program_cache = _shader_cache(pr)
        inner.samples = int(samples)
        if not _CONTEXTS:
            atexit.register(free_contexts)
        _CONTEXTS[key] = renderer
    return renderer


def free_contexts() -> None:
    """Delete the cached offscreen contexts (at exit; ``evalsuite.cli.run`` skips it: a process that ends at once
    gets its memory back from the OS, and pyrender's delete runs a full garbage collection, ~35 ms)."""
    for renderer in _CONTEXTS.values():
        with contextlib.suppress(Exception):   # best effort while the interpreter shuts down
            renderer.delete()
    _CONTEXTS.clear()
