"""Dynamic hierarchical surfaces (course §5-47): soft tissue that lags, jiggles and settles.

One level of an :class:`~.figures.AttachedSurface` (the base or an overlay) gets mass: its control
vertices are driven by the skeleton's motion through springs and dampers, and every finer level is
carried along by offset referencing. Each vertex ``x_i`` is pulled towards its *kinematic* place
``T_i(t)`` (where the posed surface puts it, :meth:`AttachedSurface.at`) and towards its
neighbours' deviations. In the deviation ``e = x - T`` the system is linear with constant
coefficients, for each coordinate:

.. math::

    m\\,\\ddot e + c\\,\\dot e + K e = -m\\,\\ddot T(t), \\qquad K = k_a I + k_n L,

``L`` the graph Laplacian of the level's control net (4-neighbours), ``k_a`` the anchor stiffness
(towards the kinematic place), ``k_n`` the coupling between neighbours, ``c`` the damping. The
skeleton's acceleration ``\\ddot T`` is the only force: a still skeleton lets the tissue settle.

Integrator: exact, unconditionally stable
-----------------------------------------
``K`` is symmetric, so ``K = Q diag(lambda) Q^T`` decouples the modes. The net's 4-neighbour grid
is the Cartesian product of two paths, whose Laplacian the orthonormal DCT-II diagonalises with
eigenvalues ``2 - 2 cos(pi k / n)``; so ``Q`` is the two-axis DCT (:func:`scipy.fft.dctn`), exact
and ``O(n log n)``, and no matrix is formed. Each mode is a damped oscillator ``omega^2 = lambda / m``, ``2 zeta omega = c / m``. A step of length
``h`` with the acceleration held constant over the step (zero-order hold, the skeleton's
acceleration estimated from its last three placements) is the exact solution
``[e, e'](t + h) = Phi(h) [e, e'](t) + Gamma(h) a``, with ``Phi`` and ``Gamma`` from the matrix
exponential of each mode's 3 x 3 augmented matrix (:func:`scipy.linalg.expm`, batched). The
spectral radius of ``Phi(h)`` is ``exp(-c h / (2 m))`` or below for every ``h > 0``: **any time
step is stable** (``c > 0``); the step only sets how finely the skeleton's motion is sampled.

Energy decay
------------
``E = 1/2 m |e'|^2 + 1/2 e^T K e``. With no skeleton motion, per mode
``V = E + zeta omega m e e'`` obeys ``V(t) = V(0) exp(-2 zeta omega t)`` exactly, and
``(1 - zeta) E <= V <= (1 + zeta) E``; since ``zeta omega = c / (2 m)`` for every mode, for
underdamped modes (``zeta < 1``)

.. math::

    E(t) \\le E(0)\\, \\frac{1 + \\zeta_{max}}{1 - \\zeta_{max}}\\, e^{-c t / m},

which :meth:`SoftTissue.settle_time` inverts (the constructor refuses overdamped settings, whose
slow modes would not follow this bound).

References
----------
D. R. Forsey, "A surface model for skeleton-based character animation", 1991; course notes C25,
SIGGRAPH 1991, §5-47.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import scipy.linalg
from numpy.typing import NDArray

from ..errors import InvalidGeometryError
from .figures import AttachedSurface, set_base_points, set_world_points
from .skeleton import Pose
from .surface import HierarchicalSurface

__all__ = ["SoftTissue", "grid_laplacian", "grid_laplacian_eigenvalues", "PROPAGATOR_CACHE"]

#: Propagators kept per :class:`SoftTissue`, one per distinct time step (oldest dropped first).
PROPAGATOR_CACHE = 8

Array = NDArray[np.float64]


def grid_laplacian(shape: tuple[int, int]) -> Array:
    """The graph Laplacian (dense, symmetric) of a ``shape`` grid with 4-neighbour edges."""
    nu, nv = shape

    def path(n: int) -> Array:
        P = np.zeros((n, n))
        i = np.arange(n - 1)
        P[i, i + 1] = P[i + 1, i] = -1.0
        P[np.arange(n), np.arange(n)] = -P.sum(1)
        return P

    return np.kron(path(nu), np.eye(nv)) + np.kron(np.eye(nu), path(nv))


def grid_laplacian_eigenvalues(shape: tuple[int, int]) -> Array:
    """Eigenvalues of :func:`grid_laplacian` in the order of the two-axis orthonormal DCT-II
    coefficients, shape ``shape``: ``(2 - 2 cos(pi i / n_u)) + (2 - 2 cos(pi j / n_v))``."""
    nu, nv = shape
    return (2.0 - 2.0 * np.cos(np.pi * np.arange(nu) / nu))[:, None] + (2.0 - 2.0 * np.cos(np.pi * np.arange(nv) / nv))


def _positive(x: float, name: str, zero_ok: bool = False) -> float:
    if isinstance(x, bool):
        raise InvalidGeometryError(f"{name}: expected a number, got {x!r}")
    try:
        v = float(x)
    except (TypeError, ValueError):
        raise InvalidGeometryError(f"{name}: expected a number, got {x!r}") from None
    if not (math.isfinite(v) and (v >= 0 if zero_ok else v > 0)):
        raise InvalidGeometryError(f"{name}: expected a finite number {'>= 0' if zero_ok else '> 0'}, got {x!r}")
    return v


class SoftTissue:
    """One level of an attached surface made dynamic (course §5-47, see the module notes).

    Parameters
    ----------
    figure : AttachedSurface
    level : int, default 0
        The dynamic level: 0 for the base, or an overlay id.
    mass, stiffness, coupling, damping : float
        ``m`` per vertex, anchor stiffness ``k_a``, neighbour coupling ``k_n`` (>= 0) and damping
        ``c``, in consistent units (e.g. seconds and model units).
    pose : Pose, optional
        The starting pose (default: rest), at rest relative to it (``e = e' = 0``).

    Raises
    ------
    InvalidGeometryError
        Non-positive or non-finite parameters, an unknown level, or a setting whose slowest mode is
        not underdamped (``c >= 2 sqrt(m k_a)``).
    """

    def __init__(self, figure: AttachedSurface, level: int = 0, *, mass: float = 1.0, stiffness: float = 400.0,
                 coupling: float = 100.0, damping: float = 6.0, pose: Pose | None = None) -> None:
        if not isinstance(figure, AttachedSurface):
            raise InvalidGeometryError(f"figure: expected an AttachedSurface, got {type(figure).__name__}")
        self.figure = figure
        rest = figure.rest
        if isinstance(level, bool) or not isinstance(level, (int, np.integer)) or (
                level != 0 and level not in {o.id for o in rest.overlays}):
            raise InvalidGeometryError(f"level: the surface has no overlay {level!r} (0 is the base)")
        self.level = int(level)
        self.mass = _positive(mass, "mass")
        self.stiffness = _positive(stiffness, "stiffness")
        self.coupling = _positive(coupling, "coupling", zero_ok=True)
        self.damping = _positive(damping, "damping")
        shape = rest.base.n_poles if level == 0 else next(o for o in rest.overlays if o.id == level).shape
        self.shape = (int(shape[0]), int(shape[1]))
        self._lam = (self.stiffness + self.coupling * grid_laplacian_eigenvalues(self.shape)).reshape(-1)  # of K
        omega = np.sqrt(self._lam / self.mass)
        self.zeta_max = float(self.damping / (2.0 * self.mass * omega.min()))
        if not self.zeta_max < 1.0:
            raise InvalidGeometryError(f"damping: the slowest mode is overdamped (zeta = {self.zeta_max:.3g} >= 1); "
                                       f"use damping < {2.0 * math.sqrt(self.mass * self.stiffness):.6g}")
        self._props: dict[float, tuple[Array, Array]] = {}
        start = pose if pose is not None else figure.skeleton.pose()
        self.time = 0.0
        self._pose = start
        T = self._kinematic(start)
        self._T = [T, T]  # the last two kinematic places (for the velocity and acceleration)
        self._h_last: float | None = None
        n = T.shape[0]
        self._e = np.zeros((n, 3))  # modal coordinates of the deviation
        self._de = np.zeros((n, 3))

    # ------------------------------------------------------------------ pieces
    def _to_modes(self, x: Array) -> Array:
        """World vectors (n, 3) on the net -> modal coordinates (n, 3) (orthonormal: Q^T x)."""
        import scipy.fft  # here, as in _from_modes: not at every process's start

        X = scipy.fft.dctn(x.reshape(self.shape + (3,)), type=2, norm="ortho", axes=(0, 1))
        return np.asarray(X).reshape(-1, 3)

    def _from_modes(self, m: Array) -> Array:
        """Modal coordinates (n, 3) -> world vectors (n, 3) (Q m)."""
        import scipy.fft

        X = scipy.fft.idctn(m.reshape(self.shape + (3,)), type=2, norm="ortho", axes=(0, 1))
        return np.asarray(X).reshape(-1, 3)

    def _kinematic(self, pose: Pose) -> Array:
        hs = self.figure.at(pose)
        self._hs = hs
        pts = hs.base.control_points if self.level == 0 else hs.control_points(self.level)
        return np.asarray(pts, float).reshape(-1, 3)

    def propagator(self, h: float) -> tuple[Array, Array]:
        """Per mode, ``Phi(h)`` (n, 2, 2) and ``Gamma(h)`` (n, 2) of the exact step (module notes)."""
        h = _positive(h, "dt")
        if h not in self._props:
            if len(self._props) >= PROPAGATOR_CACHE:  # frame-timed (jittered) steps: keep the newest
                del self._props[next(iter(self._props))]
            n = self._lam.size
            A = np.zeros((n, 3, 3))
            A[:, 0, 1] = 1.0
            A[:, 1, 0] = -self._lam / self.mass
            A[:, 1, 1] = -self.damping / self.mass
            A[:, 1, 2] = -1.0  # the input: the skeleton's acceleration
            E = scipy.linalg.expm(A * h)
            self._props[h] = (E[:, :2, :2].copy(), E[:, :2, 2].copy())
        return self._props[h]

    def settle_time(self, fraction: float = 0.01) -> float:
        """Time after the skeleton stops within which the energy falls below ``fraction`` of its
        value at the stop (the bound of the module notes)."""
        f = _positive(fraction, "fraction")
        z = self.zeta_max
        return float(math.log((1.0 + z) / ((1.0 - z) * f)) * self.mass / self.damping)

    def energy(self) -> float:
        """Kinetic plus spring energy of the deviation (module notes)."""
        return float(0.5 * self.mass * np.sum(self._de ** 2) + 0.5 * np.sum(self._lam[:, None] * self._e ** 2))

    @property
    def deviation(self) -> Array:
        """World deviation ``x - T`` of the level's vertices, shape ``shape + (3,)``."""
        return self._from_modes(self._e).reshape(self.shape + (3,))

    # ------------------------------------------------------------------ stepping
    def step(self, pose: Pose, dt: float) -> HierarchicalSurface:
        """Advance by ``dt`` to the skeleton in ``pose``; returns the surface with the dynamic level
        displaced (finer levels carried by offset referencing).

        The skeleton's acceleration over the step is estimated from its last three kinematic places
        (second difference), held constant over the step (zero-order hold).
        """
        h = _positive(dt, "dt")
        Phi, Gam = self.propagator(h)
        T_new = self._kinematic(pose)
        T0, T1 = self._T
        v_new = (T_new - T1) / h
        v_old = np.zeros_like(v_new) if self._h_last is None else (T1 - T0) / self._h_last
        acc = self._to_modes((v_new - v_old) / h)
        e = Phi[:, 0, 0, None] * self._e + Phi[:, 0, 1, None] * self._de + Gam[:, 0, None] * acc
        de = Phi[:, 1, 0, None] * self._e + Phi[:, 1, 1, None] * self._de + Gam[:, 1, None] * acc
        self._e, self._de = e, de
        self._T = [T1, T_new]
        self._h_last = h
        self.time += h
        self._pose = pose
        return self.surface()

    def surface(self) -> HierarchicalSurface:
        """The surface now: the current pose with the dynamic level's deviation applied."""
        hs = self._hs.copy()
        x = self._T[1].reshape(self.shape + (3,)) + self.deviation
        if self.level == 0:
            set_base_points(hs, x)
        else:
            set_world_points(hs, self.level, x)
        return hs

    def to_dict(self) -> dict[str, Any]:
        """The parameters (not the state) as JSON-ready data; the figure is stored separately."""
        return {"type": "SoftTissue", "level": self.level, "mass": self.mass, "stiffness": self.stiffness,
                "coupling": self.coupling, "damping": self.damping}
