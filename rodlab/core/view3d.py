"""3-D pictures of rodlab's field files (``rodlab fea --fields``): the deformed rod over its undeformed outline,
coloured by von Mises stress or displacement, parts labelled, the ball's displacement arrow, a colour bar with
units. pyvista (the ``viz`` extra) renders; off-screen on a machine without a display through the EGL or
OSMesa library that VTK's wheels load at run time (Debian / Ubuntu: ``libegl1 libgl1-mesa-dri``, or
``libosmesa6``). Where VTK can render nowhere it crashes the process, so the first off-screen picture of a
process is tried in a child process first (:func:`check_offscreen`), and a clear :class:`RenderError` results.
"""
from __future__ import annotations

import atexit
import importlib.util
import io
import logging
import os
import subprocess
import sys
import warnings
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import LocatedError, RenderError
from .view_labels import grouped_labels, tick_counts
from .vtkio import decode_strings
from .fileio import atomic_write_bytes

__all__ = ["RenderError", "FieldView", "LOAD_KEYS", "parse_load", "read_field_view", "check_offscreen",
           "start_offscreen_check", "render_view", "require_pyvista", "render_triangle_sets", "field_peak"]

log = logging.getLogger(__name__)

#: load cases of a field file: unit force along x, y, z of {T}, 1 g0 along x, y, z
LOAD_KEYS = ("Fx", "Fy", "Fz", "gx", "gy", "gz")
_COLOURS = ("stress", "displacement")
_PART_LABEL = {"pipe_holder": "pipe holder", "pipe_I": "pipe I", "ring_1": "ring 1", "bend": "bend",
               "ring_2": "ring 2", "pipe_II": "pipe II", "ball_holder": "ball holder", "ball": "ball"}
_HINT = ("install the EGL or OSMesa library that VTK loads (Debian / Ubuntu: `apt-get install libegl1 "
         "libgl1-mesa-dri`, or `libosmesa6`), or run where a display is available")
_offscreen_ok: bool | None = None
_probe: subprocess.Popen | None = None              # started early by start_offscreen_check


def require_pyvista():
    """pyvista, or a :class:`RenderError` naming the extra to install."""
    try:
        import pyvista
    except ImportError as e:
        raise RenderError("3-D views need pyvista: pip install 'rodlab[viz]'") from e
    return pyvista


_PROBE = ("import pyvista as pv; p = pv.Plotter(off_screen=True, window_size=(48, 48)); "
          "p.add_mesh(pv.Sphere(), color='red'); img = p.screenshot(return_img=True); p.close(); "
          "raise SystemExit(0 if img is not None and img.max() > 0 else 3)")


def start_offscreen_check() -> None:
    """Start :func:`check_offscreen`'s probe now, in a child process, and go on: a command that renders 3-D views
    after other work (the study's figures: ~1.6 s) has the answer waiting (the probe takes ~2 s: VTK's import).
    Does nothing when the answer is known or pyvista is missing (:func:`check_offscreen` then says so)."""
    global _probe
    if _offscreen_ok is not None or _probe is not None or importlib.util.find_spec("pyvista") is None:
        return                                   # (pyvista found, not imported: the child imports it)
    try:
        _probe = _start_probe()
    except OSError as e:
        log.debug("off-screen probe not started early: %s", e)
        return
    atexit.register(_drop_probe)                 # a command that stops before its views: no child left


def _start_probe() -> subprocess.Popen:
    """The probe's child process (its stderr kept for the log)."""
    return subprocess.Popen([sys.executable, "-c", _PROBE], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            text=True)


def _stop(probe: subprocess.Popen | None) -> None:
    """Kill a probe still running and reap it."""
    if probe is not None and probe.poll() is None:
        probe.kill()
        probe.wait()


def _drop_probe() -> None:
    """Stop a probe nobody waited for (the process ends before its 3-D views)."""
    global _probe
    probe, _probe = _probe, None
    _stop(probe)


def check_offscreen() -> None:
    """Raise :class:`RenderError` unless VTK renders off-screen here (tried once per process, in a child
    process: where no OpenGL exists VTK's render window ends the process with a segmentation fault; the probe
    :func:`start_offscreen_check` started is waited for)."""
    global _offscreen_ok, _probe
    require_pyvista()
    if _offscreen_ok is None:
        probe, _probe = _probe, None
        try:
            probe = probe or _start_probe()
            try:
                _, err = probe.communicate(timeout=120)
            except KeyboardInterrupt:
                _stop(probe)
                raise
            _offscreen_ok = probe.returncode == 0
            if not _offscreen_ok:
                log.info("off-screen rendering probe failed (exit %s): %s", probe.returncode, err[-2000:])
        except (OSError, subprocess.TimeoutExpired) as e:
            log.info("off-screen rendering probe failed: %s", e)
            _stop(probe)
            _offscreen_ok = False
    if not _offscreen_ok:
        raise RenderError(f"3-D rendering is impossible here: VTK found no OpenGL to render off-screen; {_HINT}")


def parse_load(value: str) -> str:
    """``x``/``Fx``/``fx`` -> ``Fx``, ``gz`` -> ``gz``; a :class:`RenderError` for anything else."""
    v = str(value).strip()
    key = {"x": "Fx", "y": "Fy", "z": "Fz"}.get(v.lower(), v[:1].upper() + v[1:].lower() if v[:1] in "Ff" else v.lower())
    if key not in LOAD_KEYS:
        raise RenderError(f"--load {value!r}: expected one of x, y, z (unit force), {', '.join(LOAD_KEYS)}")
    return key


@dataclass
class FieldView:
    """A field file read for viewing: ``mesh`` (pyvista dataset, coordinates [mm] in {6}), ``rod``, ``model``
    (``solid`` | ``frame``), ``ball_centre_mm`` shape=(3,), ``ball_displacement`` [mm per unit load] shape=(6, 3)
    (rows: :data:`LOAD_KEYS`), ``parts`` (names; empty for a frame), ``path``."""

    mesh: object
    rod: str
    model: str
    ball_centre_mm: np.ndarray
    ball_displacement: np.ndarray
    parts: tuple
    path: Path

    def __post_init__(self) -> None:
        if np.shape(self.ball_centre_mm) != (3,) or np.shape(self.ball_displacement) != (6, 3):
            raise ValueError("FieldView.ball_centre_mm must have shape (3,) and ball_displacement (6, 3)")


def read_field_view(path: str | Path) -> FieldView:
    """Read a ``.vtu`` / ``.vtp`` written by ``rodlab fea --fields``; errors name the file and what is missing."""
    pv = require_pyvista()
    path = Path(path)
    if not path.is_file():
        raise LocatedError("no such file (write one with `rodlab fea ROD --model solid --fields OUT.vtu`)", path)
    if path.suffix.lower() not in (".vtu", ".vtp"):
        raise LocatedError(f"expected a .vtu or .vtp field file, got {path.suffix!r}", path)
    try:
        ET.parse(path)                          # malformed XML: say where, before VTK's readers log their errors
    except ET.ParseError as e:
        raise LocatedError(f"not a VTK XML file: {e}", path, line=e.position[0]) from e
    _quiet_vtk()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")      # pyvista reports a damaged file as a warning
            mesh = pv.read(path)
    except Exception as e:                       # VTK's readers raise assorted errors on damaged files
        first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        raise LocatedError(f"not a readable VTK file ({first})", path) from e
    fd = mesh.field_data
    for key in ("ball_centre_mm", "ball_displacement"):
        if key not in fd:
            raise LocatedError("field data lacks this key: not a field file of `rodlab fea --fields`", path, key=key)
    missing = [f"displacement_{k}" for k in LOAD_KEYS if f"displacement_{k}" not in mesh.point_data]
    if missing:
        raise LocatedError(f"point arrays missing: {', '.join(missing)}", path, key=missing[0])
    texts = {k: decode_strings(fd[k]) for k in ("rod", "model", "part_names") if k in fd and len(fd[k])}
    text = lambda k, d: texts[k][0] if texts.get(k) else d   # noqa: E731
    return FieldView(mesh, text("rod", path.stem), text("model", "solid"), np.asarray(fd["ball_centre_mm"]).ravel()[:3],
                     np.asarray(fd["ball_displacement"], dtype=float).reshape(6, 3),
                     tuple(texts.get("part_names", ())), path)


def _units(load: str, stress: bool) -> str:
    return ("MPa" if stress else "um") + (" per N" if load.startswith("F") else " per g0")


def _case_text(load: str) -> str:
    axis = load[1]
    return f"unit force along +{axis}_T at the ball" if load.startswith("F") else f"self-weight, 1 g0 along +{axis}_T"


def auto_scale(view: FieldView, load: str) -> float:
    """Exaggeration that makes the largest displacement 8 % of the rod's size."""
    u = np.linalg.norm(view.mesh.point_data[f"displacement_{load}"], axis=1).max()
    size = np.ptp(np.asarray(view.mesh.points), axis=0).max()
    return float(0.08 * size / u) if u > 0 else 1.0


@dataclass
class _Scene:
    """What one picture draws: the undeformed surface and its outline, the deformed surface carrying the colour
    array ``colour``, the colour bar's title and range, and the peak of the colour array (value, part)."""

    undeformed: object
    outline: object
    deformed: object
    bar_title: str
    clim: tuple
    peak: tuple


def field_peak(view: FieldView, values: np.ndarray) -> tuple:
    """The peak of a field: (largest of ``values``, one per node of ``view``; the name of the part of a cell at
    that node, "" when the file names no parts). The picture's caption states it."""
    i = int(np.argmax(values))
    if not view.parts or "part" not in view.mesh.cell_data:
        return float(values[i]), ""
    if view.model == "frame":                                    # poly-lines along the centreline
        cells = view.mesh.point_cell_ids(i)                        # a shared end point: the section starting there
        name = view.parts[int(np.asarray(view.mesh.cell_data["part"])[max(cells)])] if len(cells) else ""
        return float(values[i]), _PART_LABEL.get(name, name)
    at = np.nonzero(np.asarray(view.mesh.cell_connectivity) == i)[0]
    if not at.size:
        return float(values[i]), ""
    offsets = getattr(view.mesh, "cell_offsets", None)
    offsets = view.mesh.offset if offsets is None else offsets          # pyvista < 0.45
    cell = int(np.searchsorted(np.asarray(offsets), at[0], side="right") - 1)
    name = view.parts[int(np.asarray(view.mesh.cell_data["part"])[cell])]
    return float(values[i]), _PART_LABEL.get(name, name)


def _scene(view: FieldView, load: str, scale: float, colour: str) -> _Scene:
    mesh = view.mesh.copy()
    disp = np.asarray(mesh.point_data[f"displacement_{load}"])
    stress = colour == "stress" and f"von_mises_{load}" in mesh.point_data
    values = np.asarray(mesh.point_data[f"von_mises_{load}"]) if stress else 1e3 * np.linalg.norm(disp, axis=1)
    mesh.point_data["colour"] = values
    title = ("von Mises stress" if stress else "displacement") + f" [{_units(load, stress)}]"
    # a solid's stress colour bar to the 99.5th percentile: the clamp's edge is singular and would take the whole
    # range (a frame's section stress is not: its bar goes to the peak)
    top = float(np.percentile(values, 99.5)) if stress and view.model != "frame" else float(values.max())
    clim = (0.0, top if top > 0 else 1.0)
    if view.model == "frame":                                    # a centreline: drawn as a tube
        r = 0.012 * np.ptp(np.asarray(mesh.points), axis=0).max()
        deformed = mesh.copy()
        deformed.points = np.asarray(mesh.points) + scale * disp
        und = mesh.tube(radius=r)
        return _Scene(und, und.extract_feature_edges(), deformed.tube(radius=r), title, clim, field_peak(view, values))
    try:
        surf = mesh.extract_surface(nonlinear_subdivision=2, algorithm="dataset_surface")
    except TypeError:                                            # pyvista < 0.47: no algorithm keyword
        surf = mesh.extract_surface(nonlinear_subdivision=2)
    outline = surf.extract_feature_edges(feature_angle=35, boundary_edges=True, non_manifold_edges=False,
                                         manifold_edges=False)
    deformed = surf.copy()
    deformed.points = np.asarray(surf.points) + scale * np.asarray(surf.point_data[f"displacement_{load}"])
    return _Scene(surf, outline, deformed, title, clim, field_peak(view, values))


def _labels(plotter, view: FieldView) -> None:
    """Each part's name at its centre (a frame's: at the middle of the part's longest stretch of centreline)."""
    mesh = view.mesh
    if not view.parts or "part" not in mesh.cell_data:
        return
    centres = np.asarray(mesh.cell_centers().points)
    part = np.asarray(mesh.cell_data["part"])
    frame = view.model == "frame"
    sizes = np.array([mesh.get_cell(c).n_points for c in range(mesh.n_cells)]) if frame else None
    pts, names = [], []
    for k, name in enumerate(view.parts):
        sel = part == k
        if sel.any():
            pts.append(centres[np.flatnonzero(sel)[np.argmax(sizes[sel])]] if frame else centres[sel].mean(axis=0))
            names.append(_PART_LABEL.get(name, name))
    plotter.add_point_labels(np.array(pts), names, font_size=13, point_size=1, shape_opacity=0.55,
                             always_visible=True, show_points=False, text_color="black", shape_color="white")


def _camera(plotter, camera: str) -> None:
    if camera == "above":                                        # from above, tilted to show the flange's tube
        plotter.view_vector((0.25, -0.6, 1.0), viewup=(0.0, 1.0, 0.0))
    elif camera == "xz":
        plotter.view_xz(negative=False)
    elif camera == "xy":
        plotter.view_xy()
    elif camera == "yz":
        plotter.view_yz()
    else:
        plotter.view_vector((1.0, -1.6, 0.9), viewup=(0.0, 0.0, 1.0))
    plotter.reset_camera(bounds=None)
    plotter.camera.zoom(1.15)


#: camera directions: auto (across the ball's displacement), iso, xz (the bend plane), xy (from above), yz
CAMERAS = ("auto", "iso", "xz", "xy", "yz")


def render_view(view: FieldView, png: str | Path | None, load: str = "Fy", colour: str = "stress",
                scale: float | None = None, camera: str = "auto", title: str | None = None,
                window_size=(1400, 900)) -> Path | None:
    """Draw one load case of ``view``; to ``png`` (off-screen, written atomically) or, with ``png=None``, in
    an interactive window. ``scale``: displacement exaggeration (``None``: :func:`auto_scale`); ``camera``: one
    of :data:`CAMERAS` (``auto``: looking across the ball's displacement)."""
    pv = require_pyvista()
    load = parse_load(load)
    if colour not in _COLOURS:
        raise RenderError(f"colour must be one of {', '.join(_COLOURS)}; got {colour!r}")
    if camera not in CAMERAS:
        raise RenderError(f"view must be one of {', '.join(CAMERAS)}; got {camera!r}")
    scale = auto_scale(view, load) if scale is None else float(scale)
    if not (np.isfinite(scale) and scale > 0):
        raise RenderError(f"scale must be a positive number, got {scale!r}")
    if png is not None:
        check_offscreen()
    elif sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        raise RenderError("no display for the interactive window (DISPLAY is not set): write a picture with -o VIEW.png")
    scene = _scene(view, load, scale, colour)
    _quiet_vtk()
    plotter = pv.Plotter(off_screen=png is not None, window_size=list(window_size))
    plotter.set_background("white")
    plotter.add_mesh(scene.undeformed, color="#9a9a9a", opacity=0.22, smooth_shading=True)
    plotter.add_mesh(scene.outline, color="#404040", line_width=1.5)
    plotter.add_mesh(scene.deformed, scalars="colour", cmap="turbo", clim=list(scene.clim), smooth_shading=True,
                     above_color="magenta" if scene.clim[1] < scene.peak[0] else None,
                     scalar_bar_args={"title": scene.bar_title, "vertical": True, "position_x": 0.87,
                                      "position_y": 0.15, "height": 0.7, "width": 0.045, "color": "black",
                                      "title_font_size": 17, "label_font_size": 15, "fmt": "%.3g", "above_label": ""})
    _labels(plotter, view)
    u_ball = view.ball_displacement[LOAD_KEYS.index(load)]
    _ball_arrow(pv, plotter, view, u_ball, scale)
    plotter.add_text(title or f"rod {view.rod} ({view.model} model): {_case_text(load)}", position="upper_left",
                     font_size=13, color="black")
    plotter.add_text(_caption(view, load, scale, scene, u_ball), position="lower_left", font_size=12, color="black")
    plotter.add_axes(color="black", xlabel="x", ylabel="y", zlabel="z")
    _camera(plotter, _auto_camera(u_ball) if camera == "auto" else camera)
    if png is None:
        plotter.show()
        return None
    return _screenshot(plotter, png)


def _caption(view: FieldView, load: str, scale: float, scene: _Scene, u_ball: np.ndarray) -> str:
    unit = _units(load, False)
    umax = 1e3 * np.linalg.norm(np.asarray(view.mesh.point_data[f"displacement_{load}"]), axis=1).max()
    ub = 1e3 * np.where(np.abs(u_ball) > 1e-6 * np.abs(u_ball).max(), u_ball, 0.0)
    lines = [f"displacements x {scale:.3g} (largest {umax:.3g} {unit}); grey: undeformed",
             f"ball centre (red arrow): {np.linalg.norm(ub):.3g} {unit}, ({', '.join(f'{c:.3g}' for c in ub)}) "
             "along x, y, z of {T}; coordinates [mm] in {6}"]
    if scene.bar_title.startswith("von Mises"):
        peak, part = scene.peak
        over = f"; magenta above {scene.clim[1]:.3g}" if scene.clim[1] < peak else ""
        lines.insert(1, f"peak von Mises {peak:.3g} {_units(load, True)}{' in the ' + part if part else ''}{over}")
    return "\n".join(lines)


def _auto_camera(u_ball: np.ndarray) -> str:
    """Across the ball's displacement: a load across the bend plane (y) seen from above, tilted so that the tube
    at the flange shows; an in-plane load across the bend plane (xz)."""
    return "above" if abs(u_ball[1]) > max(abs(u_ball[0]), abs(u_ball[2])) else "xz"


def _ball_arrow(pv, plotter, view: FieldView, u_ball: np.ndarray, scale: float) -> None:
    """A red arrow from the ball's deformed centre along its displacement (length: 15 % of the rod's size)."""
    n = np.linalg.norm(u_ball)
    if n <= 0:
        return
    size = np.ptp(np.asarray(view.mesh.points), axis=0).max()
    start = view.ball_centre_mm + scale * u_ball
    plotter.add_mesh(pv.Arrow(start=start, direction=u_ball / n, scale=0.15 * size, tip_length=0.3,
                              tip_radius=0.08, shaft_radius=0.03), color="red")


def render_triangle_sets(sets, png, view, title: str = "", note: str | None = None, window_size=(1300, 900)) -> Path:
    """Coloured triangle sets (:class:`rodlab.core.render3d.TriangleSet`: the CAD's parts, a deformed shape) drawn
    off-screen to ``png``: smooth shading, each set's colour and opacity, its label at its centre, parallel
    projection along ``view`` = (direction towards the camera, up vector, axis labels or None) of
    :data:`rodlab.core.render3d.VIEWS`."""
    pv = require_pyvista()
    check_offscreen()
    _quiet_vtk()
    plotter = pv.Plotter(off_screen=True, window_size=list(window_size))
    plotter.set_background("white")
    centres: dict = {}
    for ts in sets:
        faces = np.hstack([np.full((len(ts.triangles), 1), 3), np.asarray(ts.triangles)]).ravel()
        mesh = pv.PolyData(np.asarray(ts.vertices, dtype=float), faces)
        plotter.add_mesh(mesh, color=tuple(ts.rgb), opacity=ts.alpha, smooth_shading=True, specular=0.3)
        used = np.asarray(ts.vertices)[np.unique(np.asarray(ts.triangles))]
        centres.setdefault(ts.label, []).append(used.mean(axis=0) if used.size else np.zeros(3))
    direction, up, labels = view
    points, texts = grouped_labels({n: np.mean(c, axis=0) for n, c in centres.items()}, direction, up, _PART_LABEL)
    plotter.add_point_labels(points, texts, font_size=13, shape_opacity=0.55, always_visible=True, show_points=False,
                             text_color="black", shape_color="white")
    plotter.view_vector(tuple(direction), viewup=tuple(up))
    plotter.enable_parallel_projection()
    plotter.reset_camera()
    if labels:
        n_x, n_y, n_z = tick_counts(sets)
        plotter.show_bounds(xtitle="x_T [mm]", ytitle="y_T [mm]", ztitle="z_T [mm]", color="black", font_size=10,
                            location="outer", grid=False, fmt="%.0f", n_xlabels=n_x, n_ylabels=n_y, n_zlabels=n_z)
    else:
        plotter.add_axes(color="black", xlabel="x", ylabel="y", zlabel="z")
    if title:
        plotter.add_text(title, position="upper_left", font_size=11, color="black")
    if note:
        plotter.add_text(note, position="lower_left", font_size=10, color="black")
    return _screenshot(plotter, png)


def _screenshot(plotter, png) -> Path:

    img = plotter.screenshot(return_img=True)
    plotter.close()
    from PIL import Image
    buf = io.BytesIO()
    Image.fromarray(img).save(buf, format="PNG")
    return atomic_write_bytes(png, buf.getvalue())


def _quiet_vtk() -> None:
    """VTK's logger warns on stderr when no X display exists before falling back to EGL (not the user's concern:
    the probe has checked that rendering works), and its readers log their own errors besides raising them."""
    try:
        from vtkmodules.vtkCommonCore import vtkLogger, vtkObject
        vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_OFF)
        vtkObject.GlobalWarningDisplayOff()
    except ImportError:                      # older VTK: the warnings stay
        pass
