"""Corrupt STEP and IGES files for the hostile-input tests, generated from files the tests write.

Nothing here is committed as a blob: every damaged file is made from a clean file written by
``write_step``/``write_iges`` in the test's temporary folder. STEP mutations work on instance records
(``#N = ...;``), IGES mutations on whole entities, so that they are the damage a tester makes by hand
or a crash mid-write leaves: a deleted line, two swapped references, a cut at an entity boundary with
the trailer put back.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

_RECORD = re.compile(rb"#\d+\s*=.*?;\s*(?=#\d+\s*=|ENDSEC;)", re.S)
_REF = re.compile(rb"#(\d+)")
_TRAILER = b"ENDSEC;\nEND-ISO-10303-21;\n"


@dataclass(frozen=True)
class StepText:
    """A STEP file split into its header (through ``DATA;``), its instance records and its trailer."""

    head: bytes
    records: tuple[bytes, ...]

    @classmethod
    def parse(cls, data: bytes) -> StepText:
        start = data.index(b"DATA;") + len(b"DATA;\n")
        end = data.rindex(b"ENDSEC;")
        return cls(data[:start], tuple(m.group(0) for m in _RECORD.finditer(data, start, end + len(b"ENDSEC;"))))

    def join(self, records: tuple[bytes, ...] | list[bytes] | None = None) -> bytes:
        return self.head + b"".join(self.records if records is None else records) + _TRAILER

    def record_of(self, ident: int) -> int:
        for k, r in enumerate(self.records):
            if r.startswith(b"#%d " % ident) or r.startswith(b"#%d=" % ident):
                return k
        raise KeyError(ident)

    def references(self) -> list[tuple[int, int, int]]:
        """``(record index, start, end)`` of every ``#N`` after the ``=`` of its record."""
        out = []
        for k, r in enumerate(self.records):
            eq = r.index(b"=")
            out.extend((k, m.start(), m.end()) for m in _REF.finditer(r, eq))
        return out


def step_delete(text: StepText, k: int) -> bytes:
    """Delete the ``k``-th instance record."""
    return text.join(text.records[:k] + text.records[k + 1:])


def step_cut(text: StepText, k: int) -> bytes:
    """Keep the first ``k`` records, then put the trailer back (a write cut short at a record)."""
    return text.join(text.records[:k])


def step_swap(text: StepText, a: int, b: int) -> bytes:
    """Swap the ``a``-th and ``b``-th references of the file (see :meth:`StepText.references`)."""
    refs = text.references()
    (ka, sa, ea), (kb, sb, eb) = refs[a], refs[b]
    recs = list(text.records)
    ta, tb = recs[ka][sa:ea], recs[kb][sb:eb]
    if ka == kb:
        lo, hi = sorted([(sa, ea, tb), (sb, eb, ta)])
        r = recs[ka]
        recs[ka] = r[:lo[0]] + lo[2] + r[lo[1]:hi[0]] + hi[2] + r[hi[1]:]
    else:
        recs[ka] = recs[ka][:sa] + tb + recs[ka][ea:]
        recs[kb] = recs[kb][:sb] + ta + recs[kb][eb:]
    return text.join(recs)


# B-spline surface records: the simple form ``B_SPLINE_SURFACE_WITH_KNOTS('',p,q,(...` and the
# complex (rational) form ``( ... B_SPLINE_SURFACE(p,q,(...) ... B_SPLINE_SURFACE_WITH_KNOTS((mu),(mv),...``.
_DEGREES = re.compile(rb"B_SPLINE_SURFACE(?:_WITH_KNOTS\('[^']*',|\()\s*(-?\d+)\s*,\s*(-?\d+)\s*,")
_MULTS = re.compile(rb"(?:\.[TFU]\.\s*,\s*\.[TFU]\.\s*,\s*\.[TFU]\.\s*,|B_SPLINE_SURFACE_WITH_KNOTS\()"
                    rb"\s*\(([-\d,\s]+)\)\s*,\s*\(([-\d,\s]+)\)")


def _spline_records(text: StepText) -> list[int]:
    return [k for k, r in enumerate(text.records) if _DEGREES.search(r)]


def step_degree(text: StepText, k: int, direction: int, value: int) -> bytes:
    """Set the u (``direction`` 0) or v (1) degree of the ``k``-th B-spline surface record (any ``k``:
    modulo their count) to ``value``."""
    recs = list(text.records)
    i = _spline_records(text)[k % len(_spline_records(text))]
    m = _DEGREES.search(recs[i])
    assert m is not None
    g = 1 + direction % 2
    recs[i] = recs[i][:m.start(g)] + str(value).encode() + recs[i][m.end(g):]
    return text.join(recs)


def step_multiplicity(text: StepText, k: int, which: int, value: int) -> bytes:
    """Set one knot multiplicity of the ``k``-th B-spline surface record to ``value``: ``which`` picks
    the direction (even: u, odd: v) and the entry (``which // 2``, modulo the list's length; entry 0 is
    the first end knot)."""
    recs = list(text.records)
    i = _spline_records(text)[k % len(_spline_records(text))]
    m = _MULTS.search(recs[i])
    assert m is not None, recs[i][:200]
    g = 1 + which % 2
    entries = recs[i][m.start(g):m.end(g)].split(b",")
    entries[(which // 2) % len(entries)] = str(value).encode()
    recs[i] = recs[i][:m.start(g)] + b",".join(entries) + recs[i][m.end(g):]
    return text.join(recs)


def step_unit_overflow(text: StepText, k: int, which: int) -> bytes:
    """A pole of the ``k``-th B-spline surface (``which``: which of its poles) at ``1.0E+308`` in a
    file whose length unit becomes the kilometre: finite as written, ``inf`` once scaled to mm."""
    recs = list(text.records)
    i = _spline_records(text)[k % len(_spline_records(text))]
    poles = [int(x) for x in _REF.findall(recs[i][recs[i].index(b"=") + 1:])]
    # Only a pole the surface uses: a closed surface lists its wrap poles twice (the last row or
    # column repeats the first), and OCC's reader keeps one of each pair, so a changed duplicate is
    # dropped and nothing overflows (found by the fuzz: the torus's pole #90).
    coords = [recs[text.record_of(p)].split(b"(", 2)[-1] for p in poles]
    used = [p for p, c in zip(poles, coords) if coords.count(c) == 1] or poles
    j = text.record_of(used[which % len(used)])
    recs[j] = re.sub(rb"\(\s*[-+.\dEe]+\s*,", b"(1.0E+308,", recs[j], count=1)
    for u, r in enumerate(recs):
        if b"LENGTH_UNIT" in r and b"SI_UNIT(" in r:
            recs[u] = re.sub(rb"SI_UNIT\((?:\.\w+\.|\$)\s*,\s*\.METRE\.\)", b"SI_UNIT(.KILO.,.METRE.)", r)
    return text.join(recs)


def step_replace(data: bytes, old: bytes, new: bytes) -> bytes:
    assert old in data, old
    return data.replace(old, new, 1)


# ---------------------------------------------------------------------------------------- IGES
@dataclass(frozen=True)
class IgesText:
    """A fixed-format IGES file as its lines by section."""

    lines: tuple[bytes, ...]

    @classmethod
    def parse(cls, data: bytes) -> IgesText:
        return cls(tuple(data.splitlines()))

    def section(self, letter: bytes) -> list[int]:
        return [i for i, ln in enumerate(self.lines) if ln[72:73] == letter]

    def n_entities(self) -> int:
        return len(self.section(b"D")) // 2

    def join(self, lines: list[bytes]) -> bytes:
        return b"\n".join(lines) + b"\n"


def iges_cut(text: IgesText, k: int) -> bytes:
    """Keep the first ``k`` entities (directory pairs and their parameter lines) and put the original
    Terminate line back: a write cut short at an entity boundary."""
    d, p = text.section(b"D"), text.section(b"P")
    keep_d = set(d[:2 * k])
    first_cut_p = int(text.lines[d[2 * k]][8:16]) if 2 * k < len(d) else len(p) + 1
    keep_p = set(p[:first_cut_p - 1])
    lines = [ln for i, ln in enumerate(text.lines)
             if ln[72:73] in (b"S", b"G", b"T") or i in keep_d or i in keep_p]
    return text.join(lines)


def iges_delete_line(text: IgesText, i: int) -> bytes:
    """Delete one line of the Directory or Parameter section."""
    body = text.section(b"D") + text.section(b"P")
    drop = body[i % len(body)]
    return text.join([ln for j, ln in enumerate(text.lines) if j != drop])


_INT = re.compile(rb"(?<![\d.EeDH+-])\d+(?![\d.EeDH])")


def iges_swap(text: IgesText, a: int, b: int) -> bytes:
    """Swap two integer fields of the Parameter section (pointers among them), keeping 80 columns."""
    p = text.section(b"P")
    fields = [(i, m.start(), m.end()) for i in p for m in _INT.finditer(text.lines[i][:64])
              if m.start() > 0 or text.lines[i][:1] != b" "]
    if len(fields) < 2:
        return text.join(list(text.lines))
    (ia, sa, ea), (ib, sb, eb) = fields[a % len(fields)], fields[b % len(fields)]
    lines = list(text.lines)
    va, vb = lines[ia][sa:ea], lines[ib][sb:eb]
    if ia == ib:
        lo, hi = sorted([(sa, ea, vb), (sb, eb, va)])
        data = lines[ia][:64]
        data = data[:lo[0]] + lo[2] + data[lo[1]:hi[0]] + hi[2] + data[hi[1]:]
        lines[ia] = data[:64].ljust(64) + lines[ia][64:]
    else:
        for i, s, e, v in ((ia, sa, ea, vb), (ib, sb, eb, va)):
            data = lines[i][:64]
            data = (data[:s] + v + data[e:]).rstrip()
            if len(data) > 64:
                return text.join(list(text.lines))  # does not fit the 64 columns: no swap
            lines[i] = data.ljust(64) + lines[i][64:]
    return text.join(lines)


#: Values a degree or a knot multiplicity is set to by :func:`mutate`: OCC's limit and beyond it,
#: non-positive, one above degree + 1, and absurdly large (issue 34's degree 1e9, multiplicity 2e9).
BAD_DEGREES = (0, -3, 26, 1000000000)
BAD_MULTIPLICITIES = (0, -1, 4, 5, 2000000000)


def mutate(fmt: str, clean: bytes, kind: str, a: int, b: int) -> bytes:
    """One damaged copy of ``clean`` (``fmt`` "step" or "iges"): ``kind`` "delete" (a record/line),
    "swap" (two references) or "cut" (at an entity boundary, trailer put back); for STEP with B-spline
    surfaces also "degree" (one set to a :data:`BAD_DEGREES` value), "multiplicity" (one knot's set to
    a :data:`BAD_MULTIPLICITIES` value) or "unit" (a pole at 1e308 in a kilometre file); the integers ``a``,
    ``b`` choose where (any size: taken modulo the file's counts). The mutation fuzz's generator
    (tests/bridge/test_fuzz_exchange.py, benchmarks/bench_fuzz_exchange.py)."""
    if fmt == "step":
        text = StepText.parse(clean)
        if kind == "degree":
            return step_degree(text, a, b, BAD_DEGREES[(b // 2) % len(BAD_DEGREES)])
        if kind == "multiplicity":
            return step_multiplicity(text, a, b, BAD_MULTIPLICITIES[(a + b) % len(BAD_MULTIPLICITIES)])
        if kind == "unit":
            return step_unit_overflow(text, a, b)
        n, refs = len(text.records), len(text.references())
        if kind == "delete":
            return step_delete(text, a % n)
        if kind == "swap":
            return step_swap(text, a % refs, b % refs)
        return step_cut(text, 1 + a % (n - 1))
    itext = IgesText.parse(clean)
    if kind == "delete":
        return iges_delete_line(itext, a)
    if kind == "swap":
        return iges_swap(itext, a, b)
    return iges_cut(itext, 1 + a % (itext.n_entities() - 1))


def write(folder: Path, name: str, data: bytes) -> Path:
    path = folder / name
    path.write_bytes(data)
    return path
