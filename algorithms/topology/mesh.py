"""Polygon meshes of arbitrary topology: the control meshes of generalized B-splines (course §8-6).

:class:`Mesh` holds vertices ``(V, 3)`` and faces given as lists of vertex indices of any side
count (3 or more), oriented consistently (counter-clockwise seen from the side the normal points
to). At construction the half-edge adjacency is built once and the mesh is checked to be an
oriented 2-manifold, possibly with boundary; anything else is an :class:`InvalidGeometryError`
naming the face, edge or vertex at fault:

* a face with fewer than 3 vertices, a repeated vertex, or an index out of range;
* an edge used by more than two faces, or twice in the same direction (inconsistent orientation);
* a vertex whose faces do not form one fan (two cones touching at a vertex, "bow-tie").

Queries (valence, ordered one-ring, ordered faces around a vertex, face neighbours, boundary edges
and vertices, Euler characteristic) answer from the half-edge tables. :func:`catmull_clark` does one
step of Catmull–Clark refinement (Catmull & Clark 1978), which makes every face a quadrilateral; the
generalized biquadratic scheme (:mod:`occsurf.algorithms.topology.generalized`) asks for such meshes.

:func:`read_obj` and :func:`write_obj` read and write the Wavefront OBJ subset that describes a
polygon mesh (``v`` and ``f`` records; texture/normal indices, groups, materials and comments are
skipped), in plain Python, with the file name and line number in every error.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from .._files import atomic_write
from ..errors import ExchangeError, InvalidGeometryError

__all__ = ["Mesh", "read_obj", "write_obj", "catmull_clark", "doo_sabin"]

Array = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class Mesh:
    """An oriented polygon mesh (2-manifold, possibly with boundary).

    Parameters
    ----------
    vertices : array_like, shape (V, 3)
        Vertex positions (2-D positions are accepted and stored with z = 0).
    faces : sequence of sequences of int
        Each face lists ``>= 3`` distinct vertex indices, counter-clockwise seen from outside.

    Raises
    ------
    InvalidGeometryError
        For bad shapes, non-finite coordinates, out-of-range or repeated indices, and meshes that
        are not oriented 2-manifolds (the message names the face, edge or vertex).

    Examples
    --------
    >>> m = Mesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2, 3]])
    >>> m.valence(0), m.is_closed
    (2, False)
    """

    vertices: Array
    faces: tuple[tuple[int, ...], ...]
    _next: dict[tuple[int, int], int] = field(init=False, repr=False)  # directed edge -> face
    _fans: tuple[tuple[int, ...], ...] = field(init=False, repr=False)
    _boundary_vertex: NDArray[np.bool_] = field(init=False, repr=False)

    if TYPE_CHECKING:  # the generated __init__ takes array_like / nested sequences; __post_init__ stores these

        def __init__(self, vertices: ArrayLike, faces: Sequence[Sequence[int]] | NDArray[np.integer]) -> None: ...

    def __post_init__(self) -> None:
        P = V.as_finite_array(self.vertices, "vertices", ndim=2)
        if P.shape[1] == 2:
            P = np.column_stack((P, np.zeros(P.shape[0])))
        if P.shape[1] != 3 or P.shape[0] < 3:
            raise InvalidGeometryError(f"vertices: expected shape (V, 3) with V >= 3, got {P.shape}")
        nv = P.shape[0]
        faces: list[tuple[int, ...]] = []
        if isinstance(self.faces, (str, bytes)) or not isinstance(self.faces, Sequence) and not isinstance(self.faces, np.ndarray):
            raise InvalidGeometryError(f"faces: expected a sequence of vertex-index lists, got {type(self.faces).__name__}")
        if len(self.faces) == 0:
            raise InvalidGeometryError("faces: expected at least one face, got none")
        for i, f in enumerate(self.faces):
            try:
                idx = [int(v) for v in f]
            except (TypeError, ValueError) as err:
                raise InvalidGeometryError(f"faces[{i}]: expected a list of vertex indices, got {f!r}") from err
            if any(float(a) != b for a, b in zip(f, idx)):
                raise InvalidGeometryError(f"faces[{i}]: vertex indices must be integers, got {list(f)!r}")
            if len(idx) < 3:
                raise InvalidGeometryError(f"faces[{i}]: a face needs at least 3 vertices, got {len(idx)}")
            bad = [v for v in idx if not 0 <= v < nv]
            if bad:
                raise InvalidGeometryError(f"faces[{i}]: vertex index {bad[0]} out of range [0, {nv - 1}]")
            if len(set(idx)) != len(idx):
                raise InvalidGeometryError(f"faces[{i}]: repeated vertex in {idx}")
            faces.append(tuple(idx))
        half: dict[tuple[int, int], int] = {}
        # An edge with three or more faces uses one direction twice, so this one check also
        # catches non-manifold edges.
        for i, f in enumerate(faces):
            for a, b in zip(f, f[1:] + f[:1]):
                if (a, b) in half:
                    raise InvalidGeometryError(
                        f"faces: edge ({a}, {b}) is used in the same direction by faces {half[(a, b)]} and {i}: "
                        "the orientation is inconsistent or the edge is non-manifold"
                    )
                half[(a, b)] = i
        # faces around each vertex, as one counter-clockwise fan
        around: list[list[int]] = [[] for _ in range(nv)]
        for i, f in enumerate(faces):
            for v in f:
                around[v].append(i)
        fans: list[tuple[int, ...]] = []
        bnd = np.zeros(nv, dtype=bool)
        for v in range(nv):
            fs = around[v]
            if not fs:
                fans.append(())
                continue
            # start at a face whose edge v -> next has no twin (boundary), if any
            start = fs[0]
            for fi in fs:
                nxt = _next_of(faces[fi], v)
                if (nxt, v) not in half:
                    start, bnd[v] = fi, True
                    break
            fan = [start]
            while True:
                prv = _prev_of(faces[fan[-1]], v)
                g = half.get((v, prv))
                if g is None or g == start:
                    break
                if g in fan:  # cannot happen for a consistent manifold, but never loop forever
                    break
                fan.append(g)
            if len(fan) != len(fs):
                raise InvalidGeometryError(
                    f"faces: vertex {v} is non-manifold: its {len(fs)} faces do not form one fan "
                    f"(a single fan holds {len(fan)} of them)"
                )
            fans.append(tuple(fan))
        object.__setattr__(self, "vertices", V.readonly(P))
        object.__setattr__(self, "faces", tuple(faces))
        object.__setattr__(self, "_next", half)
        object.__setattr__(self, "_fans", tuple(fans))
        object.__setattr__(self, "_boundary_vertex", V.readonly(bnd))

    # ------------------------------------------------------------------ sizes
    @property
    def n_vertices(self) -> int:
        return self.vertices.shape[0]

    @property
    def n_faces(self) -> int:
        return len(self.faces)

    @property
    def edges(self) -> NDArray[np.intp]:
        """Undirected edges ``(E, 2)`` with ``a < b``, sorted."""
        e = sorted({(min(a, b), max(a, b)) for a, b in self._next})
        return np.array(e, dtype=np.intp).reshape(-1, 2)

    @property
    def n_edges(self) -> int:
        return self.edges.shape[0]

    @property
    def euler_characteristic(self) -> int:
        """``V - E + F`` (vertices used by no face are not counted)."""
        used = sum(1 for f in self._fans if f)
        return used - self.n_edges + self.n_faces

    @property
    def boundary_edges(self) -> NDArray[np.intp]:
        """Directed edges ``(B, 2)`` that have a face on one side only, in that face's direction."""
        e = sorted((a, b) for a, b in self._next if (b, a) not in self._next)
        return np.array(e, dtype=np.intp).reshape(-1, 2)

    @property
    def is_closed(self) -> bool:
        """True if every edge has two faces."""
        return self.boundary_edges.shape[0] == 0

    @property
    def is_quad(self) -> bool:
        """True if every face has four sides."""
        return all(len(f) == 4 for f in self.faces)

    def genus(self) -> int:
        """Genus of a closed connected mesh: ``(2 - χ) / 2``.

        Raises
        ------
        InvalidGeometryError
            If the mesh has boundary or more than one connected component.
        """
        if not self.is_closed:
            raise InvalidGeometryError("genus: the mesh has boundary edges; genus is defined here for closed meshes")
        if len(self.components()) != 1:
            raise InvalidGeometryError(f"genus: the mesh has {len(self.components())} components, expected 1")
        return (2 - self.euler_characteristic) // 2

    def components(self) -> list[list[int]]:
        """Face indices of each edge-connected component."""
        seen = np.zeros(self.n_faces, dtype=bool)
        out = []
        for s in range(self.n_faces):
            if seen[s]:
                continue
            stack, comp = [s], []
            seen[s] = True
            while stack:
                f = stack.pop()
                comp.append(f)
                for g in self.face_neighbours(f):
                    if g >= 0 and not seen[g]:
                        seen[g] = True
                        stack.append(g)
            out.append(sorted(comp))
        return out

    # ------------------------------------------------------------------ adjacency
    def _vertex(self, v: object) -> int:
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not 0 <= int(v) < self.n_vertices:
            raise InvalidGeometryError(f"v: expected a vertex index from 0 to {self.n_vertices - 1}, got {v!r}")
        return int(v)

    def _face(self, f: object) -> int:
        if isinstance(f, bool) or not isinstance(f, (int, np.integer)) or not 0 <= int(f) < self.n_faces:
            raise InvalidGeometryError(f"f: expected a face index from 0 to {self.n_faces - 1}, got {f!r}")
        return int(f)

    def is_boundary_vertex(self, v: int) -> bool:
        """True if ``v`` lies on a boundary edge."""
        return bool(self._boundary_vertex[self._vertex(v)])

    @property
    def boundary_vertices(self) -> NDArray[np.intp]:
        """Indices of the vertices on boundary edges."""
        return np.flatnonzero(self._boundary_vertex)

    def vertex_faces(self, v: int) -> tuple[int, ...]:
        """Faces around ``v`` in counter-clockwise order (seen from outside).

        Face ``i + 1`` shares with face ``i`` the edge from ``v`` to the vertex that precedes ``v`` in
        face ``i``. For a boundary vertex the fan starts at the face after the boundary edge that
        leaves ``v``.
        """
        return self._fans[self._vertex(v)]

    def one_ring(self, v: int) -> tuple[int, ...]:
        """Neighbours of ``v`` (joined by an edge), counter-clockwise, ``e_k`` = successor of ``v``
        in face ``k`` of :meth:`vertex_faces`; a boundary vertex adds the last face's predecessor."""
        v = self._vertex(v)
        fan = self._fans[v]
        ring = [_next_of(self.faces[f], v) for f in fan]
        if self._boundary_vertex[v] and fan:
            ring.append(_prev_of(self.faces[fan[-1]], v))
        return tuple(ring)

    def valence(self, v: int) -> int:
        """Number of edges at ``v``."""
        return len(self.one_ring(v))

    def face_neighbours(self, f: int) -> tuple[int, ...]:
        """Face across each edge of face ``f`` (edge ``i`` joins corners ``i`` and ``i + 1``); -1 on
        boundary edges."""
        face = self.faces[self._face(f)]
        return tuple(self._next.get((b, a), -1) for a, b in zip(face, face[1:] + face[:1]))

    def face_of_edge(self, a: int, b: int) -> int:
        """The face that has the directed edge ``a -> b``, or -1."""
        return self._next.get((int(a), int(b)), -1)

    def face_centroids(self) -> Array:
        """Average of each face's vertices, shape ``(F, 3)``."""
        return np.array([self.vertices[list(f)].mean(axis=0) for f in self.faces])

    def with_vertices(self, vertices: ArrayLike) -> Mesh:
        """The same connectivity with new vertex positions ``(V, 3)``."""
        P = V.as_finite_array(vertices, "vertices", ndim=2)
        if P.shape != self.vertices.shape:
            raise InvalidGeometryError(f"vertices: expected shape {self.vertices.shape}, got {P.shape}")
        return Mesh(P, self.faces)

    def __repr__(self) -> str:
        return f"Mesh(vertices={self.n_vertices}, faces={self.n_faces}, closed={self.is_closed})"


def _next_of(face: tuple[int, ...], v: int) -> int:
    i = face.index(v)
    return face[(i + 1) % len(face)]


def _prev_of(face: tuple[int, ...], v: int) -> int:
    i = face.index(v)
    return face[i - 1]


# ---------------------------------------------------------------------------- refinement
def catmull_clark(mesh: Mesh) -> Mesh:
    """One step of Catmull–Clark refinement (Catmull & Clark 1978, "Recursively generated B-spline
    surfaces on arbitrary topological meshes"): every ``k``-sided face becomes ``k`` quadrilaterals.

    Face points are face centroids; interior edge points average the edge's ends and the two face
    points; an interior vertex of valence ``n`` moves to ``(Q + 2R + (n - 3) S) / n`` (``Q`` the mean
    of its face points, ``R`` of its edge midpoints). On the boundary the cubic B-spline curve rules
    are used (edge point = midpoint; vertex = ``(a + 6 S + b) / 8``), so the boundary curve refines as
    a uniform cubic B-spline.

    Returns
    -------
    Mesh
        Vertex order: the old vertices, then one point per face, then one per edge (in
        :attr:`Mesh.edges` order). New vertices created from faces take the face's valence.
    """
    P = mesh.vertices
    nv, nf = mesh.n_vertices, mesh.n_faces
    E = mesh.edges
    eid = {(int(a), int(b)): i for i, (a, b) in enumerate(E)}
    fp = mesh.face_centroids()
    ep = np.empty((E.shape[0], 3))
    for i, (a, b) in enumerate(E):
        f1, f2 = mesh.face_of_edge(a, b), mesh.face_of_edge(b, a)
        if f1 >= 0 and f2 >= 0:
            ep[i] = (P[a] + P[b] + fp[f1] + fp[f2]) / 4.0
        else:
            ep[i] = (P[a] + P[b]) / 2.0
    newP = P.copy()
    for v in range(nv):
        fan = mesh.vertex_faces(v)
        if not fan:
            continue
        ring = mesh.one_ring(v)
        if mesh.is_boundary_vertex(v):
            a, b = ring[0], ring[-1]
            newP[v] = (P[a] + 6.0 * P[v] + P[b]) / 8.0
        else:
            n = len(ring)
            Q = fp[list(fan)].mean(axis=0)
            R = ((P[list(ring)] + P[v]) / 2.0).mean(axis=0)
            newP[v] = (Q + 2.0 * R + (n - 3.0) * P[v]) / n
    faces = []
    for fi, f in enumerate(mesh.faces):
        k = len(f)
        for i in range(k):
            a, b, c = f[i - 1], f[i], f[(i + 1) % k]
            e_in = nv + nf + eid[(min(a, b), max(a, b))]
            e_out = nv + nf + eid[(min(b, c), max(b, c))]
            faces.append((b, e_out, nv + fi, e_in))
    return Mesh(np.vstack((newP, fp, ep)), faces)


def doo_sabin(mesh: Mesh) -> Mesh:
    """One step of Doo–Sabin refinement (Doo & Sabin 1978, "Behaviour of recursive division surfaces
    near extraordinary points"): afterwards every interior vertex has valence 4.

    Each corner ``v`` of a face with ``k`` vertices ``v = x_0, x_1, ..., x_{k-1}`` gets a new vertex
    ``Σ_i α_i x_i`` with ``α_0 = 1/4 + 5/(4k)`` and ``α_i = (3 + 2 cos(2π i / k)) / (4k)`` (for
    ``k = 4`` the biquadratic B-spline rule 9/16, 3/16, 1/16, 3/16). New faces: one per old face
    (its corners' new vertices), one quadrilateral per interior edge, and one per interior vertex
    (the new vertices of its faces, a polygon with as many sides as the vertex's valence).
    Boundary edges and boundary vertices make no face.

    Returns
    -------
    Mesh
        Vertex order: face by face, corner by corner (the order of :attr:`Mesh.faces`).
    """
    P = mesh.vertices
    corner: dict[tuple[int, int], int] = {}  # (face, old vertex) -> new vertex
    pts: list[Array] = []
    for fi, f in enumerate(mesh.faces):
        k = len(f)
        i = np.arange(k)
        alpha = (3.0 + 2.0 * np.cos(2.0 * np.pi * i / k)) / (4.0 * k)
        alpha[0] = 0.25 + 5.0 / (4.0 * k)
        X = P[list(f)]
        for c in range(k):
            corner[(fi, f[c])] = len(pts)
            pts.append(alpha @ np.roll(X, -c, axis=0))
    faces: list[tuple[int, ...]] = [tuple(corner[(fi, v)] for v in f) for fi, f in enumerate(mesh.faces)]
    for a, b in mesh.edges:
        f1, f2 = mesh.face_of_edge(a, b), mesh.face_of_edge(b, a)
        if f1 >= 0 and f2 >= 0:  # f1 has a -> b, f2 has b -> a: the quad runs b, a in f1 then a, b in f2
            faces.append((corner[(f1, b)], corner[(f1, a)], corner[(f2, a)], corner[(f2, b)]))
    for v in range(mesh.n_vertices):
        fan = mesh.vertex_faces(v)
        if fan and not mesh.is_boundary_vertex(v):
            faces.append(tuple(corner[(f, v)] for f in fan))
    return Mesh(np.array(pts), faces)


# ---------------------------------------------------------------------------- OBJ files
#: OBJ records that carry nothing a polygon mesh needs (texture/normal data, grouping, materials,
#: lines/points and free-form records); they are skipped.
_SKIPPED = frozenset(("vt", "vn", "vp", "o", "g", "s", "usemtl", "mtllib", "l", "p",
                      "cstype", "deg", "bmat", "step", "curv", "curv2", "surf", "parm", "trim", "hole", "end"))

def read_obj(path: str | os.PathLike[str]) -> Mesh:
    """Read a polygon mesh from a Wavefront OBJ file.

    ``v x y z [w]`` records give vertices (a 4th homogeneous coordinate divides the others);
    ``f a b c ...`` records give faces, each token ``i``, ``i/t``, ``i//n`` or ``i/t/n`` with 1-based or
    negative (relative) vertex indices. Other records (``vt``, ``vn``, ``o``, ``g``, ``s``,
    ``usemtl``, ``mtllib``, comments) are skipped; line continuations (``\\``) are joined.

    Raises
    ------
    ExchangeError
        If the file is missing or unreadable, has a malformed ``v``/``f`` record (file and line
        number in the message) or has no faces.
    InvalidGeometryError
        If the faces do not form an oriented 2-manifold (see :class:`Mesh`).
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8", errors="strict")
    except FileNotFoundError as err:
        raise ExchangeError(f"read_obj: no such file: {p}") from err
    except (OSError, UnicodeDecodeError) as err:
        raise ExchangeError(f"read_obj: cannot read {p}: {err}") from err
    verts: list[tuple[float, float, float]] = []
    faces: list[list[int]] = []
    lines = text.replace("\\\r\n", " ").replace("\\\n", " ").splitlines()
    for lineno, raw in enumerate(lines, 1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        tok = line.split()
        key = tok[0]
        where = f"{p.name}:{lineno}"
        if key == "v":
            if len(tok) not in (4, 5, 7, 8):
                raise ExchangeError(f"read_obj: {where}: a 'v' record needs 3 (or 4) numbers, optionally followed by "
                                    f"an r g b colour, got {len(tok) - 1}: {raw.strip()!r}")
            try:
                # "v x y z r g b" (MeshLab, scanners) carries a colour: read and ignored
                xs = [float(t) for t in tok[1:]][: 3 if len(tok) == 7 else 4]
            except ValueError as err:
                raise ExchangeError(f"read_obj: {where}: non-numeric vertex coordinate in {raw.strip()!r}") from err
            if not all(np.isfinite(xs)) or (len(xs) == 4 and xs[3] == 0.0):
                raise ExchangeError(f"read_obj: {where}: vertex coordinates must be finite (w != 0), got {raw.strip()!r}")
            if len(xs) == 4:
                xs = [x / xs[3] for x in xs[:3]]
            verts.append((xs[0], xs[1], xs[2]))
        elif key == "f":
            if len(tok) < 4:
                raise ExchangeError(f"read_obj: {where}: a face needs at least 3 vertices, got {len(tok) - 1}")
            face = []
            for t in tok[1:]:
                head = t.split("/", 1)[0]
                try:
                    i = int(head)
                except ValueError as err:
                    raise ExchangeError(f"read_obj: {where}: bad vertex reference {t!r} in a face") from err
                if i == 0:
                    raise ExchangeError(f"read_obj: {where}: vertex index 0 (OBJ indices start at 1)")
                j = i - 1 if i > 0 else len(verts) + i
                if not 0 <= j < len(verts):
                    raise ExchangeError(
                        f"read_obj: {where}: face refers to vertex {i}, but only {len(verts)} vertices are defined so far"
                    )
                face.append(j)
            faces.append(face)
        elif key in _SKIPPED:
            continue
        else:
            raise ExchangeError(f"read_obj: {where}: unknown record {key!r}")
    if not faces:
        raise ExchangeError(f"read_obj: {p} has no faces ({len(verts)} vertices)")
    used = sorted({v for f in faces for v in f})
    if len(used) != len(verts):  # drop vertices no face uses, renumbering the rest
        remap = {v: i for i, v in enumerate(used)}
        verts = [verts[v] for v in used]
        faces = [[remap[v] for v in f] for f in faces]
    return Mesh(np.array(verts, dtype=float), faces)


def write_obj(mesh: Mesh, path: str | os.PathLike[str], *, comment: str | None = None) -> Path:
    """Write ``mesh`` as a Wavefront OBJ file (``v`` and ``f`` records, 17 significant digits, so
    coordinates read back bit-exact). Written atomically (:func:`occsurf.algorithms._files.atomic_write`):
    a failed write leaves no partial file; a device or read-only target is refused.

    Raises
    ------
    ExchangeError
        If the file cannot be written.
    """
    if not isinstance(mesh, Mesh):
        raise InvalidGeometryError(f"mesh: expected a Mesh, got {type(mesh).__name__}")
    p = Path(path)
    out: list[str] = []
    if comment:
        out.extend(f"# {c}" for c in comment.splitlines())
    out.extend(f"v {x!r} {y!r} {z!r}" for x, y, z in mesh.vertices.tolist())
    out.extend("f " + " ".join(str(v + 1) for v in f) for f in mesh.faces)
    try:
        atomic_write(p, ("\n".join(out) + "\n").encode("utf-8"))
    except ExchangeError as err:
        raise ExchangeError(f"write_obj: {err}") from err
    return p
