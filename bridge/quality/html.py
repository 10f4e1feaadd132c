"""The offline page of a quality report (``DIR/index.html`` of ``occsurf check``).

One HTML file that opens from the file system with no network: the model overview (numbers and the
overview pictures), a face table sortable by any column (worst first by default), the edge-
continuity table, and per face its curvature map, zebra stripes, sections with combs and flags
with their suggested corrections. An interactive 3-D view (:mod:`.viewer_js`: rotate, zoom, switch
the indicator, per-pixel zebra and isophotes with adjustable stripes, the draft against any axis,
sections with combs and edge classes as line sets, picking linked to the tables; the PNGs instead
without WebGL) runs on three.js r187, vendored in ``static/three-viewer.min.js`` (MIT licence,
``static/THREE_LICENSE``) and embedded in the page (gzip-compressed behind its licence comment,
inflated by the page), since a page opened from ``file://`` may not load scripts as ES modules.

:func:`viewer_payload` packs the triangulated faces, their per-vertex indicators and the line sets
into one gzip-compressed block of float32 / uint16 / uint32 arrays (:data:`VIEWER_DATA_LAYOUT`;
:func:`viewer_data` and :func:`viewer_array` read it back); :func:`render_html` builds the page from
a report's JSON and that payload.
"""

from __future__ import annotations

import base64
import functools
import gzip
import html
import json
import math
from collections.abc import Sequence
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .choices import face_scores
from .viewer_js import VIEWER_CSS, VIEWER_JS

if TYPE_CHECKING:
    from .report import QualityReport

__all__ = ["render_html", "viewer_payload", "write_html", "VIEWER_INDICATORS", "PER_PIXEL", "viewer_script",
           "render_index_html", "write_index_html", "viewer_data", "viewer_array", "VIEWER_DATA_LAYOUT"]

#: Indicators the 3-D view can switch between: (key, label, colour map, symmetric scale).
VIEWER_INDICATORS: tuple[tuple[str, str, str, bool], ...] = (
    ("mean", "mean curvature H", "diverging", True),
    ("gaussian", "Gaussian curvature K", "diverging", True),
    ("max", "max principal curvature k1", "diverging", True),
    ("absolute", "|k1|+|k2|", "rainbow", False),
    ("zebra", "zebra (per pixel, follows the view)", "stripes", False),
    ("isophote", "isophotes (per pixel)", "stripes", False),
    ("draft", "draft angle, deg (pull direction below)", "diverging", True),
    ("shaded", "shaded", "grey", False),
)
#: Indicators the page draws per pixel from the normals (a shader): their per-vertex values are not
#: sent (on the OCCT bearing they were 0.9 of its 7.6 MB page).
PER_PIXEL = ("zebra", "isophote")
#: Vertices above which the 3-D view's mesh is thinned (every k-th triangle kept is not an
#: option: faces would get holes; instead big models are sent whole and the page stays usable
#: up to a few hundred thousand vertices).
MAX_VIEWER_VERTICES = 400_000
#: The pull direction of the report's stored draft angles (:func:`~.report.face_fields`' default);
#: the page recomputes the draft for the others.
DRAFT_PULL = (0.0, 0.0, 1.0)
#: The page's pull directions: (label, direction).
PULL_CHOICES: tuple[tuple[str, tuple[int, int, int]], ...] = (
    ("+z", (0, 0, 1)), ("-z", (0, 0, -1)), ("+x", (1, 0, 0)), ("-x", (-1, 0, 0)), ("+y", (0, 1, 0)), ("-y", (0, -1, 0)))
#: The directions the zebra stripes can run in the view: (label, the view-space axis the stripe
#: phase follows, i.e. across the stripes).
ZEBRA_DIRECTIONS: tuple[tuple[str, tuple[float, float, float]], ...] = (
    ("vertical", (1.0, 0.0, 0.0)), ("horizontal", (0.0, 1.0, 0.0)), ("diagonal", (1.0, 1.0, 0.0)))


def viewer_script() -> str:
    """The vendored three.js bundle (read from the package data)."""
    return resources.files("occsurf.bridge.quality").joinpath("static/three-viewer.min.js").read_text("utf-8")


@functools.lru_cache(maxsize=1)
def _packed_viewer_script() -> tuple[str, str]:
    """The bundle's licence comment (kept in the page as text) and the whole bundle gzip-compressed,
    base64 (567 KB -> 187 KB a page; the page inflates and runs it, as it inflates the model's
    arrays). Made once per process."""
    text = viewer_script()
    return text[:text.index("*/") + 2], base64.b64encode(gzip.compress(text.encode("utf-8"), 9, mtime=0)).decode("ascii")


#: How the 3-D view's arrays are stored (the payload's ``"data"``, read by the page and by
#: :func:`viewer_data` / :func:`viewer_array`).
VIEWER_DATA_LAYOUT = """\
payload["data"] is base64 text of one gzip member (RFC 1952). Inflated, it holds every array of
the payload end to end, each starting at a multiple of 4 bytes. The payload refers to an array as
{"at": byte offset, "n": number of elements, "dtype": "<f4" | "<u2" | "<u4", "columns": c,
"delta": d}: little-endian float32, uint16 or uint32 values, an array of n / c rows of c columns
(points and normals: 3; the array the page builds is row by row, x0 y0 z0 x1 ...). Stored are
(1) the columns one after the other (all x, then all y, then all z); (2) where d is true, each
column's values as unsigned integers of their width (a float's bits) replaced by their differences
from the value before them in the column, modulo 2**32 (or 2**16; the first kept): the page
restores them by a running sum; (3) the bytes in planes, as HDF5's and Blosc's shuffle filter
does: the first byte of every element, then the second byte of every element, and so on (stored
element i's byte k at at + k * n + i). (1) to (3) let deflate find what neighbouring mesh vertices
share: the OCCT bearing's 3.8 MB of arrays compress to 2.4 MB with them, 2.7 MB without.
"""

_UNSIGNED = {"<f4": "<u4", "<u4": "<u4", "<u2": "<u2"}


class _Packer:
    """The payload's arrays in one block (:data:`VIEWER_DATA_LAYOUT`): :meth:`add` places one and
    returns its reference, :meth:`data` compresses the whole."""

    def __init__(self) -> None:
        self._parts: list[bytes] = []
        self._at = 0

    def add(self, a: Any, dtype: str, *, columns: int = 1, delta: bool = False) -> dict[str, Any]:
        import numpy as np

        x = np.ascontiguousarray(np.asarray(a, dtype=dtype).reshape(-1, columns).T)
        u = x.view(_UNSIGNED[dtype])
        if delta and u.shape[1] > 1:
            u = u.copy()
            u[:, 1:] -= x.view(_UNSIGNED[dtype])[:, :-1]  # unsigned: modulo 2**width
        n, width = u.size, u.dtype.itemsize
        planes = u.reshape(-1).view(np.uint8).reshape(n, width).T.tobytes()
        ref = {"at": self._at, "n": int(n), "dtype": dtype, "columns": columns, "delta": bool(delta)}
        pad = -len(planes) % 4
        self._parts.append(planes + bytes(pad))
        self._at += len(planes) + pad
        return ref

    def points(self, a: Any) -> dict[str, Any]:
        """Float32 rows of three coordinates (points, normals), by columns and differences."""
        return self.add(a, "<f4", columns=3, delta=True)

    def polylines(self, polylines: Sequence[Any]) -> dict[str, Any]:
        """Polylines ``(k_i, 3)`` as one float32 array of their points end to end (``"points"``)
        and one of uint32 point counts (``"counts"``)."""
        import numpy as np

        pls = [np.asarray(p, float).reshape(-1, 3) for p in polylines]
        pls = [p for p in pls if len(p) >= 2 and np.all(np.isfinite(p))]
        pts = np.concatenate(pls) if pls else np.zeros((0, 3))
        return {"points": self.points(pts), "counts": self.add([len(p) for p in pls], "<u4")}

    def data(self) -> str:
        # mtime 0: the same report gives the same bytes; level 6 is zlib's default (level 9 gains 0.4 %
        # on the bearing's arrays for 3x the time)
        return base64.b64encode(gzip.compress(b"".join(self._parts), 6, mtime=0)).decode("ascii")


def viewer_data(payload: dict[str, Any]) -> bytes:
    """The payload's arrays as one inflated block (:data:`VIEWER_DATA_LAYOUT`), for
    :func:`viewer_array`."""
    return gzip.decompress(base64.b64decode(payload["data"]))


def viewer_array(data: bytes | dict[str, Any], ref: dict[str, Any]) -> Any:
    """The array ``ref`` refers to, flat and row by row (``n`` values of its ``dtype``), from
    :func:`viewer_data`'s block or from the payload itself (inflated anew on each call)."""
    import numpy as np

    raw = viewer_data(data) if isinstance(data, dict) else data
    unsigned = np.dtype(_UNSIGNED[ref["dtype"]])
    n, width, at, columns = int(ref["n"]), unsigned.itemsize, int(ref["at"]), int(ref.get("columns", 1))
    planes = np.frombuffer(raw, np.uint8, count=n * width, offset=at).reshape(width, n)
    u = np.ascontiguousarray(planes.T).view(unsigned).reshape(columns, n // columns)
    if ref.get("delta"):
        u = np.cumsum(u, axis=1, dtype=unsigned)  # modulo 2**width, the differences' inverse
    return np.ascontiguousarray(u.T).reshape(n).view(np.dtype(ref["dtype"]))


def viewer_payload(report: QualityReport) -> dict[str, Any]:
    """The 3-D view's data for ``report`` (what the page's script reads; JSON-safe).

    Returns
    -------
    dict
        ``data``: the arrays, compressed (:data:`VIEWER_DATA_LAYOUT`); every array below is a
        reference into it (``{"at", "n", "dtype"}``, :func:`viewer_array`).
        ``faces``: per face ``index``, ``n`` (vertices), ``points`` and ``normals`` (float32,
        shape (n, 3)), ``triangles`` ((m, 3), of ``triangles_dtype``:
        ``"uint16"`` when ``n <= 65536``, else ``"uint32"``), ``values``: one float32 array
        (n,) per coloured indicator of :data:`VIEWER_INDICATORS` the face has (NaN kept, the report's
        :class:`~occsurf.bridge.quality.report.FaceField` values; not the :data:`PER_PIXEL` ones,
        which the page draws from the normals); empty when the model has more than
        :data:`MAX_VIEWER_VERTICES` vertices (``skipped``).
        ``ranges``: each coloured indicator's common colour range (symmetric about 0 where the
        value has a sign). ``pull``: the pull direction of the stored draft values.
        ``zebra_pairs``, ``isophote_pairs``: the stripe counts the view starts with.
        ``lines``: ``sections`` and ``combs`` (comb teeth and outlines) of
        :func:`~occsurf.bridge.quality.pictures.model_sections`, each ``{"points", "counts"}``
        (polylines end to end, float32 (sum k, 3), and their point counts, uint32);
        ``inflections`` (float32 (j, 3)); ``edges``: one entry per continuity class of
        :attr:`QualityReport.edge_lines` with its ``class``, ``color`` (RGB in [0, 1],
        :data:`~occsurf.bridge.quality.pictures.EDGE_COLORS`), ``points`` and ``counts``.
    """
    import numpy as np

    from .pictures import EDGE_COLORS, ISOPHOTE_PAIRS, ZEBRA_PAIRS, model_sections
    from .scales import value_range

    fields = [report.fields[k] for k in sorted(report.fields)]
    total = sum(f.mesh.n_vertices for f in fields)
    pack = _Packer()
    faces = []
    if total <= MAX_VIEWER_VERTICES:
        for f in fields:
            N = np.nan_to_num(f.mesh.normals, nan=0.0)
            small = f.mesh.n_vertices <= 1 << 16  # the indices fit 16 bits: half the bytes, as WebGL takes them
            faces.append({
                "index": f.mesh.index, "n": f.mesh.n_vertices,
                "points": pack.points(f.mesh.points), "normals": pack.points(N),
                "triangles": pack.add(f.mesh.triangles, "<u2" if small else "<u4"),
                "triangles_dtype": "uint16" if small else "uint32",
                "values": {k: pack.add(f.values[k], "<f4") for k, *_ in VIEWER_INDICATORS
                           if k not in PER_PIXEL and k in f.values},
            })
    ranges = {}
    for key, _, _, _ in VIEWER_INDICATORS:
        if key in (*PER_PIXEL, "shaded") or not fields:
            continue
        lo, hi = value_range([f.values[key] for f in fields], key, report.size)
        ranges[key] = [lo, hi]
    sections, combs, inflections = model_sections(report)
    order = list(EDGE_COLORS)
    classes = sorted({c for c, _ in report.edge_lines}, key=lambda c: (order.index(c) if c in order else len(order), c))
    edges = [dict(pack.polylines([pl for c, pl in report.edge_lines if c == cls]), **{
        "class": cls, "color": list(EDGE_COLORS.get(cls, (0.4, 0.4, 0.4)))}) for cls in classes]
    lines = {"sections": pack.polylines(sections), "combs": pack.polylines(combs),
             "inflections": pack.points(np.asarray(inflections, float).reshape(-1, 3)), "edges": edges}
    return {"data": pack.data(), "faces": faces, "ranges": ranges, "size": report.size, "skipped": total > MAX_VIEWER_VERTICES,
            "n_vertices": total, "pull": list(DRAFT_PULL), "zebra_pairs": ZEBRA_PAIRS,
            "isophote_pairs": ISOPHOTE_PAIRS, "lines": lines}


# ---------------------------------------------------------------------------------------- page
def _fmt(x: Any, digits: int = 3) -> str:
    if x is None:
        return "-"
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, (int, float)):
        if isinstance(x, float) and not math.isfinite(x):
            return str(x)
        return f"{x:.{digits}g}"
    if isinstance(x, (list, tuple)):
        return "(" + ", ".join(_fmt(v, digits) for v in x) + ")"
    return html.escape(str(x))


def _num_attr(x: Any) -> str:
    """A ``data-v`` sort key: the number, or empty for missing values (sorted last)."""
    if isinstance(x, bool) or x is None:
        return ""
    try:
        v = float(x)
    except (TypeError, ValueError):
        return html.escape(str(x))
    return repr(v) if math.isfinite(v) else ""


def _overview(doc: dict[str, Any], pictures: dict[str, str]) -> str:
    status = "passed" if doc.get("passed") else "failed"
    rows = [
        ("file", html.escape(doc.get("path", ""))), ("format", _fmt(doc.get("format"))),
        ("model size (bbox diagonal)", _fmt(doc.get("model_size"), 5)),
        ("faces", str(doc.get("n_faces"))), ("edges between faces", str(doc.get("n_edges"))),
        ("worst G1 angle", f"{_fmt(doc.get('worst_g1_deg'))} deg"), ("flags", str(doc.get("n_flags"))),
        ("thresholds", f"{html.escape(str(doc.get('preset')))}: " + ", ".join(
            f"{k} {_fmt(v)}" for k, v in (doc.get("thresholds") or {}).items() if k != "name")),
        ("result", f'<span class="{status}">{status}</span> ({len(doc.get("failures") or [])} violations)'),
        ("seconds", ", ".join(f"{k} {v:.2f}" for k, v in (doc.get("seconds") or {}).items())),
    ]
    out = ['<section id="overview"><h2>Model</h2><table class="kv">']
    out += [f"<tr><th>{k}</th><td>{v}</td></tr>" for k, v in rows]
    out.append("</table>")
    for w in doc.get("warnings") or []:
        out.append(f'<p class="warn">warning: {html.escape(str(w))}</p>')
    if doc.get("failures"):
        out.append('<details class="failures"><summary>violations</summary><ul>')
        out += [f"<li>{html.escape(str(f))}</li>" for f in doc["failures"][:500]]
        out.append("</ul></details>")
    if pictures:
        out.append('<div class="pics">')
        for kind, name in pictures.items():
            out.append(f'<figure><img src="{html.escape(name)}" alt="model {kind}" loading="lazy">'
                       f"<figcaption>{html.escape(kind)}</figcaption></figure>")
        out.append("</div>")
    out.append("</section>")
    return "\n".join(out)


def _face_table(faces: list[dict[str, Any]], violations: list[dict[str, Any]]) -> str:
    cols = ("face", "type", "k_min", "k_max", "flags", "worst G1 (deg)", "degenerate pts", "vertices", "status")
    out = ['<section id="faces"><h2>Faces</h2><p class="hint">Click a column to sort; rows start worst first '
           '(unevaluated, then by flags plus violations of adjacent edges, then the largest angle at an adjacent '
           'edge). Click a row to highlight its face in the 3-D view.</p>',
           '<div class="table-scroll"><table class="sortable" id="face-table"><thead><tr>']
    out += [f'<th data-col="{i}">{c}</th>' for i, c in enumerate(cols)]
    out.append("</tr></thead><tbody>")
    scores = face_scores(faces, violations)
    for f in sorted(faces, key=lambda f: (-scores[int(f["index"])], int(f["index"]))):
        n_flags = len(f.get("flags") or ())
        status = "error" if f.get("error") else ("flagged" if n_flags else "ok")
        cells = [
            (f["index"], f'<a href="#face-{f["index"]}">{f["index"]}</a>'), (f.get("type"), _fmt(f.get("type"))),
            (f.get("k_min"), _fmt(f.get("k_min"))), (f.get("k_max"), _fmt(f.get("k_max"))),
            (n_flags, str(n_flags)), (f.get("worst_g1_deg"), _fmt(f.get("worst_g1_deg"))),
            (f.get("n_degenerate"), str(f.get("n_degenerate", 0))), (f.get("n_vertices"), str(f.get("n_vertices", 0))),
            (status, status),
        ]
        out.append(f'<tr class="{status}" data-face="{int(f["index"])}">'
                   + "".join(f'<td data-v="{_num_attr(v)}">{t}</td>' for v, t in cells) + "</tr>")
    out.append("</tbody></table></div></section>")
    return "\n".join(out)


def _point_attr(p: Any) -> str:
    """A point ``[x, y, z]`` as the ``data-point`` of a table row (empty when missing)."""
    try:
        xyz = [float(x) for x in p]
    except (TypeError, ValueError):
        return ""
    return ",".join(repr(x) for x in xyz) if len(xyz) == 3 and all(math.isfinite(x) for x in xyz) else ""


def _edge_table(edges: list[dict[str, Any]], violations: list[dict[str, Any]]) -> str:
    bad = {v.get("edge") for v in violations}
    cols = ("edge", "faces", "matched", "class", "g0_max", "g1_max_deg", "g2_max", "g2_max_rel (%)", "worst_point",
            "midpoint")
    out = ['<section id="edges"><h2>Edge continuity</h2>']
    if not edges:
        out.append("<p>No edge is shared by two faces, and no loose edges matched geometrically: "
                   "nothing to measure.</p></section>")
        return "\n".join(out)
    out.append('<p class="hint">Click a row to fly the 3-D view to the edge\'s worst point.</p>'
               '<div class="table-scroll"><table class="sortable" id="edge-table"><thead><tr>')
    out += [f'<th data-col="{i}">{c}</th>' for i, c in enumerate(cols)]
    out.append("</tr></thead><tbody>")
    for k, e in enumerate(edges):
        idx = e.get("index", k)
        cls = "violation" if idx in bad else ""
        cells = [
            (idx, str(idx)), (None, _fmt(e.get("faces"))), (e.get("matched"), _fmt(e.get("matched"))),
            (e.get("classification"), _fmt(e.get("classification"))), (e.get("g0_max"), _fmt(e.get("g0_max"))),
            (e.get("g1_max_deg"), _fmt(e.get("g1_max_deg"))), (e.get("g2_max"), _fmt(e.get("g2_max"))),
            (e.get("g2_max_rel"), _fmt(e.get("g2_max_rel"))), (None, _fmt(e.get("worst_point"), 5)),
            (None, _fmt(e.get("midpoint"), 5)),
        ]
        point = _point_attr(e.get("worst_point")) or _point_attr(e.get("midpoint"))
        out.append(f'<tr class="{cls}" data-edge="{html.escape(str(idx))}" data-point="{point}">'
                   + "".join(f'<td data-v="{_num_attr(v)}">{t}</td>' for v, t in cells) + "</tr>")
    out.append("</tbody></table></div></section>")
    return "\n".join(out)


def _face_sections(faces: list[dict[str, Any]]) -> str:
    out = ['<section id="face-details"><h2>Faces in detail</h2>']
    for f in faces:
        out.append(f'<article class="face" id="face-{f["index"]}"><h3>face {f["index"]}: {_fmt(f.get("type"))}'
                   + (f' <small>{html.escape(str(f["name"]))}</small>' if f.get("name") else "") + "</h3>")
        out.append(f'<p>k_min {_fmt(f.get("k_min"))}, k_max {_fmt(f.get("k_max"))} (1/unit); Gaussian '
                   f'{_fmt(f.get("gaussian_range"))}, mean {_fmt(f.get("mean_range"))}; worst adjacent G1 '
                   f'{_fmt(f.get("worst_g1_deg"))} deg</p>')
        if f.get("error"):
            out.append(f'<p class="error">{html.escape(f["error"])}</p>')
        for note in f.get("notes") or []:
            out.append(f'<p class="note">{html.escape(str(note))}</p>')
        pics = f.get("pictures") or {}
        if pics:
            out.append('<div class="pics">')
            for kind, name in pics.items():
                out.append(f'<figure><img src="{html.escape(name)}" alt="face {f["index"]} {kind}" loading="lazy">'
                           f"<figcaption>{html.escape(kind)}</figcaption></figure>")
            out.append("</div>")
        flags = f.get("flags") or []
        if flags:
            out.append('<table class="flags"><tr><th>flag</th><th>value</th><th>location</th><th>uv</th>'
                       "<th>suggested correction</th></tr>")
            for g in flags:
                out.append(f"<tr><td>{_fmt(g.get('kind'))}</td><td>{_fmt(g.get('value'))}</td>"
                           f"<td>{_fmt(g.get('location'), 5)}</td><td>{_fmt(g.get('uv'), 4)}</td>"
                           f"<td>{_fmt(g.get('suggestion'))}</td></tr>")
            out.append("</table>")
        else:
            out.append('<p class="ok">no flags</p>')
        out.append("</article>")
    out.append("</section>")
    return "\n".join(out)


_CSS = """
body{font:14px/1.4 system-ui,sans-serif;margin:0 1.5em 3em;color:#222;background:#fafbfc}
h1{font-size:1.5em}h2{border-bottom:1px solid #ccd;padding-bottom:.2em;margin-top:1.6em}
table{border-collapse:collapse;margin:.5em 0}th,td{border:1px solid #dde;padding:2px 7px;text-align:left}
table.sortable th{cursor:pointer;background:#eef1f6;user-select:none}table.sortable th:after{content:" \\2195";color:#99a}
tr.error td{background:#fde2e2}tr.flagged td{background:#fff5d6}tr.violation td{background:#fde2e2}
.passed{color:#070;font-weight:bold}.failed{color:#b00;font-weight:bold}.warn,.error{color:#b00}.note{color:#555}
.pics{display:flex;flex-wrap:wrap;gap:8px}.pics figure{margin:0}.pics img{max-width:520px;border:1px solid #dde}
figcaption{font-size:.85em;color:#555;text-align:center}
nav a{margin-right:1em}
"""

_SORT_JS = r"""
for (const t of document.querySelectorAll('table.sortable')){
  t.querySelectorAll('th').forEach((th, i) => th.addEventListener('click', () => {
    const body = t.tBodies[0]; const rows = Array.from(body.rows);
    const dir = th.dataset.dir === 'desc' ? 1 : -1; th.dataset.dir = dir === 1 ? 'asc' : 'desc';
    rows.sort((a, b) => { const x = a.cells[i].dataset.v, y = b.cells[i].dataset.v;
      const fx = parseFloat(x), fy = parseFloat(y);
      if (x === '' && y !== '') return 1; if (y === '' && x !== '') return -1;
      if (!isNaN(fx) && !isNaN(fy)) return dir * (fx - fy);
      return dir * String(x).localeCompare(String(y)); });
    rows.forEach(r => body.appendChild(r));
  }));
}
"""


def _json_script(element_id: str, data: Any) -> str:
    text = json.dumps(data, allow_nan=False, separators=(",", ":")).replace("</", "<\\/")
    return f'<script type="application/json" id="{element_id}">{text}</script>'


def _viewer_section(payload: dict[str, Any]) -> str:
    """The 3-D view's section: its controls, the canvas with the legend, and the note and pictures
    shown instead when the browser has no WebGL (filled in by the script)."""
    from .pictures import EDGE_COLORS, ISOPHOTE_PAIRS, ZEBRA_PAIRS

    def select(element_id: str, choices: Sequence[tuple[str, str]]) -> str:
        return f'<select id="{element_id}">' + "".join(
            f'<option value="{html.escape(v)}">{html.escape(label)}</option>' for v, label in choices) + "</select>"

    indicators = select("indicator", [(k, label) for k, label, _, _ in VIEWER_INDICATORS])
    pulls = select("pull", [(",".join(str(x) for x in d), label) for label, d in PULL_CHOICES])
    directions = select("zebra-dir", [(",".join(repr(x) for x in d), label) for label, d in ZEBRA_DIRECTIONS])
    classes = [e["class"] for e in (payload.get("lines") or {}).get("edges") or []]
    key = "".join(f'<span style="background:rgb({",".join(str(round(255 * c)) for c in EDGE_COLORS.get(k, (.4, .4, .4)))})">'
                  f"</span>{html.escape(k)}" for k in classes)
    return (
        '<section id="view3d"><h2>3-D view</h2>'
        f'<div id="viewer-ui"><label id="viewer-indicator">indicator {indicators}</label><span id="viewer-status">loading...</span></div>'
        '<div id="viewer-ui-more"><div id="viewer-controls">'
        f'<fieldset><legend>zebra</legend><label>stripe pairs <input type="number" id="zebra-count" min="1" max="64" '
        f'step="1" value="{ZEBRA_PAIRS}"></label> <label>running {directions}</label></fieldset> '
        f'<fieldset><legend>isophotes</legend><label>bands <input type="number" id="iso-count" min="1" max="64" '
        f'step="1" value="{ISOPHOTE_PAIRS}"></label></fieldset> '
        f'<fieldset><legend>draft</legend><label>pull {pulls}</label></fieldset> '
        '<fieldset title="sections navy, curvature combs orange with inflections green, edges by continuity class">'
        '<legend>lines</legend><label><input type="checkbox" id="show-sections"> sections</label> '
        '<label><input type="checkbox" id="show-combs"> combs</label> '
        f'<label><input type="checkbox" id="show-edges"> edges</label><span id="edge-key">{key}</span>'
        '</fieldset></div><p id="viewer-pick"></p></div>'
        '<div id="viewer-wrap"><canvas id="viewer"></canvas><div id="legend"><div class="title"></div><div class="hi"></div>'
        '<canvas width="24" height="240"></canvas><div class="lo"></div></div></div>'
        '<div id="viewer-fallback" hidden><p class="warn why"></p><div class="pics"></div></div>'
        '<noscript><p class="warn">The 3-D view needs JavaScript; the overview pictures and the tables hold the '
        "report.</p></noscript></section>"
    )


def render_html(doc: dict[str, Any], payload: dict[str, Any], pictures: dict[str, str] | None = None) -> str:
    """The page for a report's JSON ``doc`` (:meth:`QualityReport.to_json`), the 3-D view's
    ``payload`` (:func:`viewer_payload`) and the overview ``pictures`` (kind -> file name)."""
    from ..rendering.vtk_scene import COLORMAPS

    title = f"occsurf check: {Path(str(doc.get('path', ''))).name}"
    licence, packed = _packed_viewer_script()
    parts = [
        "<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{html.escape(title)}</title><style>{_CSS}{VIEWER_CSS}</style></head><body>",
        f"<h1>{html.escape(title)}</h1>",
        '<nav><a href="#overview">model</a><a href="#view3d">3-D view</a><a href="#faces">faces</a>'
        '<a href="#edges">edges</a><a href="#face-details">faces in detail</a></nav>',
        _overview(doc, pictures or {}),
        _viewer_section(payload),
        _face_table(doc.get("faces") or [], doc.get("violations") or []),
        _edge_table(doc.get("edges") or [], doc.get("violations") or []),
        _face_sections(doc.get("faces") or []),
        '<footer><p class="note">3-D view: three.js r187 (MIT licence), embedded. Pictures: VTK, offscreen. '
        "Curvature in 1/model units; magenta: degenerate points (undefined normal).</p></footer>",
        _json_script("viewer-data", payload),
        _json_script("viewer-indicators", [list(x) for x in VIEWER_INDICATORS]),
        _json_script("viewer-maps", {k: [list(c) for c in v] for k, v in COLORMAPS.items()}),
        f"<script>{_SORT_JS}</script>",
        f"<script>{licence}</script>",
        f'<script type="application/octet-stream" id="viewer-three">{packed}</script>',
        f"<script>{VIEWER_JS}</script>",
        "</body></html>",
    ]
    return "\n".join(parts)


def write_html(path: str | Path, doc: dict[str, Any], payload: dict[str, Any],
               pictures: dict[str, str] | None = None) -> Path:
    """Write the page atomically to ``path``."""
    from ..exchange.files import atomic_write

    path = Path(path)
    atomic_write(path, render_html(doc, payload, pictures).encode("utf-8"))
    return path


# ---------------------------------------------------------------------------------------- index
def _index_row(f: dict[str, Any]) -> str:
    status = f.get("status", "?")
    link = f.get("report")
    name = html.escape(str(f.get("path", "")))
    name_cell = f'<a href="{html.escape(link)}">{name}</a>' if link else name
    w = f.get("worst_g1_edge") or {}
    worst = "-" if not w else (f'{_fmt(w.get("g1_max_deg"))} deg, faces {_fmt(w.get("faces"))} '
                               f'({html.escape(str(w.get("classification")))})')
    flags = ", ".join(f"{n} {html.escape(k)}" for k, n in (f.get("flags") or {}).items()) or "-"
    crashed = f.get("crashed_faces") or []
    notes = [html.escape(str(f["error"]))] if f.get("error") else []
    if crashed:
        notes.append(f"faces {', '.join(str(k) for k in crashed)} crashed the checker and were left out")
    notes += [html.escape(str(x)) for x in f.get("skipped") or []]
    thumb = f.get("thumbnail")
    pic = f'<img src="{html.escape(thumb)}" alt="" loading="lazy">' if thumb else ""
    cls = {"ok": "", "failed": "flagged"}.get(status, "error")
    n_flags = sum((f.get("flags") or {}).values())
    cells = [
        (f.get("path"), name_cell), (status, f'<span class="{"passed" if status == "ok" else "failed"}">{status}</span>'),
        (f.get("n_faces"), _fmt(f.get("n_faces"))), (f.get("n_edges"), _fmt(f.get("n_edges"))),
        (w.get("g1_max_deg"), worst), (f.get("worst_g1_deg"), _fmt(f.get("worst_g1_deg"))), (n_flags, flags),
        (f.get("n_violations"), _fmt(f.get("n_violations"))), (f.get("seconds"), _fmt(f.get("seconds"))),
        (None, "<br>".join(notes) or "-"), (None, pic),
    ]
    return f'<tr class="{cls}">' + "".join(f'<td data-v="{_num_attr(v)}">{t}</td>' for v, t in cells) + "</tr>"


def render_index_html(summary: dict[str, Any]) -> str:
    """The page over several files' reports (``DIR/index.html`` of ``occsurf check`` on several
    files or folders): one sortable row per file (status, faces, edges, its worst G1 edge among the
    edges meant to be tangent-continuous, the worst G1 of all edges, flags by kind, violations of
    the preset, seconds, crashed faces) linking to that file's own page. Offline, no script but the
    table sorting."""
    files = summary.get("files") or []
    cols = ("file", "status", "faces", "edges", "worst G1 edge (smooth edges)", "worst G1 all (deg)", "flags",
            "violations", "seconds", "notes", "")
    counts = summary.get("counts") or {}
    head = ", ".join(f"{n} {html.escape(k)}" for k, n in counts.items())
    gate = summary.get("fail_on")
    verdict = ("" if not gate else
               f' <span class="{"passed" if summary.get("passed") else "failed"}">--fail-on {html.escape(gate)}: '
               f'{"passed" if summary.get("passed") else "FAILED"}</span>')
    parts = [
        "<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>occsurf check: {len(files)} files</title><style>{_CSS}"
        "td img{max-width:180px;border:1px solid #dde}</style></head><body>",
        f"<h1>occsurf check: {len(files)} files</h1>",
        f'<p>{head}; preset {html.escape(str(summary.get("preset")))}{verdict}. Click a column to sort; '
        "a file's name opens its own report.</p>",
        '<table class="sortable" id="file-table"><thead><tr>',
        "".join(f'<th data-col="{i}">{c}</th>' for i, c in enumerate(cols)),
        "</tr></thead><tbody>",
        *[_index_row(f) for f in files],
        "</tbody></table>",
        '<p class="note">Worst G1 edge: the largest normal angle over the edges classified gap, G0, G1 or G2 '
        "(meant to be tangent-continuous; designed creases, seams and degenerate edges are in the all-edges "
        "column).</p>",
        f"<script>{_SORT_JS}</script>", "</body></html>",
    ]
    return "\n".join(parts)


def write_index_html(path: str | Path, summary: dict[str, Any]) -> Path:
    """Write :func:`render_index_html` atomically to ``path``."""
    from ..exchange.files import atomic_write

    path = Path(path)
    atomic_write(path, render_index_html(summary).encode("utf-8"))
    return path
