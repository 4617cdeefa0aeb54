"""Render settings and the offscreen pyrender renderer.

A :class:`View` (camera, figure size, floor; :mod:`renderers.framing`, re-exported here) is
computed ONCE per segment from the motion of every condition of that segment, so all
conditions are framed identically and drawn with the same thickness. :class:`FigureRenderer` renders frames offscreen through EGL (or
whatever ``PYOPENGL_PLATFORM`` says) and reads back colour only.
"""
from __future__ import annotations

import itertools
import math
from dataclasses import asdict, dataclass, field

import numpy as np

from evalsuite.errors import InputError
from renderers._gl import capture_draws, import_pyrender, offscreen_renderer, replay_draws, set_samples
from renderers.camera import FRAMINGS, UP_AXES, VIEWS, Camera, _unit
from renderers.figure import FigureStyle, srgb_to_linear
from renderers.framing import View, make_view
from renderers.skeleton import joint_list
from renderers.styles import STYLES, BodyMesh

__all__ = ["FACES", "FigureRenderer", "RenderSettings", "View", "make_view"]
FACES = ("visible", "blank")
_TOKENS = itertools.count()


@dataclass(frozen=True)
class RenderSettings:
    """Everything that decides how a clip looks (hashed to tell whether a video is up to date)."""

    width: int = 640
    height: int = 480
    view: str = "front"
    framing: str = "full"
    fps: float | None = None          # None: the motion's own frame rate
    up_axis: str = "y"
    yfov_deg: float = 30.0
    elevation_deg: float = 8.0
    margin: float = 0.06
    msaa: int = 4                     # multisample anti-aliasing samples (0, 2, 4, 8); 0 is fastest
    crf: int = 20                     # H.264 quality (lower is better)
    center: bool = True               # move each motion's mean root position to the origin (ground plane)
    style: FigureStyle = field(default_factory=FigureStyle)
    drop_joints: tuple = ()           # joints not drawn nor framed, besides the non-body ones (renderers.skeleton)
    body: str = "stick"               # body style, a name in renderers.styles.STYLES
    character: str | None = None      # the character file of the "character" style (glTF 2.0 with a skin)
    face: str = "visible"             # "visible": a face that shows where the head faces; "blank": a face mask

    def __post_init__(self):
        object.__setattr__(self, "drop_joints", joint_list(self.drop_joints))
        if not (isinstance(self.width, int) and isinstance(self.height, int)
                and 16 <= self.width <= 7680 and 16 <= self.height <= 4320):
            raise InputError(f"resolution {self.width}x{self.height}: expected integers from 16x16 to 7680x4320",
                             field="resolution")
        if self.width % 2 or self.height % 2:
            raise InputError(f"resolution {self.width}x{self.height}: H.264 needs even width and height",
                             field="resolution")
        if self.view not in VIEWS:
            raise InputError(f"unknown view {self.view!r}; expected one of {', '.join(VIEWS)}", field="view")
        if self.framing not in FRAMINGS:
            raise InputError(f"unknown framing {self.framing!r}; expected one of {', '.join(FRAMINGS)}",
                             field="framing")
        if self.up_axis not in UP_AXES:
            raise InputError(f"unknown up axis {self.up_axis!r}; expected one of {', '.join(UP_AXES)}",
                             field="up_axis")
        if self.fps is not None and not (math.isfinite(self.fps) and self.fps > 0):
            raise InputError(f"fps must be a positive number, got {self.fps!r}", field="fps")
        if self.body not in STYLES:
            raise InputError(STYLES.unknown(self.body).reason, field="body")
        if self.character is not None and not isinstance(self.character, str):
            raise InputError(f"expected the path of a character file, got {self.character!r}", field="character")
        if self.face not in FACES:
            raise InputError(f"unknown face {self.face!r}; expected one of {', '.join(FACES)}", field="face")
        if self.msaa not in (0, 2, 4, 8):
            raise InputError(f"msaa must be 0, 2, 4 or 8, got {self.msaa!r}", field="msaa")

    def to_dict(self) -> dict:
        d = asdict(self)
        d["style"], d["drop_joints"] = self.style.to_dict(), list(self.drop_joints)
        return d

    @classmethod
    def from_dict(cls, d: dict) -> RenderSettings:
        d = dict(d)
        unknown = set(d) - set(cls.__dataclass_fields__)
        if unknown:
            raise InputError(f"unknown render setting(s) {', '.join(sorted(unknown))}; expected any of "
                             f"{', '.join(cls.__dataclass_fields__)}", field="render")
        style = d.pop("style", None)
        if isinstance(style, str):   # ``style: mannequin`` names the body style (the CLI's --style)
            if "body" in d and d["body"] != style:
                raise InputError(f"style {style!r} and body {d['body']!r} disagree; give one", field="style")
            d["body"], style = style, None
        if isinstance(style, dict):
            unknown = set(style) - set(FigureStyle.__dataclass_fields__)
            if unknown:
                raise InputError(f"unknown style setting(s) {', '.join(sorted(unknown))}", field="render.style")
            d["style"] = FigureStyle.from_dict(style)
        elif isinstance(style, FigureStyle):
            d["style"] = style
        return cls(**d)


class FigureRenderer:
    """Offscreen renderer of figures (the meshes of any body style) seen through one :class:`View`.

    Use as a context manager (on exit the figures leave the scene; the GL context is kept
    for the next renderer of the same size, see :func:`renderers._gl.offscreen_renderer`)::

        with FigureRenderer(view, settings) as r:
            for frame in r.frames(mesh, positions): ...
    """

    def __init__(self, view: View, settings: RenderSettings):
        pr = import_pyrender()
        self._pr = pr
        self.view = view
        self.settings = settings
        style = settings.style
        cam = view.camera
        self.scene = pr.Scene(bg_color=[float(c) for c in style.background] + [1.0],
                              ambient_light=[0.45, 0.45, 0.45])
        self.scene.add(pr.PerspectiveCamera(yfov=math.radians(cam.yfov_deg), aspectRatio=cam.aspect,
                                            znear=cam.znear, zfar=cam.zfar), pose=cam.pose())
        # Key light from above and to the camera's left, so the figure has shape.
        eye, target = np.asarray(cam.eye), np.asarray(cam.target)
        dist = np.linalg.norm(eye - target)
        cam_pose = cam.pose()
        light_dir = _unit(cam_pose[:3, 2] + 0.6 * cam_pose[:3, 1] - 0.4 * cam_pose[:3, 0])
        light_cam = Camera(tuple(target + light_dir * dist), tuple(target), cam.up, cam.yfov_deg,
                           cam.width, cam.height, cam.znear, cam.zfar)
        self.scene.add(pr.DirectionalLight(color=[1.0, 1.0, 1.0], intensity=2.6), pose=light_cam.pose())
        # Bounds of everything the clip can show, set on our meshes instead of computed:
        # vertices change per frame in place (so computed bounds would go stale), and
        # pyrender computes mesh bounds with np.infty, which numpy 2 removed. The
        # shadow-casting light frames its shadow map from these bounds.
        centre = np.asarray(view.floor_centre, float)
        self._bounds = np.stack([centre - 3.0 * view.size, centre + 3.0 * view.size])
        self.material = pr.MetallicRoughnessMaterial(baseColorFactor=[1.0, 1.0, 1.0, 1.0], metallicFactor=0.0,
                                                     roughnessFactor=0.7)
        if view.floor_height is not None:
            floor = self._floor_mesh(view, settings)
            floor._bounds = self._bounds
            self.scene.add(floor)
        self._entries: dict = {}
        self._renderer = offscreen_renderer(pr, cam.width, cam.height, settings.msaa)
        self._clip = cam.projection() @ np.linalg.inv(cam.pose())   # world -> clip space
        self.partial_redraw = True
        self._token = next(_TOKENS)   # the pixels outside the figure differ between renderers (floor, view)

    def _floor_mesh(self, view: View, settings: RenderSettings):
        pr = self._pr
        up = UP_AXES[settings.up_axis]
        a = _unit(np.cross(up, [1.0, 0.0, 0.0] if abs(up[0]) < 0.9 else [0.0, 1.0, 0.0]))
        b = np.cross(up, a)
        half = 25.0 * view.size   # its far edge lies near the horizon, not across the picture
        c = np.asarray(view.floor_centre, float)
        c = c - np.dot(c, up) * up + view.floor_height * up
        corners = np.array([c - half * a - half * b, c + half * a - half * b,
                            c + half * a + half * b, c - half * a + half * b])
        faces = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.uint32)
        if np.dot(np.cross(corners[1] - corners[0], corners[2] - corners[0]), up) < 0:
            faces = faces[:, ::-1].copy()
        # the figures' material and a vertex colour: a body style's floor-coloured vertices (the mannequin's
        # contact shadow fades into the floor) are shaded exactly as the floor
        colors = np.tile(srgb_to_linear(settings.style.floor_color), (4, 1)).astype(np.float32)
        prim = pr.Primitive(positions=corners.astype(np.float32), normals=np.tile(up, (4, 1)).astype(np.float32),
                            color_0=colors, indices=faces, material=self.material)
        return pr.Mesh([prim])

    def render_vertices(self, vertices: np.ndarray, normals: np.ndarray, faces: np.ndarray,
                        colors: np.ndarray) -> np.ndarray:
        """One frame ``(H, W, 3)`` uint8 of the given triangles (a read-only view; copy to keep).

        The first call for a mesh (faces, vertex count) creates its GL buffers; later calls
        only overwrite its vertex buffer in place (positions and normals change per frame,
        faces and colours do not), which skips pyrender's per-mesh setup. Several meshes
        (the panels of a comparison) stay in the scene; only the one drawn is visible.
        """
        pr = self._pr
        key = (id(faces), len(vertices))
        entry = self._entries.get(key)
        if entry is None or not entry["prim"]._buffers:
            if entry is not None:
                self.scene.remove_node(entry["node"])
            prim = pr.Primitive(positions=vertices, normals=normals, color_0=colors, indices=faces,
                                material=self.material)
            mesh = pr.Mesh([prim])
            mesh._bounds = self._bounds   # see __init__: fixed, and pyrender's own needs numpy < 2
            # (holding `faces` keeps its id, part of the key, from being reused meanwhile)
            entry = {"node": self.scene.add(mesh), "prim": prim, "faces": faces,
                     "rgba": np.asarray(prim.color_0, dtype=np.float32),   # pyrender stores RGBA
                     "data": np.empty((len(vertices), 10), dtype=np.float32)}
            self._entries[key] = entry
        else:
            from OpenGL import GL

            data = entry["data"]
            data[:, 0:3], data[:, 3:6], data[:, 6:10] = vertices, normals, entry["rgba"]
            self._renderer._platform.make_current()
            GL.glBindBuffer(GL.GL_ARRAY_BUFFER, entry["prim"]._buffers[0])
            GL.glBufferSubData(GL.GL_ARRAY_BUFFER, 0, data.nbytes, data)
        # one figure per panel lives in the scene; only the one being drawn is visible
        for other in self._entries.values():
            other["node"].mesh.is_visible = other is entry
        from OpenGL import GL

        set_samples(self.settings.msaa)   # used if pyrender (re)creates its framebuffers now
        flags = self._pr.RenderFlags.SHADOWS_DIRECTIONAL if self.settings.style.shadow else self._pr.RenderFlags.NONE
        inner = self._renderer._renderer
        inner._program_cache.full_shading = self.settings.style.shadow
        scissor = self._scissor(inner, vertices)
        inner._evalsuite_read_rect = scissor   # the read copies just this rectangle (renderers._gl)
        if entry.get("replay") is not None and getattr(inner, "_evalsuite_owner", None) == self._token:
            # the last pass on this context was ours: same uniforms, only the vertex buffer changed
            return replay_draws(self._renderer, entry["replay"], self.scene.bg_color, scissor)
        try:
            if scissor is not None:
                self._renderer._platform.make_current()
                GL.glEnable(GL.GL_SCISSOR_TEST)
                GL.glScissor(*scissor)
            color, _ = self._renderer.render(self.scene, flags)
        finally:
            if scissor is not None:
                self._renderer._platform.make_current()
                GL.glDisable(GL.GL_SCISSOR_TEST)
                self._renderer._platform.make_uncurrent()
        inner._evalsuite_owner = self._token
        entry["replay"] = None if self.settings.style.shadow else capture_draws(pr, inner, self.scene, flags)
        return color

    def _scissor(self, inner, vertices):
        """``(x, y, w, h)`` GL rectangle that needs redrawing, or None for the whole frame.

        Everything outside the figure's projected bounding box is plain background or the static
        floor (unless the figure casts a shadow), so only the union of this frame's and the previous frame's boxes (the
        previous figure must be erased) is cleared, drawn and resolved; the rest of the
        context's buffers already hold background. On a CPU rasteriser, clearing and
        resolving the full multisampled frame cost more than drawing the figure.
        """
        cam = self.view.camera
        w, h = cam.width, cam.height
        background = (tuple(self.settings.style.background), self._token)   # what lies outside the boxes
        rect = None
        if self.partial_redraw and not self.settings.style.shadow:
            # x, y and w in clip space (einsum, not a BLAS product: OpenBLAS would wake its threads each frame,
            # and they spin on the cores llvmpipe and the encoder need)
            rows = self._clip[[0, 1, 3]]
            homo = np.einsum("vi,ki->vk", vertices, rows[:, :3]) + rows[:, 3]
            wcoord = homo[:, 2]
            if len(vertices) and np.all(wcoord > 1e-9):
                ndc = homo[:, :2] / wcoord[:, None]
                x0 = int(np.floor((ndc[:, 0].min() + 1.0) * 0.5 * w)) - 2
                x1 = int(np.ceil((ndc[:, 0].max() + 1.0) * 0.5 * w)) + 2
                y0 = int(np.floor((ndc[:, 1].min() + 1.0) * 0.5 * h)) - 2   # GL: rows from the bottom
                y1 = int(np.ceil((ndc[:, 1].max() + 1.0) * 0.5 * h)) + 2
                rect = (max(x0, 0), max(y0, 0), min(x1, w), min(y1, h))
        previous = getattr(inner, "_evalsuite_dirty", None)
        inner._evalsuite_dirty = ((0, 0, w, h) if rect is None else rect, background)
        if rect is None or previous is None or previous[1] != background:
            return None
        p = previous[0]
        x0, y0, x1, y1 = min(rect[0], p[0]), min(rect[1], p[1]), max(rect[2], p[2]), max(rect[3], p[3])
        if x1 <= x0 or y1 <= y0:
            x0 = y0 = x1 = y1 = 0
        return (x0, y0, x1 - x0, y1 - y0)

    def frames(self, mesh: BodyMesh, positions: np.ndarray, chunk: int = 64):
        """Yield one frame per row of ``positions`` ``(T, J, 3)``."""
        for start in range(0, len(positions), chunk):
            verts, norms = mesh.vertices(positions[start:start + chunk])
            for v, n in zip(verts, norms):
                yield self.render_vertices(v, n, mesh.faces, mesh.colors)

    def close(self):
        # The GL context stays cached for the next renderer of this size (see
        # _offscreen_renderer); only this scene's figure is let go.
        for entry in self._entries.values():
            self.scene.remove_node(entry["node"])
        self._entries = {}
        self._renderer = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
