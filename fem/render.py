"""Offscreen mode-shape rendering with pyvista/VTK: PNG stills, one-period GIFs, mode grids.

The structure is drawn as solids: every beam as a tube whose radius is the equivalent
radius of its section, rigid bodies as thin tubes from master to slaves, point masses as
small spheres, supports as dark cubes, plus optional *decorations* (arbitrary solids such as
adapter blocks, PZT wafers, a top frame or a base plate) that ride on one node's rigid
motion. The deformed shape is coloured by displacement magnitude (relative to its maximum)
over a faint ghost of the undeformed structure.

Beams are deformed with the cubic Hermite shape functions of a frame element, from the
end translations and rotations, so bending modes look curved between nodes.

Rendering never needs an X server or a GPU: unless the caller has chosen a VTK window class
with ``VTK_DEFAULT_OPENGL_WINDOW``, the render functions create VTK's OSMesa window
(``vtkOSOpenGLRenderWindow``: Mesa's llvmpipe software rasteriser, Debian package
``libosmesa6``) for the duration of the call. VTK's own default would try X first (and warn
``bad X server connection`` without a display) before falling back to EGL.

Mode numbers are 1-based throughout (mode 1 is the lowest), as on the command line.

Pieces, each usable alone:

- :func:`mode_scene` builds the deformable geometry of a mode (no rendering): tests read
  the colours (``"displacement / max"``) and the deflections off its meshes. It and the
  numerics under it live in :mod:`trussid.fem.render_scene` (re-exported here); this
  module holds the offscreen backend and the PNG/GIF/grid writers.
- :func:`render_mode`, :func:`render_mode_gif`, :func:`render_mode_grid` draw it.
- :class:`Decoration` and :func:`decorations_from_solids`
  attach solids to nodes; a model builder can hand any list of
  ``Decoration(mesh, colour, node)`` to the render functions.
"""


from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import math
import os
from pathlib import Path
from typing import Any, Sequence

import numpy as np
from PIL import Image

from trussid.fem.errors import RenderError
from trussid.fem.model import Model
from trussid.fem.render_scene import (DEFAULT_AMPLITUDE, FIXED_PART_COLOUR, GHOST_COLOR,
                                      GHOST_OPACITY, SCALAR_NAME, SUPPORT_COLOR, Decoration,
                                      ModeScene, check_mode_number, decorations_from_solids,
                                      default_cmap, equivalent_radius, hermite_beam_displacements,
                                      mode_scene, node_displacements)
from trussid._util.files import atomic_path

# The scene names are re-exported: code and users import them from here (fem.render).
__all__ = ["DEFAULT_AMPLITUDE", "DEFAULT_WINDOW", "GHOST_COLOR", "GHOST_OPACITY", "SUPPORT_COLOR",
           "SCALAR_NAME", "RenderError", "Decoration", "FIXED_PART_COLOUR",
           "decorations_from_solids", "hermite_beam_displacements", "equivalent_radius",
           "check_mode_number", "node_displacements", "ModeScene", "mode_scene", "offscreen_backend", "render_mode",
           "render_mode_gif", "render_mode_grid", "default_cmap"]

DEFAULT_WINDOW = (1024, 768)


# --------------------------------------------------------------------------- rendering
def _osmesa_available() -> bool:
    for name in ("libOSMesa.so.8", "libOSMesa.so.6", ctypes.util.find_library("OSMesa")):
        if name:
            try:
                ctypes.CDLL(name)
                return True
            except OSError:
                continue
    return False


@contextlib.contextmanager
def offscreen_backend():
    """Create VTK render windows with OSMesa (no X server, no GPU) inside this block.

    An explicit ``VTK_DEFAULT_OPENGL_WINDOW`` set by the user wins (e.g.
    ``vtkEGLRenderWindow`` on a GPU machine). The variable is restored on exit so that the
    rest of the process is unaffected.
    """
    key = "VTK_DEFAULT_OPENGL_WINDOW"
    if os.environ.get(key):
        yield os.environ[key]
        return
    if not _osmesa_available():
        raise RenderError(
            "offscreen rendering needs Mesa's OSMesa library (Debian/Ubuntu package libosmesa6, "
            "installed by scripts/setup.sh), or set VTK_DEFAULT_OPENGL_WINDOW to another VTK "
            "window class such as vtkEGLRenderWindow")
    os.environ[key] = "vtkOSOpenGLRenderWindow"
    try:
        yield os.environ[key]
    finally:
        os.environ.pop(key, None)


def _check_size(window_size) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in window_size)
    except (TypeError, ValueError):
        raise RenderError(f"window size must be two integers (width, height), got {window_size!r}") from None
    if not (16 <= w <= 8192 and 16 <= h <= 8192):
        raise RenderError(f"window size {w}x{h} is out of range: each side must be 16 to 8192 pixels")
    return w, h


def _view_vector(view) -> np.ndarray:
    named = {"iso": (1.0, -1.6, 0.9), "xz": (0.0, -1.0, 0.0), "xy": (0.0, 0.0, 1.0),
             "yz": (1.0, 0.0, 0.0)}
    v = np.asarray(named.get(view, view) if isinstance(view, str) else view, float)
    if isinstance(view, str) and view not in named:
        raise RenderError(f"unknown view {view!r}: use one of {', '.join(named)} or a direction (3,)")
    if v.shape != (3,) or not np.isfinite(v).all() or np.linalg.norm(v) == 0:
        raise RenderError(f"view direction must be a non-zero 3-vector, got {view!r}")
    return v / np.linalg.norm(v)


def _groups(scene: ModeScene, meshes: dict[str, Any]) -> dict[tuple, Any]:
    """Merge the parts' meshes by how they are drawn (kind, colour, opacity).

    A testbed has some twenty solids; one actor per drawing style instead of one per part
    saves most of pyvista's per-actor overhead.
    """
    import pyvista as pv  # deferred: VTK takes ~1 s to load; only drawing needs it

    by_key: dict[tuple, list] = {}
    for part in scene.parts:
        if part.name in meshes:
            key = (part.kind, str(part.color) if part.color is not None else None, part.opacity)
            by_key.setdefault(key, []).append(meshes[part.name])
    return {key: (items[0] if len(items) == 1 else pv.merge(items, merge_points=False))
            for key, items in by_key.items()}


def _add_scene(plotter, scene: ModeScene, factor: float, cmap, show_ghost: bool,
               scalar_bar: bool, font_size: int, frame=None) -> dict[tuple, Any]:
    """Add the ghost and the deformed meshes to the active subplot (``frame``: its (width,
    height) in pixels, so that the title sits inside it and a long one is set smaller).

    Returns the datasets the actors draw, by group (:func:`_groups`), for animation.
    """
    import pyvista as pv  # deferred: VTK takes ~1 s to load; only drawing needs it

    if show_ghost:
        ghosts = list(scene.ghost_meshes().values())
        if ghosts:
            ghost = ghosts[0] if len(ghosts) == 1 else pv.merge(ghosts, merge_points=False)
            plotter.add_mesh(ghost, color=GHOST_COLOR, opacity=GHOST_OPACITY, smooth_shading=True,
                             scalars=None, show_scalar_bar=False)
    cmap = default_cmap() if cmap is None else cmap
    bar_args = dict(title="displacement\n/ max", n_labels=6, fmt="%.1f", vertical=True, position_x=0.87,
                    position_y=0.1, height=0.62, width=0.05, color="black",
                    title_font_size=max(font_size, 12), label_font_size=max(font_size - 1, 12),
                    unconstrained_font_size=True)
    bar_done = False
    handles = {}
    for key, mesh in _groups(scene, scene.meshes(factor)).items():
        _, color, opacity = key
        if color is not None:
            plotter.add_mesh(mesh, color=color, opacity=opacity, scalars=None, smooth_shading=True,
                                     show_scalar_bar=False, specular=0.3)
        else:
            plotter.add_mesh(mesh, scalars=SCALAR_NAME, cmap=cmap, clim=(0.0, 1.0), opacity=opacity,
                                     smooth_shading=True, specular=0.3,
                                     show_scalar_bar=scalar_bar and not bar_done, scalar_bar_args=bar_args)
            bar_done = True
        # The actor draws this mesh through a pipeline (normals), so updating it in place
        # (copy_from) re-executes the pipeline on the next render.
        handles[key] = mesh
    # Inside the frame: "upper_left" puts the text against the window's top and left edges,
    # where its first pixels were cut; a long title (a mode label) is set smaller to fit.
    if frame is None:
        plotter.add_text(scene.title, position="upper_left", font_size=font_size, color="black")
        return handles
    w, h = frame
    size = max(7, min(font_size, int(0.92 * w / (0.62 * max(len(scene.title), 1)))))
    # pixels from the subplot's lower left corner to the text's: a margin of 2 % and a line
    plotter.add_text(scene.title, position=(int(0.02 * w), int(h - 0.02 * h - 1.5 * size)),
                     font_size=size, color="black")
    return handles


def _frame_camera(plotter, scene: ModeScene, view) -> None:
    v = _view_vector(view)
    b = np.array(scene.bounds()).reshape(3, 2)
    centre = b.mean(axis=1)
    up = np.array([0.0, 0.0, 1.0]) if abs(v[2]) < 0.95 else np.array([0.0, 1.0, 0.0])
    plotter.camera_position = [tuple(centre + v * scene.diagonal * 3), tuple(centre), tuple(up)]
    plotter.reset_camera(bounds=tuple(b.ravel()))
    # Leave the right-hand strip to the colour bar: shift the picture left and shrink it a
    # little (the window centre moves in normalised view coordinates, -1..1).
    plotter.camera.SetWindowCenter(0.14, 0.0)
    plotter.camera.zoom(0.9)


def _new_plotter(window_size, shape=(1, 1), antialias: bool = True):
    import pyvista as pv  # deferred: VTK takes ~1 s to load; only drawing needs it

    p = pv.Plotter(off_screen=True, window_size=list(window_size), shape=shape, border=False)
    # 4x multisampling smooths edges; in a software rasteriser it costs about 0.6 s per
    # 800x600 frame of a 540-beam lattice (benchmarks/results/render.md), so GIFs skip it.
    p.ren_win.SetMultiSamples(4 if antialias else 0)
    p.set_background("white")
    return p


def _write_png(image: np.ndarray, out) -> None:
    with atomic_path(out, suffix=".png") as tmp:
        Image.fromarray(image).save(tmp, format="PNG")


def _check_out(out, suffix: str):
    if out is None:
        return None
    out = Path(out)
    if out.suffix.lower() != suffix:
        raise RenderError(f"output file {str(out)!r}: expected a {suffix} file")
    return out


def render_mode(model: Model, modes, mode: int = 1, out=None, *, window_size=DEFAULT_WINDOW,
                scale: float | None = None, amplitude: float = DEFAULT_AMPLITUDE,
                label: str | None = None, labels: Sequence[str] | None = None,
                decorations: Sequence = (), view="iso", show_ghost: bool = True,
                cmap=None, n_samples: int = 9, antialias: bool = True) -> np.ndarray:
    """Render one mode shape offscreen as a still image.

    Parameters
    ----------
    model, modes, mode, scale, amplitude, label, labels, decorations, n_samples
        See :func:`mode_scene`.
    out : path-like, optional
        PNG file to write (atomically).
    window_size : (int, int)
        Width and height [pixels].
    view : {"iso", "xz", "xy", "yz"} or (3,) float
        Direction from the model towards the camera (z is up).
    show_ghost : bool
        Draw the undeformed structure faintly.
    cmap : str or matplotlib colormap, optional
        Colour map for ``|u| / max |u|``; default :func:`default_cmap`.
    antialias : bool
        4x multisample anti-aliasing.

    Returns
    -------
    image : (height, width, 3) uint8
    """
    out = _check_out(out, ".png")
    size = _check_size(window_size)
    scene = mode_scene(model, modes, mode, scale=scale, amplitude=amplitude, decorations=decorations,
                       label=label, labels=labels, n_samples=n_samples)
    with offscreen_backend():
        p = _new_plotter(size, antialias=antialias)
        try:
            _add_scene(p, scene, 1.0, cmap, show_ghost, True, _font_size(size), size)
            _frame_camera(p, scene, view)
            image = np.asarray(p.screenshot(return_img=True))
        finally:
            p.close()
    if out is not None:
        _write_png(image, out)
    return image


def render_mode_gif(model: Model, modes, mode: int = 1, out=None, *, frames: int = 24,
                    period: float = 1.5, window_size=(800, 600), scale: float | None = None,
                    amplitude: float = DEFAULT_AMPLITUDE, label: str | None = None,
                    labels: Sequence[str] | None = None, decorations: Sequence = (), view="iso",
                    show_ghost: bool = True, cmap=None, n_samples: int = 9,
                    antialias: bool = False) -> np.ndarray:
    """Render one period of a mode's vibration as an animated GIF (looping).

    Frame ``j`` shows the deformation ``sin(2 pi (j + 1/8) / frames)`` times the drawn
    amplitude (the 1/8 keeps consecutive frames distinct, so none is merged away); the
    colour range and the camera are fixed across frames.

    Parameters
    ----------
    frames : int
        Number of frames in one period (>= 2).
    period : float
        Playback duration of one period [s].
    out : path-like, optional
        GIF file to write (atomically).
    antialias : bool
        4x multisampling; off by default for GIFs (it more than doubles the time per frame
        in software rendering, and the 255-colour palette blurs the gain).
    model, modes, mode, window_size, scale, amplitude, label, labels, decorations, view, show_ghost, cmap, n_samples
        As :func:`render_mode`.

    Returns
    -------
    images : (frames, height, width, 3) uint8
    """
    out = _check_out(out, ".gif")
    size = _check_size(window_size)
    if isinstance(frames, bool) or not isinstance(frames, (int, np.integer)) or not 2 <= frames <= 1000:
        raise RenderError(f"frames must be an integer from 2 to 1000, got {frames!r}")
    if not (np.isfinite(period) and period > 0):
        raise RenderError(f"period must be positive, got {period!r}")
    scene = mode_scene(model, modes, mode, scale=scale, amplitude=amplitude, decorations=decorations,
                       label=label, labels=labels, n_samples=n_samples)
    # Harmonic motion sampled at 2 pi j / F repeats values in consecutive frames (sin 60 deg
    # = sin 120 deg), and GIF writers merge identical consecutive frames, so the file would
    # hold fewer frames than asked. A phase offset of pi / (4 F) never gives two consecutive
    # equal values: sin(a) = sin(b) needs a + b = pi (mod 2 pi), i.e. 2 F - 8 j - 4 = 1 (mod 4 F).
    factors = np.sin(2 * np.pi * (np.arange(frames) + 0.125) / frames)
    images = []
    with offscreen_backend():
        p = _new_plotter(size, antialias=antialias)
        try:
            drawn = _add_scene(p, scene, factors[0], cmap, show_ghost, True, _font_size(size),
                               size)
            _frame_camera(p, scene, view)
            for c in factors:
                for key, mesh in _groups(scene, scene.meshes(c)).items():
                    drawn[key].copy_from(mesh, deep=True)
                p.render()
                images.append(np.asarray(p.screenshot(return_img=True)))
        finally:
            p.close()
    images = np.stack(images)
    if out is not None:
        _write_gif(images, out, period / frames)
    return images


def _write_gif(images: np.ndarray, out, frame_seconds: float) -> None:
    # Pillow (already required by pyvista and matplotlib) writes the GIF; pyvista's own
    # open_gif needs imageio, which is not a dependency.
    # One palette for all frames (from a few frames spread over the period) so colours do
    # not flicker between frames; octree quantisation is ~20x faster than median cut.
    sample = Image.fromarray(np.concatenate(list(images[:: max(1, len(images) // 4)]), axis=0))
    palette = sample.quantize(colors=255, method=Image.Quantize.FASTOCTREE)
    pics = [Image.fromarray(im).quantize(palette=palette) for im in images]
    with atomic_path(out, suffix=".gif") as tmp:
        pics[0].save(tmp, format="GIF", save_all=True, append_images=pics[1:],
                     duration=max(int(round(1000 * frame_seconds)), 20), loop=0, disposal=1,
                     optimize=False)


def render_mode_grid(model: Model, modes, n: int = 6, out=None, *, ncols: int | None = None,
                     window_size=None, scale: float | None = None,
                     amplitude: float = DEFAULT_AMPLITUDE, labels: Sequence[str] | None = None,
                     decorations: Sequence = (), view="iso", show_ghost: bool = True,
                     cmap=None, n_samples: int = 9) -> np.ndarray:
    """Render modes 1..``n`` side by side in one image.

    Parameters
    ----------
    n : int
        Number of modes (1..number of modes available).
    ncols : int, optional
        Columns (default ``ceil(sqrt(n))``).
    window_size : (int, int), optional
        Whole image [pixels]; default 420 x 340 per cell.
    out : path-like, optional
        PNG file to write (atomically).
    model, modes, scale, amplitude, labels, decorations, view, show_ghost, cmap, n_samples
        As :func:`render_mode`; ``scale``, when given, applies to every mode.

    Returns
    -------
    image : (height, width, 3) uint8
    """
    out = _check_out(out, ".png")
    n_avail = np.asarray(modes.shapes_full).shape[1]
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise RenderError(f"number of modes in the grid must be a positive integer, got {n!r}")
    if n > n_avail:
        raise RenderError(f"cannot show {n} modes in the grid: only {n_avail} modes are available")
    if ncols is None:
        ncols = int(math.ceil(math.sqrt(n)))
    nrows = int(math.ceil(n / ncols))
    size = _check_size(window_size if window_size is not None else (420 * ncols, 340 * nrows))
    scenes = [mode_scene(model, modes, k, scale=scale, amplitude=amplitude, decorations=decorations,
                         labels=labels, n_samples=n_samples) for k in range(1, n + 1)]
    cell = (size[0] // ncols, size[1] // nrows)
    with offscreen_backend():
        p = _new_plotter(size, shape=(nrows, ncols))
        try:
            for k, scene in enumerate(scenes):
                p.subplot(k // ncols, k % ncols)
                p.set_background("white")
                _add_scene(p, scene, 1.0, cmap, show_ghost, k == n - 1, _font_size(cell), cell)
                _frame_camera(p, scene, view)
            image = np.asarray(p.screenshot(return_img=True))
        finally:
            p.close()
    if out is not None:
        _write_png(image, out)
    return image


def _font_size(size) -> int:
    return int(np.clip(min(size) / 48, 9, 18))
