"""Fitting data files to surfaces (course ch. 7): what ``occsurf fit`` does, as library calls.

* :func:`read_fit_input` reads a data file: ``.npy`` (an ``(m, n, 3)`` point grid or ``(m, n)``
  heights over the unit square or given ``x``/``y`` ranges), ``.csv``/``.xyz`` rows ``x, y, z``
  (a complete height grid is detected and said, anything else is scattered), or a face of a
  STEP/IGES file (sampled over its parameter bounds, to refit). Bad data raise
  :class:`~occsurf.algorithms.errors.InvalidGeometryError` with the line (or grid row) named.
* :func:`fit_input` fits it: adaptive hierarchical by default (:func:`~occsurf.algorithms.fitting.fit_adaptive`,
  course §7-10), plain least squares with ``ctrl`` poles (:func:`~occsurf.algorithms.fitting.fit_grid`),
  scattered data adaptively by :func:`~occsurf.algorithms.fitting.fit_adaptive_scattered` (or
  :func:`~occsurf.algorithms.fitting.fit_scattered` with ``ctrl`` poles). A refitted face's deviation
  from the original is measured by OCC point projection (``GeomAPI_ProjectPointOnSurf``).
* :func:`write_fit_outputs` writes ``OUT.step`` (the flat exact NURBS), ``OUT.json`` (the editable
  hierarchy, in the sidecar format of :mod:`occsurf.bridge.exchange.hierarchical_io`) and
  ``OUT.png`` (the error map per level, :func:`occsurf.bridge.rendering.error_maps.render_error_maps`).
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from occsurf.algorithms import BSplineSurface
from occsurf.algorithms.errors import ExchangeError, InvalidGeometryError, ParameterError
from occsurf.algorithms.fitting import fit_adaptive, fit_adaptive_scattered, fit_grid, fit_scattered
from occsurf.algorithms.fitting.adaptive import measure_grid
from occsurf.algorithms.hierarchical import HierarchicalSurface

if TYPE_CHECKING:
    from occsurf.algorithms.hierarchical import Overlay

    from ..rendering.error_maps import ErrorPanel

__all__ = ["FitInput", "FitResult", "read_fit_input", "face_inputs", "fit_input", "write_fit_outputs", "face_deviation",
           "error_panel", "scatter_error_panel", "GRID_SUFFIXES", "ROW_SUFFIXES"]

GRID_SUFFIXES = (".npy",)
ROW_SUFFIXES = (".csv", ".xyz", ".txt")
CAD_SUFFIXES = (".step", ".stp", ".iges", ".igs")
#: Samples per direction of a refitted face: 4 per pole, within these bounds. At least 100: an
#: analytic face converted to few rational poles (a cylinder's 7 x 2) needs many more cubic poles
#: at 1e-4 of its size than 4 x 7 samples can determine (the adaptive fit could not refine further).
FACE_SAMPLES = (100, 400)


@dataclass
class FitInput:
    """Data ready to fit.

    Attributes
    ----------
    kind : {"grid", "heights", "scattered"}
    data : ndarray
        ``(m, n, 3)`` points, ``(m, n)`` heights, or ``(k, 3)`` scattered points.
    x, y : ndarray or None
        Grid coordinates of heights.
    description : str
        What was read and detected, one line (printed by the command).
    face : object or None
        The OCC surface of a refitted face (for the deviation by OCC projection).
    warnings : list of str
        A STEP/IGES file read around damage: its ``ImportedModel.warnings`` (empty otherwise).
    """

    kind: str
    data: np.ndarray
    x: np.ndarray | None = None
    y: np.ndarray | None = None
    description: str = ""
    face: Any = None
    warnings: list[str] = field(default_factory=list)


@dataclass
class FitResult:
    """A fit and its measured statistics (see :func:`fit_input`)."""

    hierarchy: HierarchicalSurface
    levels: list[dict]
    max_error: float
    rms_error: float
    tol: float
    converged: bool
    method: str
    panels: list[ErrorPanel] = field(default_factory=list)
    face_deviation: float | None = None

    def report(self) -> dict[str, Any]:
        """The JSON document of ``occsurf fit --json`` (without the file names)."""
        counts = self.hierarchy.pole_counts()
        flat = self.hierarchy.flatten()
        doc = {"method": self.method, "tol": self.tol, "converged": self.converged, "levels": self.levels,
               "control_points_total": int(counts["stored"]), "flat_poles": list(flat.n_poles),
               "max_error": self.max_error, "rms_error": self.rms_error,
               "degree": list(flat.degree)}
        if self.face_deviation is not None:
            doc["face_deviation"] = self.face_deviation
        return doc


# ----------------------------------------------------------------------------- reading
def _range(r: Any, name: str) -> tuple[float, float] | None:
    if r is None:
        return None
    a, b = (float(x) for x in r)
    if not (np.isfinite(a) and np.isfinite(b) and a < b):
        raise ParameterError(f"{name}: expected two finite numbers lo < hi, got {r!r}")
    return a, b


def _check_grid_rows(Q: np.ndarray) -> None:
    """A grid row or column without any value is bad data (NaN only), as is a non-finite infinity."""
    bad = np.isnan(Q) if Q.ndim == 2 else np.isnan(Q).any(axis=-1)
    if np.isinf(Q).any():
        i, j = np.argwhere(np.isinf(Q))[0][:2]
        raise InvalidGeometryError(f"grid cell ({i}, {j}) is infinite")
    for ax, name in ((1, "row"), (0, "column")):
        full = bad.all(axis=ax)
        if full.any():
            raise InvalidGeometryError(f"grid {name} {int(np.argmax(full))} has NaN only (no data)")


def _read_npy(p: Path, x_range: tuple[float, float] | None, y_range: tuple[float, float] | None) -> FitInput:
    try:
        Q = np.load(p, allow_pickle=False)
    except (OSError, ValueError) as err:
        raise ExchangeError(f"{p}: not a readable .npy array ({err})") from err
    if not np.issubdtype(Q.dtype, np.number):
        raise InvalidGeometryError(f"{p}: expected a numeric array, got dtype {Q.dtype}")
    Q = np.asarray(Q, float)
    if Q.ndim == 3 and Q.shape[2] == 3:
        if x_range or y_range:
            raise ParameterError("--x/--y: ranges apply to (m, n) height grids; this file holds (m, n, 3) points")
        _check_grid_rows(Q)
        return FitInput("grid", Q, description=f"{p.name}: {Q.shape[0]} x {Q.shape[1]} grid of 3-D points")
    if Q.ndim == 2:
        _check_grid_rows(Q)
        xr, yr = x_range or (0.0, 1.0), y_range or (0.0, 1.0)
        x, y = np.linspace(*xr, Q.shape[0]), np.linspace(*yr, Q.shape[1])
        return FitInput("heights", Q, x, y, f"{p.name}: {Q.shape[0]} x {Q.shape[1]} height grid over "
                        f"[{xr[0]:g}, {xr[1]:g}] x [{yr[0]:g}, {yr[1]:g}]")
    raise InvalidGeometryError(f"{p}: expected an (m, n, 3) point grid or (m, n) heights, got shape {Q.shape}")


_SPLIT = re.compile(r"[,;\s]+")


def _parse_rows(p: Path) -> tuple[np.ndarray, np.ndarray, bool]:
    """Rows of 3 numbers (x, y, z); returns values, their line numbers, and whether a header was
    skipped. Comments (#) and blank lines are ignored."""
    try:
        text = p.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as err:
        raise ExchangeError(f"{p}: cannot read as text ({err})") from err
    rows: list[list[float]] = []
    lines: list[int] = []
    header = False
    width = None
    for no, line in enumerate(text.splitlines(), 1):
        s = line.split("#", 1)[0].strip()
        if not s:
            continue
        cells = [c for c in _SPLIT.split(s) if c]
        try:
            vals = [float(c) for c in cells]
        except ValueError:
            bad = next(c for c in cells if not _number(c))
            if not rows and not header and all(re.fullmatch(r"[A-Za-z_][\w.]*", c) for c in cells):
                header = True  # a header line of column names
                continue
            raise InvalidGeometryError(f"line {no}: non-numeric cell {bad!r}") from None
        if width is None:
            width = len(vals)
            if width != 3:
                raise InvalidGeometryError(f"line {no}: expected 3 columns (x, y, z), got {width}")
        elif len(vals) != width:
            raise InvalidGeometryError(f"line {no}: ragged row: {len(vals)} columns where the rows above have {width}")
        if all(np.isnan(vals)):
            raise InvalidGeometryError(f"line {no}: a row of NaN only")
        if any(np.isinf(vals)):
            raise InvalidGeometryError(f"line {no}: an infinite value")
        rows.append(vals)
        lines.append(no)
    if not rows:
        raise InvalidGeometryError(f"{p}: no data rows")
    return np.array(rows, float), np.array(lines), header


def _number(c: str) -> bool:
    try:
        float(c)
        return True
    except ValueError:
        return False


def _read_rows(p: Path) -> FitInput:
    R, lines, header = _parse_rows(p)
    nan = np.isnan(R).any(axis=1)
    if nan.any():
        raise InvalidGeometryError(f"line {int(lines[np.argmax(nan)])}: a missing (NaN) value; scattered rows "
                                   "must be complete (leave the row out)")
    xs, xi = np.unique(R[:, 0], return_inverse=True)
    ys, yi = np.unique(R[:, 1], return_inverse=True)
    hdr = " (header skipped)" if header else ""
    if xs.size * ys.size == R.shape[0] and xs.size >= 2 and ys.size >= 2:
        key = xi * ys.size + yi
        if np.unique(key).size == key.size:  # every (x, y) of the grid exactly once
            Z = np.empty((xs.size, ys.size))
            Z[xi, yi] = R[:, 2]
            return FitInput("heights", Z, xs, ys, f"{p.name}: {R.shape[0]} rows{hdr}, gridded: a {xs.size} x "
                            f"{ys.size} height grid z(x, y)")
    return FitInput("scattered", R, description=f"{p.name}: {R.shape[0]} rows{hdr}, scattered (not a complete "
                    "x-y grid)")


def _read_face(p: Path, face: int | None, samples: int | None, strict: bool = False) -> FitInput:
    from ..exchange.reading import read_model

    model = read_model(p, strict=strict)  # strict: a file read around damage is refused
    n = len(model.faces)
    k = 0 if face is None else int(face)
    if not 0 <= k < n:
        raise ExchangeError(f"{p}: face {k} is not in 0..{n - 1}")
    inp = _face_input(model, p, k, samples)
    inp.warnings = list(model.warnings)
    return inp


def _face_input(model: Any, p: Path, k: int, samples: int | None) -> FitInput:
    """Face ``k`` of a read model sampled over its parameter bounds (4 samples per pole each way,
    within FACE_SAMPLES), to refit."""
    f = model.faces[k]
    n = len(model.faces)
    if f.surface is None:
        raise ExchangeError(f"{p}: face {k} ({f.surface_type}) could not be converted: {f.error}")
    from OCP.BRepTools import BRepTools

    u0, u1, v0, v1 = BRepTools.UVBounds_s(f.face)
    (a0, a1), (b0, b1) = f.surface.domain
    u0, u1, v0, v1 = max(u0, a0), min(u1, a1), max(v0, b0), min(v1, b1)
    nu, nv = f.surface.n_poles
    lo, hi = FACE_SAMPLES
    mu = int(samples or np.clip(4 * nu, lo, hi))
    mv = int(samples or np.clip(4 * nv, lo, hi))
    Q = f.surface.evaluate_grid(np.linspace(u0, u1, mu), np.linspace(v0, v1, mv))
    return FitInput("grid", Q, description=f"{p.name}: face {k} of {n} ({f.surface_type}, {nu} x {nv} poles), "
                    f"sampled {mu} x {mv} over its parameter bounds", face=f.occ_surface)


def face_inputs(path: str | os.PathLike[str], faces: list[int] | None = None, *, samples: int | None = None
                ) -> Iterator[tuple[int, FitInput | ExchangeError]]:
    """Every face (or ``faces``) of a STEP/IGES file as :class:`FitInput`, the file read once.

    Yields
    ------
    (int, FitInput or ExchangeError)
        The face index and its input, or the reason it cannot be sampled.
    """
    from ..exchange.reading import read_model

    p = Path(os.fsdecode(path))
    model = read_model(p)
    for k in range(len(model.faces)) if faces is None else faces:
        try:
            yield k, _face_input(model, p, k, samples)
        except ExchangeError as err:
            yield k, err


def read_fit_input(path: str | os.PathLike[str], *, face: int | None = None, x_range: Sequence[float] | None = None,
                   y_range: Sequence[float] | None = None,
                   samples: int | None = None, strict: bool = False) -> FitInput:
    """Read a data file for fitting (see the module notes for the formats).

    A STEP/IGES file read around damage keeps its warnings (``FitInput.warnings``); with ``strict``
    (``occsurf fit --strict``) it is refused instead (ExchangeError, the message of
    :func:`occsurf.bridge.exchange.reading.strict_refusal`).

    Raises
    ------
    InvalidGeometryError
        Bad data, named by line (rows) or grid row/column: non-numeric cells, ragged rows, NaN-only
        rows, wrong shapes.
    ExchangeError
        Unreadable files, unknown formats, a face index out of range.
    """
    p = Path(os.fsdecode(path))
    if not p.is_file():
        raise ExchangeError(f"{p}: no such file")
    suffix = p.suffix.lower()
    xr, yr = _range(x_range, "--x"), _range(y_range, "--y")
    if face is not None and suffix not in CAD_SUFFIXES:
        raise ParameterError(f"--face: only for STEP/IGES input, not {suffix or 'this file'}")
    if suffix in GRID_SUFFIXES:
        return _read_npy(p, xr, yr)
    if (xr or yr) and suffix not in GRID_SUFFIXES:
        raise ParameterError("--x/--y: ranges apply to .npy height grids only")
    if suffix in ROW_SUFFIXES:
        return _read_rows(p)
    if suffix in CAD_SUFFIXES:
        return _read_face(p, face, samples, strict)
    raise ExchangeError(f"{p}: unknown data format {suffix or '(no suffix)'}; expected .npy, .csv, .xyz, "
                        ".step/.stp or .iges/.igs")


# ----------------------------------------------------------------------------- fitting
def _pair(x: Any) -> tuple[int, int] | None:
    return None if x is None else (int(x[0]), int(x[1]))


def _too_few(inp: FitInput, degree: int) -> None:
    need = degree + 1
    if inp.kind == "scattered":
        if inp.data.shape[0] < need * need:
            raise InvalidGeometryError(f"too few points for degree {degree}: {inp.data.shape[0]} rows, need at "
                                       f"least {need * need}")
    elif min(inp.data.shape[:2]) < need:
        raise InvalidGeometryError(f"too few points for degree {degree}: a {inp.data.shape[0]} x "
                                   f"{inp.data.shape[1]} grid, need at least {need} x {need}")


def fit_input(inp: FitInput, tol: float, *, ctrl: tuple[int, int] | None = None, degree: int = 3,
              smooth: float | str = 0.0, fix_boundary: bool = False, max_levels: int | None = None,
              progress: Callable[[str], None] | None = None) -> FitResult:
    """Fit ``inp`` to ``tol`` (adaptive hierarchical), or with ``ctrl`` poles (plain least squares).

    Every error reported is measured: the distance of each data point to the surface by point
    projection. A refitted face also gets ``face_deviation``: the largest distance from the fit
    (sampled at the data parameters and between them) to the original surface, by OCC's
    ``GeomAPI_ProjectPointOnSurf``.
    """
    if not (isinstance(tol, (int, float)) and np.isfinite(tol) and tol > 0):
        raise ParameterError(f"--tol: expected a positive number, got {tol!r}")
    _too_few(inp, int(degree))
    say = progress or (lambda s: None)
    ctrl = _pair(ctrl)
    if inp.kind == "scattered":
        return _fit_scattered(inp, tol, ctrl, degree, smooth, say, max_levels)
    heights = inp.kind == "heights"
    x, y = (inp.x, inp.y) if heights else (None, None)  # None: the functions' defaults (a grid of points)
    if ctrl is not None:
        fit = fit_grid(inp.data, ctrl, degree, smoothing=smooth, fix_boundary=fix_boundary, x=x, y=y)
        u, v = fit.u_params, fit.v_params
        P3 = np.stack(np.broadcast_arrays(u[:, None], v[None, :], inp.data), -1) if heights else inp.data
        dist = measure_grid(fit.surface, P3, u, v)
        e = dist[np.isfinite(dist)]
        mx, rms = float(e.max()), float(np.sqrt(np.mean(e ** 2)))
        say(f"least squares {ctrl[0]} x {ctrl[1]} poles: max error {mx:.3g}, rms {rms:.3g}")
        hs = HierarchicalSurface(fit.surface)
        levels = [{"level": 0, "overlays": 0, "control_points": ctrl[0] * ctrl[1], "max_error": mx, "rms_error": rms}]
        res = FitResult(hs, levels, mx, rms, float(tol), mx <= tol, "least squares")
        res.panels = [error_panel(fit.surface, dist, u, v, f"least squares {ctrl[0]} x {ctrl[1]}", [])]
    else:
        if smooth == "gcv":
            raise ParameterError("--smooth gcv: choose a number for the adaptive fit (gcv needs --ctrl)")
        af = fit_adaptive(inp.data, tol, degree, smoothing=float(smooth), fix_boundary=fix_boundary,
                          max_levels=max_levels, progress=say, x=x, y=y)
        levels = [L.as_dict() for L in af.levels]
        res = FitResult(af.hierarchy, levels, af.max_error, af.rms_error, float(tol), af.converged, "adaptive hierarchical")
        res.panels = [error_panel(s, d, af.u_params, af.v_params,
                                  f"level {L.level}: {L.overlays} overlays, max {L.max_error:.2g}",
                                  [o for o in af.hierarchy.overlays if o.level == L.level])
                      for L, s, d in zip(af.levels, af.level_surfaces, af.level_distances)]
    if inp.face is not None:
        res.face_deviation = face_deviation(res.hierarchy.flatten(), inp.face)
        say(f"deviation from the original face (OCC projection): {res.face_deviation:.3g}")
    return res


def _fit_scattered(inp: FitInput, tol: float, ctrl: tuple[int, int] | None, degree: int, smooth: float | str,
                   say: Callable[[str], None], max_levels: int | None) -> FitResult:
    """Scattered rows: adaptive hierarchical (:func:`~occsurf.algorithms.fitting.fit_adaptive_scattered`,
    two parameter corrections on the base), or plain least squares with ``ctrl`` poles."""
    if smooth == "gcv":
        raise ParameterError("--smooth gcv: only for gridded data; give a number for scattered data")
    lam = None if float(smooth) == 0 else float(smooth)
    if ctrl is not None:
        fit = fit_scattered(inp.data, ctrl, degree, smoothing=lam, corrections=2)
        say(f"scattered least squares {ctrl[0]} x {ctrl[1]} poles: max error {fit.max_error:.3g}")
        levels = [{"level": 0, "overlays": 0, "control_points": ctrl[0] * ctrl[1], "max_error": fit.max_error,
                   "rms_error": fit.rms_error}]
        res = FitResult(HierarchicalSurface(fit.surface), levels, fit.max_error, fit.rms_error, float(tol),
                        fit.max_error <= tol, "scattered least squares")
        res.panels = [scatter_error_panel(fit.surface, fit.u, fit.v, fit.distance,
                                          f"scattered least squares {ctrl[0]} x {ctrl[1]}")]
        return res
    af = fit_adaptive_scattered(inp.data, tol, degree, smoothing=lam, corrections=2, max_levels=max_levels,
                                progress=say)
    res = FitResult(af.hierarchy, [L.as_dict() for L in af.levels], af.max_error, af.rms_error, float(tol),
                    af.converged, "adaptive hierarchical (scattered)")
    res.panels = [scatter_error_panel(s, af.u, af.v, d, f"level {L.level}: {L.overlays} overlays, max {L.max_error:.2g}",
                                      [o for o in af.hierarchy.overlays if o.level == L.level])
                  for L, s, d in zip(af.levels, af.level_surfaces, af.level_distances)]
    return res


# ----------------------------------------------------------------------------- measuring, pictures
def face_deviation(fitted: BSplineSurface, occ_surface: Any, samples: int = 41) -> float:
    """Largest distance from the fitted surface (``samples``^2 points) to ``occ_surface``, by OCC
    point projection: the nearer of ``GeomAPI_ProjectPointOnSurf`` (global extrema) and
    ``ShapeAnalysis_Surface.ValueOfUV`` (Newton from the nearest sample).

    Notes
    -----
    Both are needed: on ``occt__bearing.iges`` face 2 (a patch with a collapsed corner row)
    ``GeomAPI_ProjectPointOnSurf`` reports 1.7e-3 for a point *on* the surface, where
    ``ValueOfUV`` finds 7e-18; elsewhere the extrema search is the safer one.

    Only the maximum of the per-point minimum is returned, so the extrema search (0.19 ms a
    point, the dearer one) runs only where it can raise it: points in decreasing ``ValueOfUV``
    gap, stopping at the first whose gap is not above the largest minimum found (its minimum,
    and every later one, can only be smaller). The same value as both projections everywhere.
    """
    from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
    from OCP.gp import gp_Pnt
    from OCP.ShapeAnalysis import ShapeAnalysis_Surface

    (u0, u1), (v0, v1) = fitted.domain
    P = fitted.evaluate_grid(np.linspace(u0, u1, samples), np.linspace(v0, v1, samples)).reshape(-1, 3)
    pts = [gp_Pnt(float(x), float(y), float(z)) for x, y, z in P]
    sas = ShapeAnalysis_Surface(occ_surface)
    gaps = np.empty(len(pts))
    for i, p in enumerate(pts):  # OCC projects one point per call
        sas.ValueOfUV(p, 1e-12)
        gaps[i] = float(sas.Gap())
    worst = 0.0
    proj = GeomAPI_ProjectPointOnSurf()
    for i in np.argsort(-gaps, kind="stable"):
        if not gaps[i] > worst:
            break
        proj.Init(pts[i], occ_surface)
        d = float(proj.LowerDistance()) if proj.NbPoints() else np.inf
        worst = max(worst, min(d, float(gaps[i])))
    return worst


def _pool(a: np.ndarray, k: int) -> np.ndarray:
    """Every k-th row/column of ``a`` with the block maximum of the error kept (NaN-aware)."""
    from scipy.ndimage import maximum_filter

    if k <= 1:
        return a
    filled = np.where(np.isfinite(a), a, -np.inf)
    m = maximum_filter(filled, size=k, mode="nearest")
    m = np.where(np.isfinite(m), m, np.nan)
    return m[::k, ::k]


def _overlay_lines(surface: BSplineSurface, overlays: Sequence[Overlay]) -> list[np.ndarray]:
    """The borders of ``overlays`` on ``surface`` as polylines (40 points a side)."""
    lines = []
    t = np.linspace(0, 1, 40)
    for o in overlays:
        (a, b), (c, d) = o.region
        for us, vs in ((a + (b - a) * t, np.full(40, c)), (a + (b - a) * t, np.full(40, d)),
                       (np.full(40, a), c + (d - c) * t), (np.full(40, b), c + (d - c) * t)):
            lines.append(surface.evaluate(us, vs))
    return lines


def error_panel(surface: BSplineSurface, dist: np.ndarray, u: np.ndarray, v: np.ndarray, title: str,
                overlays: Sequence[Overlay]) -> ErrorPanel:
    """Gridded data: the surface at the data's parameters ``u`` x ``v`` (every k-th, at most 160 a side)
    coloured by the distance ``dist`` (``(len(u), len(v))``, the largest of each k x k block kept), the
    borders of ``overlays`` (hierarchical overlays, with a ``region``) drawn: an
    :class:`~occsurf.bridge.rendering.error_maps.ErrorPanel`."""
    from ..rendering.error_maps import ErrorPanel

    k = max(1, int(np.ceil(max(u.size, v.size) / 160)))
    uu, vv = u[::k], v[::k]
    P = surface.evaluate_grid(uu, vv)
    return ErrorPanel(P, _pool(dist, k)[: uu.size, : vv.size], title, _overlay_lines(surface, overlays))


def scatter_error_panel(surface: BSplineSurface, u: np.ndarray, v: np.ndarray, distance: np.ndarray, title: str,
                        overlays: Sequence[Overlay] = ()) -> ErrorPanel:
    """Scattered data: the surface on an 80 x 80 grid coloured by the largest distance of the
    points whose parameters fall in each cell (grey where no data), overlay borders drawn."""
    from ..rendering.error_maps import ErrorPanel

    (u0, u1), (v0, v1) = surface.domain
    r = 80
    us, vs = np.linspace(u0, u1, r), np.linspace(v0, v1, r)
    iu = np.clip(np.round((u - u0) / (u1 - u0) * (r - 1)).astype(int), 0, r - 1)
    iv = np.clip(np.round((v - v0) / (v1 - v0) * (r - 1)).astype(int), 0, r - 1)
    E = np.full((r, r), -np.inf)
    np.maximum.at(E, (iu, iv), distance)
    E[~np.isfinite(E)] = np.nan
    return ErrorPanel(surface.evaluate_grid(us, vs), E, title, _overlay_lines(surface, overlays))


def write_fit_outputs(result: FitResult, out_step: str | os.PathLike[str], *, name: str = "fit",
                      picture: bool = True) -> dict[str, str]:
    """Write ``OUT.step`` + ``OUT.json`` (the editable hierarchy, sidecar format) and ``OUT.png``.

    Returns
    -------
    dict
        ``{"step": ..., "json": ..., "png": ...}`` (``png`` absent when ``picture`` is False).
    """
    from ..exchange.hierarchical_io import write_hierarchical_step
    from ..rendering.error_maps import render_error_maps

    step = Path(os.fsdecode(out_step))
    side = step.with_suffix(".json")
    png = step.with_suffix(".png")
    write_hierarchical_step(step, result.hierarchy, name, sidecar=side)
    out = {"step": str(step), "json": str(side)}
    if picture and result.panels:
        counts = result.hierarchy.pole_counts()
        title = (f"{result.method}: max distance {result.max_error:.3g} (tol {result.tol:.3g}), "
                 f"{counts['stored']} control points stored, flat {'x'.join(map(str, result.hierarchy.flatten().n_poles))}")
        render_error_maps(png, result.panels, tol=result.tol, title=title)
        out["png"] = str(png)
    return out
