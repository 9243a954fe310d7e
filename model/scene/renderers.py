"""The six built-in scenes drawn (SPEC §1): textures from the photographs scikit-image
ships (``skimage.data``), a sampling grid at any size, and one renderer per scene, each a
pure function of the frame index (:data:`RENDERERS`; no random numbers). Conventions
(brightness range, motion per frame, scaling): :mod:`rvsm.model.scene.library`, which
names, checks, batches and caches the frames these draw.
"""

from __future__ import annotations

import functools
from collections.abc import Callable

import numpy as np
from scipy import ndimage

#: The reference canvas (H, W): motion is in its pixels; other sizes render the same view.
DEFAULT_SIZE: tuple[int, int] = (250, 400)
BRIGHT_MIN = 16.0
BRIGHT_MAX = 240.0

# --------------------------------------------------------------------------- textures


@functools.cache
def _texture(name: str) -> np.ndarray:
    """A bundled ``skimage.data`` image as grey ``float64`` in [0, 1], contrast-stretched
    to its 1st..99th percentiles. Read-only."""
    import skimage.data
    from skimage.color import rgb2gray

    img = np.asarray(getattr(skimage.data, name)())
    grey = rgb2gray(img[..., :3]) if img.ndim == 3 else img.astype(np.float64) / 255.0
    lo, hi = np.percentile(grey, [1.0, 99.0])
    out = np.clip((grey - lo) / max(hi - lo, 1e-6), 0.0, 1.0)
    out.setflags(write=False)
    return out


@functools.lru_cache(maxsize=64)
def _filtered(name: str, step: float, mirror_x: bool = False) -> np.ndarray:
    """Texture ``name`` low-pass filtered for sampling with ``step`` texture pixels per
    output pixel (no filtering when magnifying). ``mirror_x`` appends the left-right
    mirror (a seamless horizontal wrap)."""
    tex = _texture(name)
    if mirror_x:
        tex = np.concatenate([tex, tex[:, ::-1]], axis=1)
    sigma = 0.45 * np.sqrt(max(step * step - 1.0, 0.0))
    if sigma > 0.05:
        tex = ndimage.gaussian_filter(tex, sigma, mode="wrap")
    tex = np.ascontiguousarray(tex)
    tex.setflags(write=False)
    return tex


def _sample(tex: np.ndarray, rows: np.ndarray, cols: np.ndarray, mode: str) -> np.ndarray:
    """Bilinear sample of ``tex`` at fractional pixel coordinates (any broadcastable shape)."""
    rows, cols = np.broadcast_arrays(rows, cols)
    return ndimage.map_coordinates(tex, [rows, cols], order=1, mode=mode, prefilter=False)


class Grid:
    """Output pixel centres in reference pixels, origin at the canvas centre.

    ``Y (1, H, 1)`` and ``X (1, 1, W)``; ``s`` is the reference pixels per output pixel;
    ``half_h, half_w`` the canvas half-extents in reference pixels; ``k (F, 1, 1)`` the
    frame index as float.
    """

    def __init__(self, size: tuple[int, int], num_frames: int, first: int = 0) -> None:
        h, w = size
        self.h, self.w = h, w
        self.s = max(DEFAULT_SIZE[0] / h, DEFAULT_SIZE[1] / w)
        self.Y = ((np.arange(h) + 0.5 - h / 2) * self.s)[None, :, None]
        self.X = ((np.arange(w) + 0.5 - w / 2) * self.s)[None, None, :]
        self.half_h, self.half_w = h * self.s / 2, w * self.s / 2
        self.k = np.arange(first, first + num_frames, dtype=np.float64)[:, None, None]
        self.F = num_frames


def to_brightness(v: np.ndarray) -> np.ndarray:
    """Map a [0, 1] image to 8-bit brightness in [BRIGHT_MIN, BRIGHT_MAX]."""
    return BRIGHT_MIN + (BRIGHT_MAX - BRIGHT_MIN) * np.clip(v, 0.0, 1.0)


def _edge_alpha(dist_inside: np.ndarray, s: float) -> np.ndarray:
    """Anti-aliased coverage from a signed distance (reference px, > 0 inside)."""
    return np.clip(dist_inside / s + 0.5, 0.0, 1.0)


def _background(g: Grid, name: str, zoom: float, gain: float, offset: float) -> np.ndarray:
    """A static background ``(1, H, W)``: texture ``name`` centred, ``zoom`` texture px per
    reference px, tiled, contrast ``gain`` around ``offset``."""
    tex = _filtered(name, zoom * g.s)
    th, tw = tex.shape
    v = _sample(tex, g.Y * zoom + th / 2, g.X * zoom + tw / 2, "grid-wrap")
    return offset + gain * (v - 0.5)


def _sphere(
    g: Grid,
    cy: np.ndarray,
    cx: np.ndarray,
    radius: np.ndarray,
    spin: np.ndarray,
    tilt: float,
    tex_name: str,
) -> tuple[np.ndarray, np.ndarray]:
    """A Lambert-shaded textured sphere: returns ``(value, alpha)`` each ``(F, H, W)``.

    ``cy, cx, radius, spin`` are ``(F, 1, 1)`` (reference px, radians); the sphere spins by
    ``spin`` about its body axis, which is tilted by ``tilt`` radians toward the viewer.
    The texture is wrapped in longitude (mirrored, seamless) and latitude.
    """
    dy, dx = g.Y - cy, g.X - cx
    r2 = (dx * dx + dy * dy) / (radius * radius)
    inside = r2 < 1.0
    nx, ny = dx / radius, dy / radius
    nz = np.sqrt(np.clip(1.0 - r2, 0.0, None))
    # tilt about the x axis: body coordinates of the surface normal
    ct, st = np.cos(tilt), np.sin(tilt)
    by = ct * ny - st * nz
    bz = st * ny + ct * nz
    lon = np.arctan2(nx, bz) + spin
    lat = np.arcsin(np.clip(by, -1.0, 1.0))
    tex = _filtered(tex_name, 1.0, mirror_x=True)
    th, tw = tex.shape
    rows = (lat / np.pi + 0.5) * (th - 1)
    cols = (lon / (2 * np.pi)) * tw
    val = _sample(tex, rows, cols, "grid-wrap")
    light = np.array([-0.45, -0.55, 0.70])
    light = light / np.linalg.norm(light)
    lambert = np.clip(nx * light[0] + ny * light[1] + nz * light[2], 0.0, None)
    shade = 0.30 + 0.75 * lambert
    val = np.where(inside, val * shade, 0.0)
    alpha = _edge_alpha((1.0 - np.sqrt(r2)) * radius, g.s)
    return val, alpha


# --------------------------------------------------------------------------- scenes


def _character(g: Grid) -> np.ndarray:
    """A tiled page of text rotating about the canvas centre at 0.012 rad/frame
    (corners move <= 2.8 reference px/frame)."""
    theta = 0.012 * g.k
    zoom = 0.9  # texture px per reference px
    tex = _filtered("text", zoom * g.s)
    th, tw = tex.shape
    c, s = np.cos(theta), np.sin(theta)
    u = (c * g.Y - s * g.X) * zoom + th / 2
    v = (s * g.Y + c * g.X) * zoom + tw / 2
    return _sample(tex, u, v, "grid-wrap")


def _teapot(g: Grid) -> np.ndarray:
    """A shaded sphere (radius 0.8 of the half-height, 100 px) wrapped with 'coffee',
    spinning at 0.03 rad/frame (<= 3 px/frame at the equator) with a slight bob."""
    back = _background(g, "brick", 0.8, 0.55, 0.32)
    radius = np.full_like(g.k, 0.8 * g.half_h)
    cy = 4.0 * np.sin(2 * np.pi * g.k / 40.0)
    cx = np.zeros_like(g.k)
    val, alpha = _sphere(g, cy, cx, radius, 0.03 * g.k, 0.35, "coffee")
    return alpha * val + (1 - alpha) * back


_COIN = (186.3, 347.2, 31.0)  # centre row, centre col, radius of the largest coin in 'coins'


def _coin(g: Grid) -> np.ndarray:
    """The largest coin of 'coins': in-plane spin 0.02 rad/frame, flip angle
    phi = 0.6 + 0.55 sin(0.05 k) (width foreshortened by cos phi), flip axis turning
    0.008 rad/frame, small circular drift; over gravel."""
    back = _background(g, "gravel", 0.7, 0.5, 0.28)
    k = g.k
    radius = 0.8 * g.half_h
    cy = 6.0 * np.sin(0.06 * k)
    cx = 10.0 * np.cos(0.04 * k) - 10.0
    psi = 0.3 + 0.008 * k  # foreshortening axis orientation
    phi = 0.6 + 0.55 * np.sin(0.05 * k)  # flip angle (coin normal vs view)
    spin = 0.02 * k
    dy, dx = g.Y - cy, g.X - cx
    cp, sp = np.cos(psi), np.sin(psi)
    a = cp * dx + sp * dy  # along the foreshortened axis
    b = -sp * dx + cp * dy
    a = a / np.cos(phi)
    cs, ss = np.cos(spin), np.sin(spin)
    qx = cs * a + ss * b
    qy = -ss * a + cs * b
    r = np.sqrt(qx * qx + qy * qy) / radius  # in coin radii
    crow, ccol, crad = _COIN
    scale = crad / radius  # texture px per reference px on the coin face
    tex = _filtered("coins", scale * g.s / np.cos(0.6 + 0.55))
    face = _sample(tex, crow + qy * scale, ccol + qx * scale, "nearest")
    # rim: a bright edge ring plus a dark shadow below
    face = face * (0.75 + 0.35 * np.cos(phi)) + 0.25 * np.clip((r - 0.9) / 0.1, 0, 1)
    alpha = _edge_alpha((1.0 - r) * radius * np.cos(phi), g.s)
    return alpha * face + (1 - alpha) * back


def _grasshopper(g: Grid) -> np.ndarray:
    """A small elliptical body (cat fur) making parabolic hops of 18 frames (height 20 px,
    30 px forward) with 4 frames of rest, tilting with its velocity (and twitching at rest),
    over grass. The hops wrap around the canvas. Peak speed about 4.5 px/frame."""
    back = _background(g, "grass", 0.9, 0.65, 0.55)
    k = g.k[:, 0, 0]
    period, hop = 22.0, 18.0
    n = np.floor(k / period)
    ph = np.minimum(k - n * period, hop) / hop  # 0..1 during the hop, 1 at rest
    stride, height = 30.0, 20.0
    span = 2 * g.half_w + 60.0
    x = np.mod(-0.55 * g.half_w + (n + ph) * stride + g.half_w + 30.0, span) - g.half_w - 30.0
    ground = 0.45 * g.half_h
    y = ground - height * 4 * ph * (1 - ph)
    # nose up on take-off, down on landing (smooth, 0 at rest) plus a small idle twitch
    tilt = -0.6 * (1 - 2 * ph) * np.sin(np.pi * ph) + 0.04 * np.sin(0.35 * k)
    cy, cx, tl = y[:, None, None], x[:, None, None], tilt[:, None, None]
    dy, dx = g.Y - cy, g.X - cx
    ct, st = np.cos(tl), np.sin(tl)
    a = ct * dx + st * dy  # along the body
    b = -st * dx + ct * dy
    la, lb = 34.0, 13.0
    r = np.sqrt((a / la) ** 2 + (b / lb) ** 2)
    tex = _filtered("chelsea", 0.6 * g.s)
    body = _sample(tex, 180.0 + b * 0.6, 140.0 + a * 0.6, "reflect")
    body = 0.05 + 0.8 * body * (1.0 - 0.5 * r)  # darker body, shaded toward the rim
    alpha = _edge_alpha((1.0 - r) * lb, g.s)
    # soft shadow on the ground
    sh = np.exp(-(((g.X - cx) / 24.0) ** 2) - ((g.Y - ground - 10.0) / 4.0) ** 2)
    back = back * (1 - 0.35 * sh)
    return alpha * body + (1 - alpha) * back


def _flyball(g: Grid) -> np.ndarray:
    """A moon-textured ball on a curved path (x: sinusoid, y: double-frequency sinusoid,
    <= 4.7 px/frame), spinning at 0.1 rad/frame and changing radius by +-15 % (depth), over
    the 'camera' photo."""
    back = _background(g, "camera", 0.8, 0.7, 0.5)
    w = 2 * np.pi / 160.0
    t = g.k - 20.0
    cx = 0.6 * g.half_w * np.sin(w * t)
    cy = -0.35 * g.half_h * np.cos(2 * w * t) + 0.1 * g.half_h
    radius = 0.24 * g.half_h * (1.0 + 0.15 * np.sin(w * t))
    val, alpha = _sphere(g, cy, cx, radius, 0.1 * g.k, 0.5, "moon")
    val = 0.1 + 0.95 * val
    # motion-blur-free, but a faint shadow below the ball helps depth
    return alpha * val + (1 - alpha) * back


def _driving(g: Grid) -> np.ndarray:
    """Driving: below the horizon a perspective road (brick) moving toward the viewer
    (bottom rows <= 3 px/frame, near-horizon rows ~0: parallax) with a slow yaw pan; above
    it the 'rocket' skyline panning 0.8 px/frame and zooming 0.15 %/frame."""
    k = g.k
    horizon = -0.15 * g.half_h
    # sky / skyline
    sky_tex = _filtered("rocket", 0.9 * g.s)
    th, tw = sky_tex.shape
    zoom = 0.9 / (1.0 + 0.0015 * k)
    sky = _sample(
        sky_tex,
        (g.Y - horizon) * zoom + 0.62 * th,
        (g.X + 0.8 * k) * zoom + tw / 2,
        "reflect",
    )
    # road: ground plane, depth d = A / (y - horizon); texture coords (d, x d / f)
    below = g.Y - horizon
    dist = np.maximum(below, 0.5 * g.s)
    bottom = g.half_h - horizon
    a_const = 30.0 * bottom  # texture px of depth at the bottom row = 30
    depth = a_const / dist
    speed = 3.0 * 30.0 / bottom  # bottom rows move ~3 reference px/frame
    lateral = (g.X + 0.5 * k) * depth / 30.0 * 0.9  # reference px -> texture px at depth
    rows = depth * 2.0 + speed * 2.0 * k
    road = np.zeros(np.broadcast_shapes(rows.shape, lateral.shape))
    weight = np.zeros_like(road)
    minif = np.broadcast_to(depth / 30.0 * 0.9 * g.s * 2.0, road.shape)
    for step in (1.0, 4.0, 16.0):
        tex = _filtered("brick", step)
        wgt = np.clip(1.0 - np.abs(np.log2(np.maximum(minif, 1.0) / step)) / 2.0, 0.0, 1.0)
        if step == 1.0:
            wgt = np.where(minif <= 1.0, 1.0, wgt)
        if step == 16.0:
            wgt = np.where(minif >= 16.0, 1.0, wgt)
        road += wgt * _sample(tex, rows, lateral, "grid-wrap")
        weight += wgt
    road = road / np.maximum(weight, 1e-9)
    fog = np.clip(below / (0.35 * bottom), 0.0, 1.0)
    road = 0.45 + (0.8 * road - 0.4) * fog
    alpha = _edge_alpha(below, g.s)
    return alpha * road + (1 - alpha) * (0.25 + 0.75 * sky)


#: Scene name -> its renderer (a grid of frame coordinates -> brightness frames).
RENDERERS: dict[str, Callable[[Grid], np.ndarray]] = {
    "character": _character,
    "teapot": _teapot,
    "coin": _coin,
    "grasshopper": _grasshopper,
    "flyball": _flyball,
    "driving": _driving,
}
