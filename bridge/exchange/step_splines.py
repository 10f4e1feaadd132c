"""B-spline entities of a STEP file that OCC will refuse, found before its transfer (and named).

OCC's STEP transfer drops a face whose surface is a ``B_SPLINE_SURFACE_WITH_KNOTS`` it cannot build
(degree 1e9 or -3, a multiplicity of 2e9, decreasing knots...) and says nothing that names it: the
model just has one face fewer. :func:`spline_problems` reads the parameters of every simple
``B_SPLINE_SURFACE_WITH_KNOTS`` and ``B_SPLINE_CURVE_WITH_KNOTS`` instance and checks what
``Geom_BSplineSurface`` / ``Geom_BSplineCurve`` require (OCC 7.9: degree 1..25, knots strictly
increasing, multiplicities from 1 to degree + 1 summing to poles + degree + 1), naming the instance,
the problem, and the faces that use the surface. Complex (rational) instances are not parsed here.
"""

from __future__ import annotations

import re

__all__ = ["spline_problems", "MAX_DEGREE"]

#: ``Geom_BSplineSurface::MaxDegree()`` / ``Geom_BSplineCurve::MaxDegree()`` in OCC 7.9.
MAX_DEGREE = 25

_INT = re.compile(rb"^[+-]?\d+$")


def _params(text: bytes, at: int) -> list[bytes] | None:
    """The top-level parameters of the instance whose ``(`` is at ``at`` (None if unbalanced)."""
    depth, out, start = 0, [], at + 1
    for k in range(at, len(text)):
        c = text[k:k + 1]
        if c == b"(":
            depth += 1
        elif c == b")":
            depth -= 1
            if depth == 0:
                out.append(text[start:k].strip())
                return out
        elif c == b"," and depth == 1:
            out.append(text[start:k].strip())
            start = k + 1
    return None


def _items(param: bytes) -> list[bytes]:
    """The items of a list parameter ``(a,b,...)`` (one level)."""
    inner = param.strip()
    if not (inner.startswith(b"(") and inner.endswith(b")")):
        return []
    body = _params(inner, 0)
    return [] if body is None or body == [b""] else body


def _ints(param: bytes) -> list[int] | None:
    items = _items(param)
    return [int(x) for x in items] if items and all(_INT.match(x) for x in items) else None


def _floats(param: bytes) -> list[float] | None:
    try:
        items = _items(param)
        return [float(x.replace(b"D", b"E").replace(b"d", b"e")) for x in items] if items else None
    except ValueError:
        return None


def _check(degree: bytes, n_poles: int, mults: bytes, knots: bytes, what: str) -> str | None:
    """What ``Geom_BSpline*`` would refuse in one direction, or None."""
    if not _INT.match(degree):
        return None  # not a number: OCC's own check reports it
    p = int(degree)
    if not 1 <= p <= MAX_DEGREE:
        return f"{what}degree {p} is outside 1..{MAX_DEGREE}"
    m, u = _ints(mults), _floats(knots)
    if m is None or u is None:
        return None
    if len(m) != len(u):
        return f"{len(m)} {what}multiplicities for {len(u)} {what}knots"
    bad = next((x for x in m if not 1 <= x <= p + 1), None)
    if bad is not None:
        return f"{what}multiplicity {bad} is outside 1..{p + 1} (degree + 1)"
    if any(b <= a for a, b in zip(u, u[1:])):
        return f"{what}knots are not strictly increasing"
    if sum(m) != n_poles + p + 1:
        return f"{what}multiplicities sum to {sum(m)}, not poles + degree + 1 = {n_poles + p + 1}"
    return None


def spline_problems(ids: list[int], types: list[str], texts: list[bytes], body_at: list[int],
                    refs_per: list[list[int]]) -> list[str]:
    """One line per B-spline instance OCC will refuse: ``#38 B_SPLINE_SURFACE_WITH_KNOTS: udegree
    1000000000 is outside 1..25 (face #12 is dropped)``. The arguments are :func:`.checks.scan_step`'s
    per-instance lists (``texts`` masked)."""
    users: dict[int, list[int]] = {}
    for j, t in enumerate(types):
        if t in ("ADVANCED_FACE", "FACE_SURFACE"):
            for r in refs_per[j]:
                users.setdefault(r, []).append(ids[j])
    out = []
    for j, t in enumerate(types):
        if t not in ("B_SPLINE_SURFACE_WITH_KNOTS", "B_SPLINE_CURVE_WITH_KNOTS"):
            continue
        text = texts[j]
        at = text.find(b"(", body_at[j])
        ps = _params(text, at) if at >= 0 else None
        if ps is None:
            continue
        why = None
        if t == "B_SPLINE_SURFACE_WITH_KNOTS" and len(ps) >= 12:
            rows = _items(ps[3])
            nu, nv = len(rows), (len(_items(rows[0])) if rows else 0)
            why = (_check(ps[1], nu, ps[8], ps[10], "u-") or _check(ps[2], nv, ps[9], ps[11], "v-"))
        elif t == "B_SPLINE_CURVE_WITH_KNOTS" and len(ps) >= 8:
            why = _check(ps[1], len(_items(ps[2])), ps[6], ps[7], "")
        if why is not None:
            faces = users.get(ids[j], [])
            dropped = f" (face {', '.join(f'#{f}' for f in faces)} is dropped)" if faces else ""
            out.append(f"#{ids[j]} {t}: {why}; OCC cannot build it{dropped}")
    return out
