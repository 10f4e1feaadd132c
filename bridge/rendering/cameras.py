"""Cameras of the offscreen VTK pictures: named views, framing a bounding box, and putting a camera
on a VTK renderer.

Every VTK picture of the package frames its content here: :class:`~.vtk_scene.Scene` (the quality
pictures) and the per-pixel Warn renderer of course ch. 10 (:mod:`.lighting`) fit a
:class:`Camera` to their content's box with :func:`fit_camera` (a perspective camera of
:data:`VIEW_ANGLE`, the whole box in view with a margin, optionally a strip kept free for a
legend) and hand it to VTK with :func:`apply_camera`. Split out of :mod:`.vtk_scene`
(2026-12-06), which still offers the same names.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from vtkmodules.vtkCommonMath import vtkMatrix4x4
    from vtkmodules.vtkRenderingCore import vtkCamera, vtkRenderer

__all__ = ["CAMERAS", "VIEWS", "VIEW_ANGLE", "Camera", "fit_camera", "apply_camera", "vtk_matrix"]

#: Named views: direction *from* the target *to* the camera, and the view-up vector (``top``
#: looks down -z with +y up).
VIEWS: dict[str, tuple[tuple[float, float, float], tuple[float, float, float]]] = {
    "iso": ((1.0, -1.0, 0.8), (0.0, 0.0, 1.0)),
    "top": ((0.0, 0.0, 1.0), (0.0, 1.0, 0.0)),
    "bottom": ((0.0, 0.0, -1.0), (0.0, -1.0, 0.0)),
    "front": ((0.0, -1.0, 0.0), (0.0, 0.0, 1.0)),
    "back": ((0.0, 1.0, 0.0), (0.0, 0.0, 1.0)),
    "left": ((-1.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
    "right": ((1.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
}
#: The presets of the quality pictures (every key of :data:`VIEWS` is accepted).
CAMERAS = {name: VIEWS[name] for name in ("iso", "top", "front", "right")}
#: Vertical opening angle of the perspective camera, degrees (before any zoom).
VIEW_ANGLE = 30.0


@dataclass(frozen=True)
class Camera:
    """A perspective camera: ``position``, ``target`` (focal point), ``up`` and vertical view angle
    in degrees."""

    position: tuple[float, float, float]
    target: tuple[float, float, float]
    up: tuple[float, float, float] = (0.0, 0.0, 1.0)
    view_angle: float = VIEW_ANGLE

    def __post_init__(self) -> None:
        from occsurf.algorithms.errors import InvalidGeometryError

        for name in ("position", "target", "up"):
            v = np.asarray(getattr(self, name), float)
            if v.shape != (3,) or not np.all(np.isfinite(v)):
                raise InvalidGeometryError(f"camera.{name}: expected 3 finite numbers, got {getattr(self, name)!r}")
            object.__setattr__(self, name, tuple(float(x) for x in v))
        d = np.subtract(self.target, self.position)
        if np.linalg.norm(d) == 0:
            raise InvalidGeometryError("camera.target: expected a point other than camera.position")
        if np.linalg.norm(np.cross(d, self.up)) <= 1e-9 * np.linalg.norm(d) * np.linalg.norm(self.up):
            raise InvalidGeometryError(f"camera.up: expected a direction not parallel to the line of sight, got "
                                       f"{list(self.up)}")
        if not 0 < float(self.view_angle) < 180:
            raise InvalidGeometryError(f"camera.view_angle: expected 0 < angle < 180 degrees, got {self.view_angle}")


def _view_axes(position: np.ndarray, target: np.ndarray, up: np.ndarray) -> np.ndarray:
    """Rows ``sideways, up, back`` of VTK's view rotation (``vtkPerspectiveTransform.SetupCamera``)."""
    back = position - target
    back = back / np.linalg.norm(back)
    side = np.cross(up, back)
    side = side / np.linalg.norm(side)
    return np.stack([side, np.cross(back, side), back])


def fit_camera(view: str | Sequence[float], lo: Sequence[float], hi: Sequence[float], aspect: float = 4 / 3, *,
               margin: float = 1.06, keep_distance: bool = False, width_share: float = 0.94,
               shift_left: bool = False, zoom: float = 1.0, up: Sequence[float] | None = None) -> Camera:
    """The camera that looks at the box ``[lo, hi]`` from a named view (:data:`VIEWS`) or from a
    direction (target to camera; up +z, or +y within ~18 degrees of the z axis, unless ``up`` is
    given: a direction not along the view, made square to it) and shows all its eight corners.

    Two framings, one code path:

    * ``keep_distance=False`` (Warn pictures, ``occsurf render``): the view angle stays
      :data:`VIEW_ANGLE` and the camera moves to the smallest distance at which every corner lies
      inside the picture, both openings divided by ``margin`` (a long part fills the frame
      instead of a fraction of its bounding sphere).
    * ``keep_distance=True`` (:class:`Scene`): the camera stands where VTK's ``ResetCamera``
      puts it (the box's bounding sphere fits the view) and the view angle narrows until the
      corners fill ``0.94`` of the height and ``width_share`` of the width, times ``zoom``;
      ``shift_left`` moves the model left by the rest of the width, clear of a legend on the
      right.
    """
    from occsurf.algorithms.errors import InvalidGeometryError

    direction: tuple[float, ...]
    view_up: tuple[float, float, float]
    if isinstance(view, str):
        if view not in VIEWS:
            raise InvalidGeometryError(f"view: expected one of {', '.join(VIEWS)}, got {view!r}")
        direction, view_up = VIEWS[view]
    else:
        direction = tuple(float(x) for x in view)
        if up is None:
            view_up = (0.0, 0.0, 1.0) if abs(direction[2]) < 0.95 * np.linalg.norm(direction) else (0.0, 1.0, 0.0)
        else:
            d, u = np.asarray(direction, float), np.asarray(up, float)
            if u.shape != (3,) or d.shape != (3,):
                raise InvalidGeometryError(f"up: expected 3 numbers, got {up!r}")
            u = u - (u @ d) / (d @ d) * d
            if not np.isfinite(u).all() or np.linalg.norm(u) <= 1e-9 * np.linalg.norm(up):
                raise InvalidGeometryError(f"up: expected a direction across the view, got {up!r}")
            u = u / np.linalg.norm(u)
            view_up = (float(u[0]), float(u[1]), float(u[2]))
    up = view_up
    lo_, hi_ = np.asarray(lo, float), np.asarray(hi, float)
    centre = (lo_ + hi_) / 2
    corners = np.array([[x, y, z] for x in (lo_[0], hi_[0]) for y in (lo_[1], hi_[1]) for z in (lo_[2], hi_[2])])
    if not keep_distance:
        back = np.asarray(direction, float) / np.linalg.norm(direction)
        right = np.cross(-back, up)
        right /= np.linalg.norm(right)
        true_up = np.cross(right, -back)
        rel = corners - centre
        tan_v = np.tan(np.radians(VIEW_ANGLE) / 2) / margin
        tan_h = tan_v * aspect
        need = rel @ back + np.maximum(np.abs(rel @ right) / tan_h, np.abs(rel @ true_up) / tan_v)
        size = max(float(np.linalg.norm(hi_ - lo_)), 1e-9)
        dist = max(float(need.max()), 0.05 * size) + 1e-3 * size  # never inside the box's near corner
        return Camera(position=tuple(centre + dist * back), target=tuple(centre), up=up)
    return _fit_by_view_angle(np.asarray(direction, float), np.asarray(up, float), centre, corners, aspect,
                              width_share, shift_left, zoom)


def _fit_by_view_angle(direction: np.ndarray, up: np.ndarray, centre: np.ndarray, corners: np.ndarray,
                       aspect: float, width_share: float, shift_left: bool, zoom: float) -> Camera:
    """:func:`fit_camera` with ``keep_distance``: VTK's ``ResetCamera`` on the box, then
    ``vtkCamera.Zoom`` (the view angle divided) and the legend's shift, computed here."""
    radius = max(float(np.linalg.norm(corners.max(axis=0) - corners.min(axis=0))) / 2, 1e-9)
    d = direction / np.linalg.norm(direction)
    vn = centre + d * radius * 4.0 - centre  # the view plane normal VTK derives from the first placement
    vn = vn / np.linalg.norm(vn)
    up = up / np.linalg.norm(up)
    angle = np.radians(VIEW_ANGLE)
    if aspect < 1.0:  # ResetCamera fits the sphere in the narrower, horizontal opening
        angle = 2.0 * np.arctan(np.tan(angle * 0.5) * aspect)
    sq = float(np.sum((corners.max(axis=0) - corners.min(axis=0)) ** 2))
    sphere = np.sqrt(sq if sq != 0 else 1.0) * 0.5
    distance = sphere / np.sin(angle * 0.5)
    if abs(float(up @ vn)) > 0.999:
        up = np.array([-up[2], up[0], up[1]])
        up = up / np.linalg.norm(up)
    position = centre + distance * vn
    axes = _view_axes(position, centre, up)
    c = (corners - position) @ axes.T
    depth = np.maximum(-c[:, 2], 1e-12)
    half = np.tan(np.radians(VIEW_ANGLE) / 2)
    need = max(float(np.max(np.abs(c[:, 1]) / depth)) / (0.94 * half),
               float(np.max(np.abs(c[:, 0]) / depth)) / (width_share * half * aspect), 1e-9)
    target = centre
    if shift_left:  # move the model left, clear of the legend
        dop = (centre - position) / np.linalg.norm(centre - position)
        shift = np.cross(dop, up) * (-(1 - width_share) * half * aspect * distance / (zoom / need))
        target, position = centre - shift, position - shift
    return Camera(position=tuple(position), target=tuple(target), up=tuple(up), view_angle=VIEW_ANGLE / (zoom / need))


def apply_camera(renderer: vtkRenderer, camera: Camera, clip_bounds: Sequence[float] | None = None) -> vtkCamera:
    """Put ``camera`` on ``renderer``'s active VTK camera (view-up orthogonalised) and fit the
    clipping range to ``clip_bounds`` ``[x0, x1, y0, y1, z0, z1]`` (default: every visible prop);
    returns the VTK camera."""
    cam = renderer.GetActiveCamera()
    cam.SetPosition(*camera.position)
    cam.SetFocalPoint(*camera.target)
    cam.SetViewUp(*camera.up)
    cam.SetViewAngle(camera.view_angle)
    cam.OrthogonalizeViewUp()
    if clip_bounds is None:
        renderer.ResetCameraClippingRange()
    else:
        renderer.ResetCameraClippingRange(*clip_bounds)
    return cam


def vtk_matrix(m: vtkMatrix4x4) -> np.ndarray:
    """A ``vtkMatrix4x4`` as a ``(4, 4)`` array."""
    return np.array([[m.GetElement(i, j) for j in range(4)] for i in range(4)])
