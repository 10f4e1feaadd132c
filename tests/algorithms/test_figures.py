"""Hierarchical surfaces for animated figures (course §5-42..5-47): skeletons, attached control nodes,
multi-segment joints, procedural offsets, the dynamic level. Closed forms and invariants; the demo
arm of :mod:`occsurf.examples.figures` is the articulated test case."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import cKDTree

from occsurf.algorithms import BSplineSurface, InvalidGeometryError
from occsurf.algorithms.hierarchical import (
    AttachedSurface,
    Binding,
    Joint,
    JointBulge,
    Skeleton,
    SoftTissue,
    attach,
    bind_to_bones,
    blend_motions,
    section_area,
)
from occsurf.algorithms.hierarchical.skinning import (
    invert_rigid,
    matrices_from_quaternions,
    quaternions_from_matrices,
    rigid_transform,
    rotation_about,
)
from occsurf.examples.figures import ARM, arm_skeleton, bisector, demo_arm, linear_baseline

US = np.linspace(0.0, 1.0, 41)
VS = np.linspace(0.0, 1.0, 37)


@pytest.fixture(scope="module")
def arm() -> AttachedSurface:
    return demo_arm()


def _rigid(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rigid_transform(rotation_about(rng.normal(size=3), rng.uniform(-np.pi, np.pi)), rng.uniform(-20, 20, 3))


# ------------------------------------------------------------------------------------ skinning
def test_quaternions_round_trip_every_branch_of_shepperds_method():
    angles = [0.0, 1e-9, 0.5, np.pi / 2, np.pi - 1e-9, np.pi]
    for axis in [(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 2, 3), (-3, 1, 0.5)]:
        for a in angles:
            R = rotation_about(axis, a)
            assert np.abs(matrices_from_quaternions(quaternions_from_matrices(R)) - R).max() < 1e-14


def test_single_weight_moves_exactly_by_that_motion_under_both_blends():
    rng = np.random.default_rng(3)
    P = rng.normal(size=(50, 3))
    M = np.stack([_rigid(1), _rigid(2)])
    W = np.zeros((50, 2))
    W[:25, 0] = W[25:, 1] = 1.0
    want = np.where(np.arange(50)[:, None] < 25, P @ M[0, :3, :3].T + M[0, :3, 3], P @ M[1, :3, :3].T + M[1, :3, 3])
    for blend in ("dual_quaternion", "linear"):
        assert np.abs(blend_motions(P, M, W, blend) - want).max() < 1e-13


def test_dual_quaternion_blend_of_a_hinge_is_the_rotation_by_the_closed_form_angle():
    """Two segments turning about one hinge: the blend with weight w is the rotation about the same
    hinge by phi, tan(phi / 2) = w sin(theta / 2) / (1 - w + w cos(theta / 2)); linear blending
    pulls the point to the hinge by |(1 - w) + w e^{i theta}| instead."""
    theta = np.radians(120.0)
    hinge = np.array([0.3, -0.2, 0.0])
    M1 = rigid_transform(rotation_about((0, 0, 1), theta), hinge - rotation_about((0, 0, 1), theta) @ hinge)
    M = np.stack([np.eye(4), M1])
    w = np.linspace(0.0, 1.0, 11)
    P = np.tile(hinge + np.array([0.0, 0.5, 0.7]), (11, 1))
    out = blend_motions(P, M, np.stack([1 - w, w], 1))
    phi = 2 * np.arctan2(w * np.sin(theta / 2), 1 - w + w * np.cos(theta / 2))
    want = np.einsum("kij,kj->ki", np.stack([rotation_about((0, 0, 1), p) for p in phi]), P - hinge) + hinge
    assert np.abs(out - want).max() < 1e-14
    r_lin = np.linalg.norm((blend_motions(P, M, np.stack([1 - w, w], 1), "linear") - hinge)[:, :2], axis=1)
    assert r_lin[5] == pytest.approx(0.5 * np.cos(theta / 2), rel=1e-12)  # halfway: cos(60 deg) of the radius


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 10_000), st.floats(-3.0, 3.0))
def test_dual_quaternion_blend_is_equivariant_under_a_rigid_motion(seed, angle):
    rng = np.random.default_rng(seed)
    P = rng.normal(size=(20, 3)) * 5
    M = np.stack([_rigid(seed + 1), rigid_transform(rotation_about((0, 0, 1), angle))])
    W = rng.dirichlet([1.0, 1.0], size=20)
    G = _rigid(seed + 7)
    a = blend_motions(P, M, W) @ G[:3, :3].T + G[:3, 3]
    b = blend_motions(P, G @ M, W)
    assert np.abs(a - b).max() < 1e-11


# ------------------------------------------------------------------------------------ skeleton
def test_pose_by_angle_equals_pose_by_matrix_and_the_angle_is_read_back():
    sk = arm_skeleton()
    a = 0.83
    by_angle = sk.pose({"elbow": a})
    by_matrix = sk.pose({"elbow": rigid_transform(rotation_about((0, 0, 1), a))})
    assert np.abs(by_angle.frames - by_matrix.frames).max() < 1e-15
    assert by_matrix.angle("elbow") == pytest.approx(a, abs=1e-15)
    # the forearm's bone turns by a about z, around the elbow at the origin
    bones = by_angle.bones()
    assert np.abs(bones[1, 0]).max() < 1e-15
    assert np.abs(bones[1, 1] - ARM["fore"] * np.array([np.cos(a), np.sin(a), 0])).max() < 1e-14
    assert np.abs(sk.pose().motions - np.eye(4)).max() < 1e-15


def test_skeleton_round_trips_through_json():
    sk = Skeleton([Joint("hip", None, _rigid(5), length=1.0), Joint("knee", "hip", (1.0, 0, 0), axis=(0, 1, 0), length=2.0),
                   Joint("toe", "knee", (2.0, 0, 0), length=0.3)])
    back = Skeleton.from_dict(json.loads(json.dumps(sk.to_dict())))
    assert back.names == sk.names
    p, q = sk.pose({"knee": 0.4, "toe": -0.2}), back.pose({"knee": 0.4, "toe": -0.2})
    assert np.array_equal(p.frames, q.frames)


@pytest.mark.parametrize(("joints", "message"), [
    ([Joint("a", "b"), Joint("b", "a")], "form a cycle"),
    ([Joint("r"), Joint("a", "b"), Joint("b", "a")], "form a cycle"),
    ([Joint("r"), Joint("a", "nope")], "unknown parent 'nope'"),
    ([Joint("r"), Joint("r", "r")], "used twice"),
    ([Joint("r"), Joint("s")], "exactly one root"),
])
def test_bad_skeletons_are_refused_in_one_line(joints, message):
    with pytest.raises(InvalidGeometryError, match=message) as err:
        Skeleton(joints)
    assert "\n" not in str(err.value)


def test_bad_joints_and_poses_are_refused_and_nothing_changes(arm):
    with pytest.raises(InvalidGeometryError, match="not a proper rotation"):
        Joint("a", None, np.diag([2.0, 1.0, 1.0, 1.0]))
    with pytest.raises(InvalidGeometryError, match="axis"):
        Joint("a", None, axis=(0, 0, 0))
    sk = arm.skeleton
    with pytest.raises(InvalidGeometryError, match="angle of joint 'elbow' is not finite"):
        sk.pose({"elbow": float("nan")})
    with pytest.raises(InvalidGeometryError, match="unknown joint 'wrist'"):
        sk.pose({"wrist": 0.1})
    with pytest.raises(InvalidGeometryError, match="not a proper rotation"):
        sk.pose({"elbow": np.diag([1.0, 1.0, -1.0, 1.0])})
    with pytest.raises(InvalidGeometryError, match="placement"):
        sk.pose(placement=np.full((4, 4), np.inf))


# ------------------------------------------------------------------------------------ bindings
def test_bind_to_bones_is_rigid_away_from_the_joint_and_blends_across_it(arm):
    P = arm.rest.base.control_points
    b = bind_to_bones(P, arm.skeleton, ARM["blend"])
    W = b.weights
    x = P[..., 0]
    assert np.array_equal(W[x <= -ARM["blend"]], np.tile([1.0, 0.0], ((x <= -ARM["blend"]).sum(), 1)))
    assert np.array_equal(W[x >= ARM["blend"]], np.tile([0.0, 1.0], ((x >= ARM["blend"]).sum(), 1)))
    mid = np.abs(x) < ARM["blend"]
    assert mid.any() and np.all((W[mid, 1] > 0) & (W[mid, 1] < 1))
    order = np.argsort(x[:, 0])
    assert np.all(np.diff(W[order, 0, 1]) >= 0)  # the forearm's weight grows along the arm


@pytest.mark.parametrize(("make", "message"), [
    (lambda s: {None: Binding(("shoulder", "wrist"), np.tile([0.5, 0.5], s + (1,)))}, "unknown joint 'wrist'"),
    (lambda s: {None: Binding(("shoulder", "elbow"), np.tile([0.5, 0.6], s + (1,)))}, "sum to 1.1"),
    (lambda s: {None: Binding(("shoulder", "elbow"), np.tile([1.5, -0.5], s + (1,)))}, "negative weight"),
    (lambda s: {None: Binding(("shoulder",), np.ones((3, 3, 1)))}, "weights for a net of"),
    (lambda s: {2: Binding.rigid("shoulder", s)}, "the base must be bound"),
    (lambda s: {None: Binding.rigid("shoulder", s), 99: Binding(("shoulder",), np.ones((3, 3, 1)))}, "neither the base"),
])
def test_bad_bindings_are_refused_in_one_line(arm, make, message):
    rest = arm.rest
    shape = tuple(rest.base.n_poles) if "base must" not in message else rest.overlays[1].shape
    with pytest.raises(InvalidGeometryError, match=message) as err:
        attach(rest, arm.skeleton, make(shape))
    assert "\n" not in str(err.value)


def test_a_bound_overlay_needs_its_parent_bound():
    base = BSplineSurface((3, 3), (np.r_[[0.0] * 4, 0.5, [1.0] * 4],) * 2,
                          np.stack([*np.meshgrid(np.linspace(0, 1, 5), np.linspace(0, 1, 5), indexing="ij"), np.zeros((5, 5))], -1))
    from occsurf.algorithms.hierarchical import HierarchicalSurface
    hs = HierarchicalSurface(base)
    o1 = hs.add_overlay((0.0, 1.0), (0.0, 1.0))
    o2 = hs.add_overlay((0.25, 0.75), (0.25, 0.75), o1)
    sk = Skeleton([Joint("r")])
    with pytest.raises(InvalidGeometryError, match=f"overlay {o2.id} is bound but its parent {o1.id} is not"):
        attach(hs, sk, {None: Binding.rigid("r", (5, 5)), o2: Binding.rigid("r", o2.shape)})


# ------------------------------------------------------------------------------------ invariants
def test_rest_pose_reproduces_the_unattached_surface(arm):
    rest = arm.rest
    posed = arm.at(arm.skeleton.pose())
    assert np.abs(posed.evaluate_grid(US, VS) - rest.evaluate_grid(US, VS)).max() < 1e-14
    assert np.abs(posed.flatten().control_points - rest.flatten().control_points).max() < 1e-14


def test_rest_pose_with_a_bound_overlay_reproduces_the_surface_too(arm):
    rest = arm.rest
    vein = rest.overlays[1]
    b = {None: arm.bindings[0], vein: bind_to_bones(rest.control_points(vein), arm.skeleton, ARM["blend"])}
    fig = attach(rest, arm.skeleton, b)
    assert np.abs(fig.at(arm.skeleton.pose()).evaluate_grid(US, VS) - rest.evaluate_grid(US, VS)).max() < 1e-14
    # posed, the bound overlay's vertices are where its binding puts them (not carried by the parent)
    pose = arm.skeleton.pose({"elbow": 1.1})
    assert np.abs(fig.at(pose).control_points(vein) - fig.control_targets(pose, vein.id)).max() < 1e-13


@pytest.mark.parametrize("seed", range(4))
def test_a_rigid_motion_of_the_whole_skeleton_moves_the_surface_rigidly(arm, seed):
    G = _rigid(seed)
    for angle in (0.0, 0.7, 2.0):
        a = arm.at(arm.skeleton.pose({"elbow": angle})).evaluate_grid(US, VS)
        b = arm.at(arm.skeleton.pose({"elbow": angle}, placement=G)).evaluate_grid(US, VS)
        assert np.abs(a @ G[:3, :3].T + G[:3, 3] - b).max() < 1e-12


def test_overlay_offsets_ride_unchanged_in_the_posed_frames(arm):
    """The course's claim (§5-42): posing changes the frames, never an overlay's stored offsets; the
    world displacement of every overlay vertex is the posed frame times the same offset."""
    rest = arm.rest
    posed = arm.at(arm.skeleton.pose({"elbow": np.radians(100)}))
    for o in rest.overlays[1:]:  # vein and elbow point: not procedural
        assert np.array_equal(posed.offsets(o.id), rest.offsets(o.id))
        F = posed.reference_frames(o.id)
        disp = np.einsum("...ij,...j->...i", F, posed.offsets(o.id))
        parent = posed.level_surface(o.parent).refine(o.inserted[0], direction="u").refine(o.inserted[1], direction="v")
        (a, b), (c, d) = o.vertices
        reference = parent.control_points[a:b + 1, c:d + 1]
        assert np.abs(posed.control_points(o.id) - reference - disp).max() < 1e-13
        # the posed frames turned with the forearm where the base is rigid with it: past the blend
        # zone by the base's support (3 spans of 5.6 / 27)
        if o.id == 2:
            R = rotation_about((0, 0, 1), np.radians(100))
            x = rest.control_points(o.id)[..., 0]
            rigid = x > ARM["blend"] + 3 * 5.6 / 27
            assert rigid.sum() >= 9
            turned = np.einsum("ij,...jk->...ik", R, rest.reference_frames(o.id))
            assert np.abs(F[rigid] - turned[rigid]).max() < 1e-12


def test_the_bulge_grows_with_the_elbow_angle_along_the_parent_normal(arm):
    bulge = arm.procedures[0]
    assert isinstance(bulge, JointBulge)
    rest = arm.rest
    for deg in (0.0, 45.0, 120.0):
        th = np.radians(deg)
        posed = arm.at(arm.skeleton.pose({"elbow": th}))
        extra = posed.offsets(bulge.overlay) - rest.offsets(bulge.overlay)
        want = bulge.gain * th * np.asarray(bulge.profile)
        assert np.abs(extra[..., :2]).max() == 0.0
        assert np.abs(extra[..., 2] - want).max() < 1e-15
    # extension (negative angle) does not flex it
    neg = arm.at(arm.skeleton.pose({"elbow": -0.3}))
    assert np.array_equal(neg.offsets(bulge.overlay), rest.offsets(bulge.overlay))


def test_attached_surface_round_trips_through_json(arm):
    back = AttachedSurface.from_dict(json.loads(json.dumps(arm.to_dict())))
    for angle in (0.0, 1.3):
        a = arm.at(arm.skeleton.pose({"elbow": angle})).flatten()
        b = back.at(back.skeleton.pose({"elbow": angle})).flatten()
        assert np.array_equal(a.control_points, b.control_points)
    bad = arm.to_dict()
    bad["procedures"][0]["kind"] = "tentacle"
    with pytest.raises(InvalidGeometryError, match="unknown procedure kind 'tentacle'"):
        AttachedSurface.from_dict(bad)


# ------------------------------------------------------------------------------------ the bent elbow
def _crossings(c: np.ndarray) -> int:
    """Proper crossings between non-adjacent segments of a polyline (x, y)."""
    p, d = c[:-1], np.diff(c, axis=0)
    i, j = np.triu_indices(len(p), 2)
    den = d[i, 0] * d[j, 1] - d[i, 1] * d[j, 0]
    w = p[j] - p[i]
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (w[:, 0] * d[j, 1] - w[:, 1] * d[j, 0]) / den
        t = (w[:, 0] * d[i, 1] - w[:, 1] * d[i, 0]) / den
    return int(np.sum((s > 0) & (s < 1) & (t > 0) & (t < 1)))


def test_the_bent_elbow_keeps_its_section_and_does_not_self_intersect(arm):
    """Bending 0..120 degrees with the multi-segment joint: the cross-section area at the elbow (the
    plane halving the bend) stays within 20 % of rest, the generators in the bend plane (the inner
    and outer sides, where a bent tube folds first) never cross themselves, and the inner sides of
    the two rigid parts stay apart. The baseline (the flat surface's poles blended linearly)
    collapses to cos(theta / 2) of the area.

    Clearance: the distance between the samples of the upper arm (rest x <= -0.2) and of the forearm
    (rest x >= 0.2), the crease of the joint itself (0.4 elbow radii) left out. At 120 degrees it is
    the flexed biceps' gap to the forearm. The samples are 0.007 apart along the arm and 0.025
    around, so the sampled distance overstates the true one by at most 0.013."""
    sk = arm.skeleton
    lin = linear_baseline(arm)
    us, vs = np.linspace(0, 1, 801), np.linspace(0, 1, 129)
    rest = arm.rest.evaluate_grid(us, vs)
    rx = rest[:, 0, 0]
    inner, outer = int(np.argmax(rest[400, :, 1])), int(np.argmin(rest[400, :, 1]))
    a0 = section_area(arm.at(sk.pose()), *bisector(0.0))
    l0 = section_area(lin.at(sk.pose()), *bisector(0.0))
    rows = []
    for deg in np.arange(0.0, 121.0, 15.0):
        th = np.radians(deg)
        pose = sk.pose({"elbow": th})
        P = arm.at(pose).evaluate_grid(us, vs)
        ours = section_area(arm.at(pose), *bisector(th)) / a0
        base = section_area(lin.at(pose), *bisector(th)) / l0
        far_a, far_b = P[rx <= -0.2].reshape(-1, 3), P[rx >= 0.2].reshape(-1, 3)
        clearance = float(cKDTree(far_b).query(far_a)[0].min())
        rows.append((deg, ours, base, clearance))
        assert abs(ours - 1.0) <= 0.2, (deg, ours)
        assert _crossings(P[:, inner, :2]) == 0 and _crossings(P[:, outer, :2]) == 0, deg
        assert clearance > 0.05, (deg, clearance)  # > 0 with room for the sampling's 0.013
    print("\nelbow deg | area ours / rest | area linear baseline / rest | clearance of the inner sides")
    for r in rows:
        print(f"{r[0]:9.0f} | {r[1]:16.4f} | {r[2]:27.4f} | {r[3]:.4f}")
    assert rows[-1][2] < 0.8  # the baseline collapses (cos 60 deg = 0.5)
    assert rows[-1][2] == pytest.approx(0.5, abs=0.01)


def test_a_narrow_joint_does_let_the_inner_side_cross(arm):
    """The check above can fail: with a blend zone of 1.6 elbow radii the inner generator crosses
    itself at 120 degrees (the rigid parts meet r tan 60 deg = 0.87 from the joint)."""
    narrow = attach(arm.rest, arm.skeleton, bind_to_bones(arm.rest.base.control_points, arm.skeleton, 0.8))
    us, vs = np.linspace(0, 1, 801), np.linspace(0, 1, 97)
    inner = int(np.argmax(arm.rest.evaluate_grid(us, vs)[400, :, 1]))
    P = narrow.at(arm.skeleton.pose({"elbow": np.radians(120)})).evaluate_grid(us, vs)
    assert _crossings(P[:, inner, :2]) > 0


def _rational_tube(r: float) -> BSplineSurface:
    """An exact circular cylinder of radius r along x (rational quadratic circle around v)."""
    w = np.sqrt(0.5)
    ring = np.array([[1, 0], [1, 1], [0, 1], [-1, 1], [-1, 0], [-1, -1], [0, -1], [1, -1], [1, 0]], float) * r
    wts = np.array([1, w, 1, w, 1, w, 1, w, 1])
    x = np.linspace(-1.0, 1.0, 4)
    P = np.stack([np.broadcast_to(x[:, None], (4, 9)), np.broadcast_to(ring[:, 0], (4, 9)),
                  np.broadcast_to(ring[:, 1], (4, 9))], -1)
    tv = np.r_[0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1]
    return BSplineSurface((3, 2), (np.r_[[0.0] * 4, [1.0] * 4], tv), P, np.tile(wts, (4, 1)))


@pytest.mark.parametrize("samples", [(801, 256), (801, 255)])
def test_section_area_of_an_exact_cylinder_and_its_tilted_ellipse(samples):
    """Closed forms: pi r^2, and pi r^2 / cos(a) for a plane tilted by a; the Richardson-extrapolated
    polygons are within 1.5e-8 (an odd count is rounded up to an even one, not left without it)."""
    s = _rational_tube(0.7)
    assert section_area(s, (0.1, 0, 0), (1, 0, 0), samples=samples) == pytest.approx(np.pi * 0.49, rel=3e-8)
    tilted = section_area(s, (0.0, 0, 0), (np.cos(0.3), np.sin(0.3), 0), samples=samples)
    assert tilted == pytest.approx(np.pi * 0.49 / np.cos(0.3), rel=3e-8)


@pytest.mark.parametrize(("call", "message"), [
    (lambda s: section_area(s, (0, 0, 0), (0, 0, 0)), "normal non-zero"),
    (lambda s: section_area(s, (0, 0, 0), (1, 0, 0), samples=(1, 1)), "at least 3"),
    (lambda s: section_area("x", (0, 0, 0), (1, 0, 0)), "expected a 3-D"),  # type: ignore[arg-type]
    (lambda s: section_area(s, (5, 0, 0), (1, 0, 0)), "do not cross the plane"),
])
def test_section_area_refuses_bad_arguments_in_one_line(call, message):
    with pytest.raises(InvalidGeometryError, match=message):
        call(_rational_tube(0.7))


# ------------------------------------------------------------------------------------ dynamics
def test_soft_tissue_settles_within_its_stated_time_after_the_motion_stops(arm):
    sk = arm.skeleton
    tissue = SoftTissue(arm, 0, mass=1.0, stiffness=300.0, coupling=150.0, damping=5.0)
    dt = 1.0 / 60.0
    for a in np.radians(np.linspace(0.0, 110.0, 19)):  # 0.3 s of bending, then a sudden stop
        tissue.step(sk.pose({"elbow": float(a)}), dt)
    still = sk.pose({"elbow": float(np.radians(110.0))})
    tissue.step(still, dt)  # the stop: the skeleton's deceleration is the last force
    e_stop, t_stop = tissue.energy(), tissue.time
    assert e_stop > 1e-4  # the motion did excite it
    bound = tissue.settle_time(0.01)
    energies = []
    while tissue.time < t_stop + bound:
        tissue.step(still, dt)
        energies.append(tissue.energy())
    assert energies[-1] < 0.01 * e_stop
    first = t_stop + dt * (1 + int(np.argmax(np.asarray(energies) < 0.01 * e_stop)))
    print(f"\nenergy at the stop {e_stop:.3e}; below 1 % after {first - t_stop:.3f} s (bound {bound:.3f} s)")
    # settled, the surface is the kinematic pose again
    assert np.abs(tissue.deviation).max() < 0.1 * np.sqrt(e_stop)
    hs = tissue.surface()
    assert np.array_equal(hs.offsets(2), arm.rest.offsets(2))  # finer levels keep their offsets


def test_soft_tissue_step_is_stable_for_any_time_step(arm):
    tissue = SoftTissue(arm, 0, mass=1.0, stiffness=300.0, coupling=150.0, damping=5.0)
    for h in (1e-4, 1 / 240, 1 / 24, 1.0, 100.0):
        Phi, _ = tissue.propagator(h)
        rho = max(np.abs(np.linalg.eigvals(P)).max() for P in Phi[::50])
        assert rho <= np.exp(-5.0 * h / 2) * (1 + 1e-9), h  # the spectral radius of the exact step
    # a still skeleton never excites it
    for _ in range(5):
        tissue.step(arm.skeleton.pose(), 0.1)
    assert tissue.energy() == 0.0


def test_soft_tissue_refuses_bad_parameters(arm):
    with pytest.raises(InvalidGeometryError, match="overdamped"):
        SoftTissue(arm, 0, stiffness=1.0, damping=5.0)
    with pytest.raises(InvalidGeometryError, match="mass"):
        SoftTissue(arm, 0, mass=float("nan"))
    with pytest.raises(InvalidGeometryError, match="no overlay 42"):
        SoftTissue(arm, 42)
    tissue = SoftTissue(arm, 0)
    with pytest.raises(InvalidGeometryError, match="dt"):
        tissue.step(arm.skeleton.pose(), 0.0)


def test_a_dynamic_overlay_level_jiggles_and_carries_its_finer_levels(arm):
    vein = arm.rest.overlays[1]
    tissue = SoftTissue(arm, vein.id, stiffness=200.0, coupling=50.0, damping=4.0)
    for a in np.radians(np.linspace(0, 90, 10)):
        hs = tissue.step(arm.skeleton.pose({"elbow": float(a)}), 1 / 60)
    kin = arm.at(arm.skeleton.pose({"elbow": float(np.radians(90))}))
    dev = hs.control_points(vein.id) - kin.control_points(vein.id)
    assert np.abs(dev - tissue.deviation).max() < 1e-12 and np.abs(dev).max() > 1e-4
    assert np.array_equal(hs.base.control_points, kin.base.control_points)  # coarser levels untouched


def test_invert_rigid_is_the_inverse():
    M = _rigid(11)
    # translations of ~20: round-off of a few ulps of 20 (4e-15) in the last column
    assert np.abs(M @ invert_rigid(M) - np.eye(4)).max() < 20 * 4 * np.finfo(float).eps


def test_the_dct_diagonalises_the_grid_laplacian():
    """The dynamic level's modes: Q^T L Q = diag(eigenvalues) with Q the two-axis orthonormal DCT-II."""
    import scipy.fft

    from occsurf.algorithms.hierarchical.dynamics import grid_laplacian, grid_laplacian_eigenvalues

    shape = (7, 5)
    n = 35
    Q = scipy.fft.idctn(np.eye(n).reshape(n, *shape), type=2, norm="ortho", axes=(1, 2)).reshape(n, n).T
    assert np.abs(Q.T @ Q - np.eye(n)).max() < 1e-14
    assert np.abs(Q.T @ grid_laplacian(shape) @ Q - np.diag(grid_laplacian_eigenvalues(shape).reshape(-1))).max() < 1e-13


# ------------------------------------------------------------------------------------ review fixes
def test_a_matrix_pose_reports_its_twist_about_the_hinge_only(arm):
    sk = arm.skeleton
    off_axis = sk.pose({"elbow": rigid_transform(rotation_about((1, 0, 0), 2.0))})
    assert off_axis.angle("elbow") == 0.0  # a pure twist about the bone: no bend, no bulge
    rest = arm.rest
    bulge = arm.procedures[0]
    assert np.array_equal(arm.at(off_axis).offsets(bulge.overlay), rest.offsets(bulge.overlay))
    # swing-twist: a rotation of 2.5 about (1, 0, 1) twists by 2 atan(tan(1.25) / sqrt(2)) about z
    tilted = sk.pose({"elbow": rigid_transform(rotation_about((1, 0, 1), 2.5))}).angle("elbow")
    assert tilted == pytest.approx(2 * np.arctan(np.tan(1.25) / np.sqrt(2)), abs=1e-14)
    assert abs(tilted) < 2.5
    # an angle given as a number is kept as given; as a matrix it is wrapped into (-pi, pi]
    assert sk.pose({"elbow": 4.0}).angle("elbow") == 4.0
    assert sk.pose({"elbow": rigid_transform(rotation_about((0, 0, 1), 4.0))}).angle("elbow") == pytest.approx(
        4.0 - 2 * np.pi, abs=1e-14)


def _chain(lengths, rot_seed=None) -> Skeleton:
    joints, parent = [], None
    for k, length in enumerate(lengths):
        rest = (np.eye(4) if rot_seed is None else _rigid(rot_seed)) if k == 0 else (lengths[k - 1], 0.0, 0.0)
        joints.append(Joint(f"j{k}", parent, rest, length=length))
        parent = f"j{k}"
    return Skeleton(joints)


def test_bind_to_bones_on_bones_shorter_than_the_blend_zone_sums_to_one():
    sk = _chain([1.0, 1.0, 1.0])
    x = np.linspace(-0.2, 3.2, 40)
    P = np.stack([*np.meshgrid(x, [0.3, -0.3], indexing="ij"), np.zeros((40, 2))], -1)
    b = bind_to_bones(P, sk, 0.6)  # zones of 1.2 overlap on bones of length 1
    W = b.weights
    assert np.abs(W.sum(-1) - 1).max() < 1e-15 and W.min() >= 0
    middle = np.abs(P[..., 0] - 1.5) < 0.05
    assert np.all(W[middle][:, [0, 1, 2]].min(axis=0) > 0)  # the middle bone shares with both neighbours


@pytest.mark.parametrize(("call", "message"), [
    (lambda: Joint("a", length="abc"), "length must be a number"),
    (lambda: Joint("a", length=None), "length must be a number"),
    (lambda: Binding.rigid("a", (np.nan, 3)), "two positive integers"),
    (lambda: Binding("elbow", np.ones((2, 2, 5)) / 5), "the string 'elbow'"),
    (lambda: Skeleton.from_dict({"type": "Skeleton", "version": 1, "joints": [
        {"name": "a", "parent": None, "rest": [[1, 0], [0]], "axis": [0, 0, 1], "length": 1}]}), "joint 0"),
    (lambda: Skeleton.from_dict({"type": "Skeleton", "version": 1, "joints": [
        {"name": "a", "parent": None, "rest": np.eye(4).tolist(), "axis": [0, 0, 1], "length": "x"}]}), "joint 0"),
])
def test_bad_constructor_and_stored_data_give_one_line_errors(call, message):
    with pytest.raises(InvalidGeometryError, match=message) as err:
        call()
    assert "\n" not in str(err.value)


def test_bad_calls_on_an_attached_surface_give_one_line_errors(arm):
    with pytest.raises(InvalidGeometryError, match="not bound"):
        arm.control_targets(arm.skeleton.pose(), 1)
    with pytest.raises(InvalidGeometryError, match="procedures"):
        attach(arm.rest, arm.skeleton, arm.bindings[0], procedures=5)  # type: ignore[arg-type]
    with pytest.raises(InvalidGeometryError, match="bound twice"):
        attach(arm.rest, arm.skeleton, {None: arm.bindings[0], 0: arm.bindings[0]})
    bad = arm.to_dict()
    bad["bindings"][0]["weights"] = "nope"
    with pytest.raises(InvalidGeometryError, match="^from_dict: AttachedSurface: ") as err:
        AttachedSurface.from_dict(bad)
    assert "InvalidGeometryError(" not in str(err.value)
    with pytest.raises(InvalidGeometryError, match="mass"):
        SoftTissue(arm, 0, mass=True)  # type: ignore[arg-type]


def test_rest_motions_are_exactly_the_identity_with_rotated_rest_frames():
    """A rotated rest frame far from the origin: the rest pose moves nothing by exactly I (not by
    W W^-1, which is 7e-15 off), so the rest surface is reproduced bit for bit."""
    sk = _chain([30.0, 25.0], rot_seed=9)
    assert np.array_equal(sk.pose().motions, np.broadcast_to(np.eye(4), (2, 4, 4)))
    moved = sk.pose({"j1": 0.3}).motions
    assert np.array_equal(moved[0], np.eye(4)) and not np.array_equal(moved[1], np.eye(4))
    base = BSplineSurface((1, 1), ([0, 0, 1, 1], [0, 0, 1, 1]),
                          (sk.rest_frame("j1") @ np.array([[[0, 1, 0, 1], [0, -1, 0, 1]], [[40, 1, 0, 1], [40, -1, 0, 1]]],
                                                          float).reshape(-1, 4).T).T.reshape(2, 2, 4)[..., :3])
    fig = attach(base, sk, bind_to_bones(base.control_points, sk, 5.0))
    assert np.array_equal(fig.at(sk.pose()).flatten().control_points, base.control_points)


def test_a_nearly_orthonormal_rest_is_made_exactly_rigid():
    R = rotation_about((1, 2, 3), 0.4)
    j = Joint("a", None, np.round(np.block([[R, np.ones((3, 1))], [np.zeros((1, 3)), np.ones((1, 1))]]), 10))
    Q = j.rest_matrix[:3, :3]
    assert np.abs(Q.T @ Q - np.eye(3)).max() < 1e-15


def test_propagators_are_cached_for_a_few_time_steps_only(arm):
    from occsurf.algorithms.hierarchical.dynamics import PROPAGATOR_CACHE

    tissue = SoftTissue(arm, 4)
    for k in range(3 * PROPAGATOR_CACHE):
        tissue.step(arm.skeleton.pose({"elbow": 0.01 * k}), 1 / 60 + 1e-5 * k)  # jittered frame times
    assert len(tissue._props) == PROPAGATOR_CACHE  # noqa: SLF001 - the bound is the point


@st.composite
def _figure_case(draw):
    """A branched skeleton of 3 levels (rotated rest frames), a random pose and placement."""
    seed = draw(st.integers(0, 10_000))
    rng = np.random.default_rng(seed)
    joints = [Joint("root", None, _rigid(seed), length=2.0), Joint("a", "root", (2.0, 0, 0), axis=rng.normal(size=3), length=1.5),
              Joint("b", "root", rigid_transform(rotation_about((0, 0, 1), 0.8), (2.0, 0, 0)), length=1.0),
              Joint("c", "a", (1.5, 0, 0), length=1.0)]
    angles = {n: draw(st.floats(-2.5, 2.5)) for n in ("root", "a", "b", "c")}
    return seed, Skeleton(joints), angles


@settings(max_examples=25, deadline=None)
@given(_figure_case(), st.booleans())
def test_rest_and_rigid_invariance_on_random_branched_skeletons(case, rational):
    seed, sk, angles = case
    rng = np.random.default_rng(seed)
    F = sk.rest_frame("root")
    u = np.linspace(-0.5, 4.5, 8)
    P = np.stack([*np.meshgrid(u, [-0.4, 0.0, 0.4, 0.8], indexing="ij"), rng.uniform(-0.2, 0.2, (8, 4))], -1)
    P = P @ F[:3, :3].T + F[:3, 3]
    kn = (np.r_[[0.0] * 4, np.linspace(0, 1, 6)[1:-1], [1.0] * 4], np.r_[[0.0] * 4, [1.0] * 4])
    base = BSplineSurface((3, 3), kn, P, rng.uniform(0.5, 2.0, (8, 4)) if rational else None)
    from occsurf.algorithms.hierarchical import HierarchicalSurface

    hs = HierarchicalSurface(base)
    o = hs.add_overlay((0.2, 0.8), (0.0, 1.0))
    hs.set_offsets(o, 0.05 * rng.standard_normal(o.shape + (3,)))
    fig = attach(hs, sk, bind_to_bones(P, sk, 0.8))
    us, vs = np.linspace(0, 1, 9), np.linspace(0, 1, 7)
    assert np.array_equal(fig.at(sk.pose()).evaluate_grid(us, vs), hs.evaluate_grid(us, vs))
    G = _rigid(seed + 3)
    a = fig.at(sk.pose(angles)).evaluate_grid(us, vs)
    b = fig.at(sk.pose(angles, placement=G)).evaluate_grid(us, vs)
    scale = max(1.0, float(np.abs(a).max()))
    assert np.abs(a @ G[:3, :3].T + G[:3, 3] - b).max() < 1e-13 * scale
