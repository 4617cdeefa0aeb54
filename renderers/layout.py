"""Side-by-side and grid layouts of several panels, with captions and text overlays.

Captions are drawn once (with Pillow and matplotlib's DejaVu Sans) onto a preallocated
canvas; per frame only the panels are copied in, so composing costs a few memcpys.
"""
from __future__ import annotations

import functools
import math

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from evalsuite.errors import InputError

LAYOUTS = ("side", "grid")


@functools.lru_cache(maxsize=16)
def font(size: int):
    """DejaVu Sans at ``size`` pixels (shipped with matplotlib), else Pillow's default font."""
    try:
        from matplotlib import font_manager

        return ImageFont.truetype(font_manager.findfont("DejaVu Sans"), size)
    except Exception:  # font lookup is best effort; Pillow always has a default
        return ImageFont.load_default(size=size)


def text_image(text: str, width: int, height: int, *, size: int | None = None, fg=(20, 20, 20),
               bg=(255, 255, 255), box: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """``(rgb (h, w, 3) uint8, alpha (h, w) float32)`` of centred, wrapped ``text``.

    With ``box=True`` the text sits on a filled rounded box (alpha 1 inside the box, 0
    elsewhere) — used for instruction overlays; otherwise the whole strip is opaque.
    """
    size = size or max(10, int(height * 0.55))
    fnt = font(size)
    img = Image.new("RGB", (width, height), tuple(bg))
    mask = Image.new("L", (width, height), 0 if box else 255)
    draw = ImageDraw.Draw(img)
    lines = _wrap(draw, text, fnt, int(width * 0.92))
    line_h = int(size * 1.25)
    total_h = line_h * len(lines)
    y0 = (height - total_h) // 2
    widths = [draw.textlength(line, font=fnt) for line in lines]
    if box:
        bw = int(max(widths) + size)
        bx0, by0 = (width - bw) // 2, max(0, y0 - size // 3)
        ImageDraw.Draw(mask).rounded_rectangle([bx0, by0, bx0 + bw, min(height - 1, y0 + total_h + size // 3)],
                                               radius=size // 3, fill=255)
    for i, (line, w) in enumerate(zip(lines, widths)):
        draw.text(((width - w) / 2, y0 + i * line_h), line, font=fnt, fill=tuple(fg))
    return np.asarray(img), np.asarray(mask, dtype=np.float32) / 255.0


def _wrap(draw, text, fnt, max_width):
    lines = []
    for para in str(text).split("\n"):
        words, line = para.split(), ""
        for word in words:
            trial = f"{line} {word}".strip()
            if line and draw.textlength(trial, font=fnt) > max_width:
                lines.append(line)
                line = word
            else:
                line = trial
        lines.append(line)
    return lines or [""]


def grid_shape(n: int, layout: str = "side", cols: int | None = None) -> tuple[int, int]:
    """``(rows, cols)`` for ``n`` panels: one row for ``side``, near-square for ``grid``."""
    if layout not in LAYOUTS:
        raise InputError(f"unknown layout {layout!r}; expected one of {', '.join(LAYOUTS)}", field="layout")
    if cols is not None:
        if cols < 1:
            raise InputError(f"cols must be at least 1, got {cols}", field="cols")
        return math.ceil(n / cols), cols
    if layout == "side":
        return 1, n
    c = math.ceil(math.sqrt(n))
    return math.ceil(n / c), c


class Compositor:
    """Places ``n`` panels of ``panel_w`` x ``panel_h`` in a grid, each under its caption."""

    def __init__(self, n: int, panel_w: int, panel_h: int, *, layout: str = "side", cols: int | None = None,
                 captions=None, caption_height: int | None = None, background=(255, 255, 255),
                 gap_color=(200, 200, 200), gap: int = 4):
        self.rows, self.cols = grid_shape(n, layout, cols)
        self.n, self.pw, self.ph = n, panel_w, panel_h
        captions = list(captions) if captions else []
        if captions and len(captions) != n:
            raise InputError(f"{len(captions)} captions for {n} panels; expected one per panel", field="captions")
        self.ch = 0
        if any(captions):
            self.ch = caption_height or max(16, int(round(panel_h * 0.1)) // 2 * 2)
        gap = gap if n > 1 else 0
        cell_w, cell_h = panel_w + gap, panel_h + self.ch + gap
        width, height = self.cols * cell_w - gap, self.rows * cell_h - gap
        self.width, self.height = width + width % 2, height + height % 2
        self.canvas = np.empty((self.height, self.width, 3), dtype=np.uint8)
        self.canvas[:] = np.asarray(gap_color, dtype=np.uint8)
        self.slots = []
        for k in range(n):
            r, c = divmod(k, self.cols)
            x, y = c * cell_w, r * cell_h
            if self.ch:
                strip, _ = text_image(captions[k] or "", panel_w, self.ch, size=max(10, int(self.ch * 0.62)),
                                      bg=background)
                self.canvas[y:y + self.ch, x:x + panel_w] = strip
            self.slots.append((y + self.ch, x))
        # one panel that fills the frame exactly (no caption, even size): compose hands it on as it is
        self.whole_panel = self.slots == [(0, 0)] and (self.ph, self.pw) == self.canvas.shape[:2]
        for k in range(n, self.rows * self.cols):     # unused cells of a grid: plain background
            r, c = divmod(k, self.cols)
            self.canvas[r * cell_h:r * cell_h + cell_h - gap, c * cell_w:c * cell_w + panel_w] = background

    def compose(self, panels) -> np.ndarray:
        """The composed frame (the same buffer every call, or the one panel when it fills the frame: write it
        out before the next)."""
        if self.whole_panel:
            return panels[0]          # one panel, no caption: no copy (the encoder copies it once)
        for (y, x), p in zip(self.slots, panels):
            self.canvas[y:y + self.ph, x:x + self.pw] = p
        return self.canvas

    def panel_origin(self, k: int) -> tuple[int, int]:
        """``(x, y)`` pixel of panel ``k``'s top-left corner in the composed frame."""
        y, x = self.slots[k]
        return x, y


class Overlay:
    """Text in a box over the frame centre (attention-check instructions)."""

    def __init__(self, text: str, width: int, height: int, *, fg=(255, 255, 255), bg=(200, 20, 20)):
        box_h = max(24, int(height * 0.3))
        size = max(12, int(min(height * 0.075, width * 0.055)))
        rgb, alpha = text_image(text, width, box_h, size=size, fg=fg, bg=bg, box=True)
        self.y0 = (height - box_h) // 2
        self.rgb = rgb.astype(np.float32)
        self.alpha = alpha[..., None]

    def apply(self, frame: np.ndarray) -> np.ndarray:
        out = np.array(frame, copy=True)
        y0, h = self.y0, self.rgb.shape[0]
        region = out[y0:y0 + h].astype(np.float32)
        out[y0:y0 + h] = (region * (1.0 - self.alpha) + self.rgb * self.alpha + 0.5).astype(np.uint8)
        return out
