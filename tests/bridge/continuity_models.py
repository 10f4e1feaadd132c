"""Closed-form two-face models for the continuity tests, built with OCC directly.

Every model is two faces meeting along the line ``x = 0, 0 <= y <= 1``: face A is the plane patch
``-1 <= x <= 0, z = 0``; face B continues it for ``x >= 0`` in a way whose continuity is known:

=================  =====================================================  =====================
``coplanar``       plane ``0 <= x <= 1``                                  all measures 0
``offset(d)``      plane at ``z = d``                                      G0 = d
``crease(deg)``    plane turned by ``deg`` about the shared line           G1 = deg
``cylinder(R)``    cylinder of radius R tangent to A along the line        G1 = 0, G2 = 1/R, 100 %
``cubic(c)``       B-spline ``z = c x^3``                                  G2 = 0, G3 = 6 c
=================  =====================================================  =====================

:func:`sewn` makes a shell of the two faces (shared edge: ``matched == 'topology'``); the faces alone
(:func:`loose`) are matched geometrically.
"""

from __future__ import annotations

import math

import numpy as np
from OCP.BRep import BRep_Builder
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace, BRepBuilderAPI_Sewing
from OCP.Geom import Geom_BSplineSurface, Geom_CylindricalSurface, Geom_Plane
from OCP.gp import gp_Ax3, gp_Dir, gp_Pnt
from OCP.TopoDS import TopoDS_Compound

from occsurf.bridge._occ import int_array, pnt_array2, real_array


def plane_face(origin, xdir, ydir, u0=0.0, u1=1.0, v0=0.0, v1=1.0):
    """Face of the plane through ``origin`` spanned by ``xdir``, ``ydir`` (u along xdir, v along ydir)."""
    n = np.cross(xdir, ydir)
    ax = gp_Ax3(gp_Pnt(*origin), gp_Dir(*n), gp_Dir(*xdir))
    return BRepBuilderAPI_MakeFace(Geom_Plane(ax), u0, u1, v0, v1, 1e-7).Face()


def face_a():
    return plane_face((0, 0, 0), (1, 0, 0), (0, 1, 0), -1.0, 0.0)


def face_b(kind: str, value: float = 0.0):
    if kind == "coplanar":
        return plane_face((0, 0, 0), (1, 0, 0), (0, 1, 0))
    if kind == "offset":
        return plane_face((0, 0, value), (1, 0, 0), (0, 1, 0))
    if kind == "crease":
        a = math.radians(value)
        return plane_face((0, 0, 0), (math.cos(a), 0, math.sin(a)), (0, 1, 0))
    if kind == "cylinder":  # axis along y through (0, 0, R); u from -90 deg (the point (0, 0, 0)) to 0
        R = value
        ax = gp_Ax3(gp_Pnt(0, 0, R), gp_Dir(0, -1, 0), gp_Dir(1, 0, 0))
        # Z = -y, X = x, so Y = Z x X = +z: P(u, v) = (R cos u, -v, R + R sin u), u = -90 deg at the line
        surf = Geom_CylindricalSurface(ax, R)
        return BRepBuilderAPI_MakeFace(surf, -math.pi / 2, 0.0, -1.0, 0.0, 1e-7).Face()
    if kind == "cubic":  # z = c x^3, x in [0, 1], y in [0, 1]: Bezier poles z = 0, 0, 0, c
        c = value
        P = np.zeros((4, 2, 3))
        for i in range(4):
            for j in range(2):
                P[i, j] = (i / 3, j, c if i == 3 else 0.0)
        s = Geom_BSplineSurface(pnt_array2(P), real_array([0.0, 1.0]), real_array([0.0, 1.0]),
                                int_array([4, 4]), int_array([2, 2]), 3, 1)
        return BRepBuilderAPI_MakeFace(s, 1e-7).Face()
    raise ValueError(kind)


def sewn(kind: str, value: float = 0.0, tol: float = 1e-6):
    sew = BRepBuilderAPI_Sewing(tol)
    sew.Add(face_a())
    sew.Add(face_b(kind, value))
    sew.Perform()
    return sew.SewedShape()


def loose(kind: str, value: float = 0.0):
    comp = TopoDS_Compound()
    bld = BRep_Builder()
    bld.MakeCompound(comp)
    bld.Add(comp, face_a())
    bld.Add(comp, face_b(kind, value))
    return comp
