"""Hierarchical surfaces against OCC: the flat form as Geom_BSplineSurface, STEP + sidecar round
trips, and STEP faces as the base of a new hierarchy (course §5-17)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose
from OCP.gp import gp_Pnt, gp_Vec

from occsurf.algorithms import BSplineSurface
from occsurf.algorithms.errors import ExchangeError
from occsurf.algorithms.hierarchical.curve import HierarchicalCurve
from occsurf.algorithms.hierarchical.surface import HierarchicalSurface
from occsurf.bridge import to_occ
from occsurf.bridge.exchange.hierarchical_io import (
    import_step_base,
    read_hierarchical_step,
    sidecar_path,
    write_hierarchical_step,
)
from occsurf.bridge.exchange.step_iges import read_step, write_step


def make_hierarchy(rational: bool = False) -> HierarchicalSurface:
    g = np.linspace(0.0, 6.0, 9)
    X, Y = np.meshgrid(g, g, indexing="ij")
    P = np.stack([X, Y, 0.6 * np.sin(X / 2) * np.cos(Y / 3)], -1)
    t = np.r_[[0.0] * 4, 0.1, 0.3, 0.45, 0.5, 0.7, [1.0] * 4]  # non-uniform
    w = 1.0 + 0.3 * np.sin(X + Y) ** 2 if rational else None
    hs = HierarchicalSurface(BSplineSurface((3, 3), (t, t), P, w))
    o1 = hs.add_overlay((0.1, 0.7), (0.1, 0.7))
    o2 = hs.add_overlay((0.3, 0.5), (0.3, 0.5), o1)
    o3 = hs.add_overlay((0.375, 0.45), (0.375, 0.45), o2)
    rng = np.random.default_rng(5)
    for o, s in ((o1, 0.1), (o2, 0.05), (o3, 0.02)):
        hs.set_offsets(o, s * rng.standard_normal(o.shape + (3,)))
    hs.move_vertex(None, (4, 4), (0.0, 0.5, 1.5))
    return hs


@pytest.mark.parametrize("rational", [False, True])
def test_flat_form_agrees_with_occ_evaluation(rational):
    hs = make_hierarchy(rational)
    occ = to_occ(hs.flatten())
    rng = np.random.default_rng(0)
    u, v = rng.uniform(0, 1, 1500), rng.uniform(0, 1, 1500)
    ours = hs.evaluate(u, v)
    D = hs.derivatives(u, v, 1)
    p, du, dv = gp_Pnt(), gp_Vec(), gp_Vec()
    occ_p, occ_du, occ_dv = [], [], []
    for a, b in zip(u, v):
        occ.D1(float(a), float(b), p, du, dv)
        occ_p.append(p.Coord())
        occ_du.append(du.Coord())
        occ_dv.append(dv.Coord())
    # OCC's evaluation of the same exact poles: both round-off only. Measured max 3.6e-15 on
    # points (model size 6) and 6e-14 on first partials (|S_u| up to 23); tolerances 1e-12
    # relative to the model size / partial size.
    assert_allclose(np.array(occ_p), ours, rtol=0, atol=1e-12 * np.abs(ours).max())
    assert_allclose(np.array(occ_du), D[:, 1, 0], rtol=0, atol=1e-12 * np.abs(D[:, 1, 0]).max())
    assert_allclose(np.array(occ_dv), D[:, 0, 1], rtol=0, atol=1e-12 * np.abs(D[:, 0, 1]).max())
    counts = hs.pole_counts()
    assert counts["flat"] == occ.NbUPoles() * occ.NbVPoles()


def test_step_round_trip_restores_the_editable_hierarchy(tmp_path):
    hs = make_hierarchy(rational=True)
    step, side = write_hierarchical_step(tmp_path / "model.step", hs, name="hierarchical")
    assert side == sidecar_path(step) and side.name == "model.hierarchy.json"
    back = read_hierarchical_step(step)
    assert back.to_dict() == hs.to_dict()
    us = np.linspace(0, 1, 41)
    assert np.array_equal(back.evaluate_grid(us, us), hs.evaluate_grid(us, us))
    o2 = back.overlays[1]
    back.move_vertex(o2, (1, 1), (0.0, 0.0, 0.2))  # editable again, with its levels
    assert np.abs(back.evaluate_grid(us, us) - hs.evaluate_grid(us, us)).max() > 1e-3
    meta = json.loads(side.read_text())
    assert meta["pole_counts"] == hs.pole_counts() and meta["step_file"] == "model.step"


def test_curve_hierarchy_round_trip(tmp_path):
    from occsurf.algorithms import BSplineCurve

    t = np.r_[[0.0] * 4, 0.25, 0.5, 0.75, [1.0] * 4]
    hc = HierarchicalCurve(BSplineCurve(3, t, np.c_[np.linspace(0, 6, 7), np.zeros(7), np.zeros(7)]))
    o = hc.add_overlay((0.25, 0.75))
    hc.set_offset(o, 2, (0.0, 0.3, 0.1))
    step, _ = write_hierarchical_step(tmp_path / "curve.step", hc)
    back = read_hierarchical_step(step)
    assert back.to_dict() == hc.to_dict()


def test_stale_or_missing_sidecar_is_refused(tmp_path):
    hs = make_hierarchy()
    step, side = write_hierarchical_step(tmp_path / "m.step", hs)
    other = hs.copy()
    other.move_vertex(None, (0, 0), (0.0, 0.0, 0.5))
    write_step(step, other.flatten())  # the STEP file edited behind the sidecar's back
    with pytest.raises(ExchangeError, match="differs"):
        read_hierarchical_step(step)
    side.unlink()
    with pytest.raises(ExchangeError, match="no hierarchy sidecar"):
        read_hierarchical_step(step)
    side.write_text("{not json")
    with pytest.raises(ExchangeError, match="unreadable"):
        read_hierarchical_step(step)


def test_failed_write_leaves_no_files(tmp_path):
    with pytest.raises(ExchangeError):
        write_hierarchical_step(tmp_path / "missing" / "m.step", make_hierarchy())
    assert not any(tmp_path.iterdir())


def test_failed_write_keeps_the_old_pair_intact(tmp_path, monkeypatch):
    # Found in review: the STEP file was replaced before the sidecar was written, so a sidecar
    # that could not be written left a new STEP file beside the old, now stale, sidecar.
    hs = make_hierarchy()
    step, side = write_hierarchical_step(tmp_path / "m.step", hs)
    old = {p: p.read_bytes() for p in (step, side)}
    edited = hs.copy()
    edited.move_vertex(None, (0, 0), (0.0, 0.0, 0.5))
    side.unlink()
    side.mkdir()  # the sidecar path is unwritable
    with pytest.raises(ExchangeError, match="hierarchy.json"):
        write_hierarchical_step(step, edited)
    assert step.read_bytes() == old[step]
    side.rmdir()
    side.write_bytes(old[side])
    # A failure while writing the second file (disk full, ...): no temporary file is left and
    # neither target changes.
    import occsurf.bridge.exchange.hierarchical_io as hio

    calls = []

    def failing_fsync(fd):
        calls.append(fd)
        if len(calls) == 2:
            raise OSError(28, "No space left on device")

    monkeypatch.setattr(hio.os, "fsync", failing_fsync)
    with pytest.raises(ExchangeError, match="No space left"):
        write_hierarchical_step(step, edited)
    monkeypatch.undo()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.hierarchy.json", "m.step"]
    assert all(p.read_bytes() == b for p, b in old.items())
    assert read_hierarchical_step(step).to_dict() == hs.to_dict()


@pytest.mark.parametrize("change, match", [
    (lambda d: d.__setitem__("version", 0), "version 0"),
    (lambda d: d.__setitem__("version", True), "version True"),
    (lambda d: d["hierarchy"]["overlays"][0].__setitem__("region", 3), "overlay 1"),
    (lambda d: d["hierarchy"].__setitem__("overlays", [{"id": 1}]), "overlay 0"),
])
def test_malformed_sidecar_raises_exchange_error(tmp_path, change, match):
    step, side = write_hierarchical_step(tmp_path / "m.step", make_hierarchy())
    data = json.loads(side.read_text())
    change(data)
    side.write_text(json.dumps(data))
    with pytest.raises(ExchangeError, match=match):
        read_hierarchical_step(step)


REALDATA = Path(__file__).resolve().parents[2].parent / "shared" / "realdata"


@pytest.mark.slow
@pytest.mark.skipif(not (REALDATA / "occt__linkrods.step").is_file(), reason="../shared/realdata not available")
def test_real_step_free_form_faces_become_editable_bases():
    # occt__linkrods.step (OCCT sample data): rational B-spline faces of bidegree (6, 3..10),
    # non-uniform, domains like [-pi/2, pi/2] x [-0.75, -0.003].
    model = read_step(REALDATA / "occt__linkrods.step")
    picked = [k for k, f in enumerate(model.faces) if f.surface_type == "BSplineSurface"][::6]
    assert picked
    for k in picked:
        hs = import_step_base(REALDATA / "occt__linkrods.step", face=k)
        s = model.faces[k].surface
        assert hs.base == s
        (u0, u1), (v0, v1) = s.domain
        o1 = hs.add_overlay((u0 + 0.25 * (u1 - u0), u0 + 0.75 * (u1 - u0)), (v0 + 0.25 * (v1 - v0), v0 + 0.75 * (v1 - v0)))
        o2 = hs.add_overlay(*o1.region, parent=o1)
        us, vs = np.linspace(u0, u1, 31), np.linspace(v0, v1, 29)
        ref = s.evaluate_grid(us, vs)
        size = float(np.ptp(ref.reshape(-1, 3), axis=0).max())
        assert np.array_equal(hs.evaluate_grid(us, vs), ref)  # zero deltas: bit-identical
        c = (o2.shape[0] // 2, o2.shape[1] // 2)
        hs.set_offset(o2, c, (0.0, 0.0, 0.05 * size))
        g = [o2.reference_parameters[a][c[a]] for a in range(2)]
        n = s.normal(*g)
        lift = (hs.evaluate(*g) - s.evaluate(*g)) @ n
        assert 0 < lift <= 0.05 * size and np.isfinite(lift)
        # Flat form: Oslo refinement of rational nets, round-off only (measured <= 1.1e-15 of the
        # model size over all 18 faces).
        assert_allclose(hs.flatten().evaluate_grid(us, vs), hs.evaluate_grid(us, vs), rtol=0, atol=1e-12 * size)


def test_step_bspline_face_becomes_a_new_base(tmp_path):
    hs = make_hierarchy()
    flat = hs.flatten()
    path = write_step(tmp_path / "plain.step", flat)
    new = import_step_base(path)
    assert new.overlays == [] and new.base == flat  # bit-exact STEP round trip
    o = new.add_overlay((0.2, 0.6), (0.2, 0.6))
    new.set_offset(o, (1, 1), (0.0, 0.0, 0.1))
    assert_allclose(new.flatten().evaluate(0.4, 0.4), new.evaluate(0.4, 0.4), atol=1e-12)


def test_non_bspline_face_is_refused(tmp_path):
    import build123d as bd

    path = write_step(tmp_path / "box.step", bd.Box(1, 1, 1))
    with pytest.raises(ExchangeError, match="Plane"):
        import_step_base(path)
    with pytest.raises(ExchangeError, match="face index"):
        import_step_base(path, face=99)


@pytest.mark.slow
def test_demo_writes_pngs_step_and_sidecar(tmp_path):
    from occsurf.examples.hierarchical import render_hierarchical_demo

    files = render_hierarchical_demo(tmp_path / "hierarchical")
    pngs = [f for f in files if f.suffix == ".png"]
    assert len(pngs) == 3
    for f in pngs:
        assert f.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and f.stat().st_size > 10_000
    step = next(f for f in files if f.suffix == ".step")
    hs = read_hierarchical_step(step)
    assert hs.depth == 3 and len(hs.overlays) == 3


def test_resaved_step_is_checked_on_every_knot_span(tmp_path):
    """Review: the sidecar check sampled a fixed 17 x 17 grid, so a STEP file holding only the base
    (a detail 0.2 high at level 5 lost) loaded silently. An identical file is recognised by its
    stored SHA-256; a re-saved one is compared inside every knot span of the flat form."""
    k = [0, 0, 0, 0, 1 / 3, 2 / 3, 1, 1, 1, 1]
    base = BSplineSurface((3, 3), (k, k), np.random.default_rng(1).normal(size=(6, 6, 3)))
    hs = HierarchicalSurface(base)
    par = None
    for _ in range(5):
        par = hs.add_overlay((0.57, 0.61), (0.57, 0.61), parent=par)
    j = int(np.flatnonzero(np.isclose(par.knots[0], 55 / 96))[0]) - par.vertices[0][0]
    hs.set_offset(par, (j, j), (0, 0, 0.5))
    step, _ = write_hierarchical_step(tmp_path / "stale.step", hs)
    assert read_hierarchical_step(step).flatten().control_points.shape == hs.flatten().control_points.shape
    write_step(step, hs.flatten())  # saved again (new header): still the same geometry
    read_hierarchical_step(step)
    write_step(step, [base])  # the detail lost behind the sidecar's back
    with pytest.raises(ExchangeError, match="differs from the hierarchy"):
        read_hierarchical_step(step)


def test_step_and_stp_do_not_share_a_sidecar_silently(tmp_path):
    a, b = make_hierarchy(), make_hierarchy(rational=True)
    step, side = write_hierarchical_step(tmp_path / "model.step", a)
    before = side.read_bytes()
    with pytest.raises(ExchangeError, match=r"model\.hierarchy\.json: is the hierarchy sidecar of model\.step"):
        write_hierarchical_step(tmp_path / "model.stp", b)
    assert side.read_bytes() == before and not (tmp_path / "model.stp").exists()
    (tmp_path / "model.stp").write_bytes(step.read_bytes())  # a copy under the other name
    with pytest.raises(ExchangeError, match=r"the hierarchy sidecar of model\.step, not of model\.stp"):
        read_hierarchical_step(tmp_path / "model.stp")
    assert_allclose(read_hierarchical_step(step).flatten().control_points, a.flatten().control_points, rtol=0, atol=0)
