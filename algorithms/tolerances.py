"""Every numeric tolerance and limit of :mod:`occsurf.algorithms`, in one place, overridable.

Each value is read where it is used, at call time, as ``tolerances.NAME``; so a block of code can
change any of them with :func:`override`::

    from occsurf.algorithms import tolerances
    with tolerances.override(KNOT_REMOVAL=1e-6, SWEEP_TOLERANCE=1e-8):
        c2 = c.remove_knot(0.5)

Overrides live in a :class:`contextvars.ContextVar`: they apply to the thread (or asyncio task) that
set them and to nothing else, so two threads can work with different tolerances at once. Functions
also take an explicit ``tol=`` keyword where a caller typically wants its own value; it wins over the
value here. :data:`MAX_DEGREE` is a kernel limit (OpenCascade's), not a tolerance: it cannot be
overridden. :func:`defaults` lists every name with its default value.

The names are grouped by the subpackage that reads them; names used by one family only carry its
prefix (``SWEEP_``, ``GORDON_``, ``SPATCH_``, ``FILL_``, ``DRAG_``).
"""

from __future__ import annotations

import contextlib
import contextvars
import math
from collections.abc import Iterator, Mapping
from types import MappingProxyType

__all__ = ["MAX_DEGREE", "override", "defaults", "get"]

#: Highest degree accepted, the same as OpenCascade's ``Geom_BSplineCurve::MaxDegree()`` so that
#: every spline we build can be handed to OCC (a test asks OCC). A kernel limit: not overridable.
MAX_DEGREE: int = 25

_DEFAULTS: dict[str, float] = {
    # ---- kernel (course ch. 2, 12) -------------------------------------------------------------
    # Two knots closer than this (relative to the knot range) are treated as one knot when counting
    # multiplicities, inserting, or converting to OCC's distinct knots + multiplicities.
    "KNOT_EQUALITY": 1e-12,
    # How far (relative to the domain length) a parameter may lie outside the domain and still be
    # snapped onto it rather than rejected. Covers round-off in callers' arithmetic.
    "PARAMETER": 1e-10,
    # Default geometric tolerance for knot removal: the largest allowed movement of any control
    # point of the refined representation (which bounds the movement of the curve by the
    # convex-hull property). Absolute, in model units.
    "KNOT_REMOVAL": 1e-9,
    # Largest array (bytes) an evaluation may allocate for its result or work space (evaluate_grid,
    # derivatives of high order, S-patch index sets, deviation grids): a request above it is refused
    # with its size named before anything is allocated or computed for minutes.
    "MAX_ARRAY_BYTES": 1 << 31,
    # Smallest number of evaluated points for which the numba kernels are used. The first use in a
    # process costs about 0.5 s (importing numba, loading the cached kernels); from 2**15 points on
    # a kernel saves ~15 ms per scattered evaluation, so that cost is repaid after a few dozen
    # calls, and below it the NumPy path takes a few milliseconds anyway.
    "NUMBA_MIN_POINTS": 1 << 15,
    # Trimmed surfaces (kernel/trimmed.py). The p-curves of a face are refined to polylines that
    # stay within TRIM_POLYLINE of them (relative to the diagonal of the surface's parameter box) for
    # point classification, in at most TRIM_POLYLINE_LEVELS halvings of the initial samples.
    "TRIM_POLYLINE": 1e-8,
    "TRIM_POLYLINE_LEVELS": 30,
    # Points within TRIM_ON (relative to the parameter box's diagonal) of a loop are classified ON
    # the boundary (contained in the face): the band absorbs the polyline error and round-off.
    "TRIM_ON": 1e-7,
    # Largest gap between consecutive p-curves of a loop (or between a p-curve and the surface's
    # domain), relative to the parameter box's diagonal. Imported faces carry gaps of the order of
    # their edge tolerances (1e-7 .. 1e-4 of the model size); larger ones mean an open loop.
    "TRIM_LOOP_GAP": 1e-3,
    # Area of a trimmed face: Gauss-Legendre on knot spans cut in 2^level pieces, level raised until
    # two successive values agree to TRIM_AREA_RTOL, at most TRIM_AREA_LEVELS times.
    "TRIM_AREA_RTOL": 1e-12,
    "TRIM_AREA_LEVELS": 6,
    # When the area does not converge, |S_u x S_v| below TRIM_AREA_SINGULAR times its largest value
    # inside the face is reported as the cause (a near-singular parametrisation).
    "TRIM_AREA_SINGULAR": 1e-3,
    # ---- geometry (course ch. 1, §6-0..6-14) ---------------------------------------------------
    # Tolerance on weights that must sum to one (affine combinations).
    "WEIGHT_SUM": 1e-12,
    # A frame basis (or any matrix that must be inverted, e.g. of an affine or projective map)
    # whose 2-norm condition number exceeds this is treated as singular: its inverse would lose
    # more than ~12 of 16 significant digits.
    "MAX_CONDITION": 1e12,
    # A curve point has no Frenet normal when |C' x C''| <= CURVATURE_ZERO * |C'| * |C''| (the sine
    # of the angle between the first two derivatives; scale-free).
    "CURVATURE_ZERO": 1e-12,
    # A surface point has no normal when |S_u x S_v| <= NORMAL_ZERO * max(|S_u|, |S_v|)^2
    # (scale-free; at a sphere pole S_u is round-off, so |S_u| |S_v| would not do).
    "NORMAL_ZERO": 1e-12,
    # Default arc-length tolerance, relative to the length of the control polygon ...
    "ARC_LENGTH": 1e-13,
    # ... reached by adaptive 16-point Gauss-Legendre with at most this many halvings.
    "ARC_LENGTH_MAX_LEVELS": 40,
    # Default tolerance of is_umbilic, relative to max(|k1|, |k2|, 1/R), R the size of the net.
    "UMBILIC": 1e-8,
    # ---- construction (course ch. 6) -----------------------------------------------------------
    # A revolution angle may exceed 2 pi by this much (absolute, radians) and still count as a
    # full turn (round-off in a caller's 2 * np.pi arithmetic); larger |angle| is rejected.
    "ANGLE_SLACK": 1e-12,
    # An extrusion vector is zero when its length is at most AXIS_ZERO times the size of the
    # geometry it moves (the largest pole coordinate, at least 1): scale-free.
    "AXIS_ZERO": 1e-12,
    # Largest gap allowed between curves that should meet (Coons corners, Gordon intersections),
    # absolute, in model units (OCC's Precision::Confusion()). Gaps up to it are closed (Coons: the
    # curves' end poles move to the corner's mean; Gordon: the intersection point is the mean);
    # larger ones raise InvalidGeometryError.
    "NETWORK_TOLERANCE": 1e-7,
    # Bicubic Coons corner compatibility: a cross-boundary derivative at a corner must equal the
    # tangent of the adjacent boundary there to this tolerance, relative to the larger of the two
    # vectors' lengths (and 1).
    "DERIVATIVE_TOLERANCE": 1e-7,
    # Default largest distance between a rational curve and the polynomial B-spline that replaces
    # it where an exact homogeneous construction is impossible (absolute, model units).
    "APPROXIMATION_TOLERANCE": 1e-6,
    # Relative agreement demanded of homogeneous corner / intersection weights (Coons, Gordon).
    "HOMOGENEOUS_WEIGHT_RTOL": 1e-12,
    # Gordon closest-point search between two curves: samples per non-empty knot span (at least 16
    # per curve) for the starting guess, then at most GORDON_NEWTON_STEPS Gauss-Newton iterations
    # from each of the GORDON_STARTS closest sample pairs (so that a nearby local minimum of the
    # distance does not hide the intersection).
    "GORDON_SAMPLES_PER_SPAN": 8,
    "GORDON_NEWTON_STEPS": 40,
    "GORDON_STARTS": 8,
    # Default tolerance of sweep, relative to the size of the swept geometry (max(1, largest
    # |coordinate| of the profile and path poles)): the pole bound is driven below
    # SWEEP_TOLERANCE * size.
    "SWEEP_TOLERANCE": 1e-6,
    # Steps of the reference rotation-minimising frame chain per non-empty path span (double
    # reflection has a global error of O(h^4): on a 1.5-turn helix with 9 spans, 128 steps agree
    # with an ODE solution of the RMF transport (DOP853, rtol 1e-13) to 7.8e-12 in the frame
    # vectors, 64 steps to 1.4e-10, 32 to 2.3e-9).
    "SWEEP_RMF_STEPS": 128,
    # Each non-empty path span is first cut in this many v spans.
    "SWEEP_INITIAL_PIECES": 2,
    # Points per v span where the pole bound is checked during refinement.
    "SWEEP_CHECKS_PER_SPAN": 5,
    # v values per v span of the final dense verification (every profile span sampled 8 times).
    "SWEEP_VERIFY_PER_SPAN": 9,
    # Refinement stops with a ToleranceError beyond this many pole rows in v.
    "SWEEP_MAX_SECTIONS": 4000,
    # A span whose error e exceeds tol is cut in ceil(SWEEP_SPLIT_SAFETY (e / tol)^(1/(q+1)))
    # pieces (at least 2, at most SWEEP_MAX_SPLIT): the interpolation error of a smooth function
    # falls like h^(q+1), so one pass usually suffices where plain halving needs several.
    "SWEEP_SPLIT_SAFETY": 1.2,
    "SWEEP_MAX_SPLIT": 16,
    # A path joint (knot of multiplicity >= degree) must be tangent-continuous within this angle
    # (radians) unless frame="fixed": a moving frame turns abruptly at a kink, tearing the sweep.
    "SWEEP_KINK_ANGLE": 1e-9,
    # A path whose ends are this close (relative to its size) and whose end tangents agree within
    # SWEEP_CLOSE_ANGLE (radians) is closed: with frame="rmf" the frame's holonomy is then spread
    # along it so that the swept surface closes too.
    "SWEEP_CLOSE_TOL": 1e-9,
    "SWEEP_CLOSE_ANGLE": 1e-6,
    # Refinement gives up (ToleranceError) rather than cut a span below this fraction of the
    # path's domain: an error that does not fall as spans shrink comes from a jump in a law, a cusp
    # of the path or a frame that turns abruptly, not from too few sections.
    "SWEEP_MIN_SPAN": 1e-9,
    # ---- fitting (course ch. 7) ----------------------------------------------------------------
    # Schoenberg-Whitney margin: a collocation system is refused when some basis function is
    # smaller than this at its own data site (the matrix is then singular or nearly so). Relative
    # to the basis' maximum of 1.
    "SCHOENBERG_WHITNEY": 1e-12,
    # Generalised cross-validation (fit_grid smoothing="gcv") searches log10(lambda) in
    # [FIT_GCV_MIN_LOG10, FIT_GCV_MAX_LOG10] (lambda = 1 weighs data and penalty alike).
    "FIT_GCV_MIN_LOG10": -10.0,
    "FIT_GCV_MAX_LOG10": 3.0,
    # GCV of a grid with missing cells: the influence trace is exact (a multi-right-hand-side
    # solve) while the sparse system has at most FIT_GCV_EXACT_TRACE unknowns, else Hutchinson's
    # estimate with FIT_GCV_PROBES Rademacher probes (standard deviation <= sqrt(2 tr / probes)).
    "FIT_GCV_EXACT_TRACE": 2500,
    "FIT_GCV_PROBES": 40,
    # Smoothing lambda used when a gridded fit has missing (NaN) cells and none is given: keeps the
    # poles without data defined (their second differences are minimised) and changes the fit
    # elsewhere by ~1e-6 relative; scattered fits use FIT_SCATTERED_SMOOTHING the same way.
    "FIT_MISSING_SMOOTHING": 1e-6,
    "FIT_SCATTERED_SMOOTHING": 1e-6,
    # Point projection (measured distances, parameter correction): damped Newton stops once every
    # parameter step is below FIT_PROJECTION_STEP times the domain size, after at most
    # FIT_PROJECTION_MAX_ITER steps.
    "FIT_PROJECTION_STEP": 1e-12,
    "FIT_PROJECTION_MAX_ITER": 30,
    # An adaptive fit evaluates each datum about this many times (candidate bases, the Newton steps
    # of every measurement, backfitting sweeps, level reports; 21 on Franke 200 x 200): from
    # NUMBA_MIN_POINTS / FIT_EVALUATIONS_PER_DATUM data on, the whole fit uses the numba kernels.
    "FIT_EVALUATIONS_PER_DATUM": 10,
    # Gridded distances are measured in blocks of about this many points (the starting partials of
    # a block by tensor-product evaluation; memory O(block), not O(data)).
    "FIT_MEASURE_BLOCK": 262144,
    # Adaptive hierarchical fitting: most overlay levels below the base; the flagged knot spans
    # are grown by FIT_ADAPTIVE_MARGIN spans on each side before overlays are placed (an
    # overlay's outer vertices taper to its border); each round refines where the distance
    # exceeds max(tol, FIT_ADAPTIVE_GREED * the current maximum) (worst places first, so the
    # ringing of a coarse fit around a sharp feature is not refined: backfitting removes it),
    # followed by FIT_ADAPTIVE_SWEEPS backfitting sweeps; at most FIT_ADAPTIVE_MAX_ROUNDS rounds.
    "FIT_ADAPTIVE_MAX_LEVELS": 6,
    "FIT_ADAPTIVE_MARGIN": 0,
    "FIT_ADAPTIVE_GREED": 0.1,
    "FIT_ADAPTIVE_SWEEPS": 2,
    "FIT_ADAPTIVE_MAX_ROUNDS": 20,
    # Before any overlay, the base's spans are multiplied by 1.5 while the regions to refine cover
    # more than this fraction of its domain (error everywhere: uniform refinement is cheaper).
    "FIT_ADAPTIVE_MAX_COVER": 0.5,
    # Overlay displacements are minimum-norm least squares with singular values below
    # FIT_OVERLAY_RCOND times the largest dropped: an overlay vertex whose B-spline reaches the
    # data only with its tail (at the support's edge) is left at zero; inverting its tiny singular
    # value made the surface swing far between the samples (1e4 x the data size measured on a
    # thread face of build123d's screw, with machine-precision cut-off).
    "FIT_OVERLAY_RCOND": 1e-3,
    # Scattered adaptive fitting refines a knot span only when it holds at least this many points
    # (its four halves could not determine finer poles otherwise; a grid's rule is two data rows
    # each way, i.e. at least four points).
    "FIT_ADAPTIVE_SPAN_POINTS": 4,
    # ---- manipulation (course ch. 3, 4) --------------------------------------------------------
    # A pivot |R[k, k]| of the equilibrated constraint matrix below RANK_RTOL * |R[0, 0]| counts as
    # zero: rows beyond it are taken as combinations of the earlier ones.
    "RANK_RTOL": 1e-10,
    # Dependent constraint rows are consistent when their targets match the combination of the
    # independent rows' targets to CONSISTENCY_RTOL times the size of the (equilibrated) targets.
    "CONSISTENCY_RTOL": 1e-9,
    # Stopping tolerance (atol and btol) of the iterative sparse solvers.
    "SPARSE_TOL": 1e-14,
    # Nonlinear constraints (curvature, tangent magnitude) are met when each residual is at most
    # NEWTON_TOL * max(1, |target|) (in the constraint's own units).
    "NEWTON_TOL": 1e-12,
    # Newton-KKT steps allowed in all continuation stages before the SLSQP fallback (and SLSQP's
    # iteration limit, at least 100).
    "DRAG_MAX_ITERATIONS": 60,
    # Newton steps tried per continuation stage before the stage is halved.
    "DRAG_NEWTON_STEPS": 10,
    # Smallest continuation step in t before giving up.
    "MIN_CONTINUATION_STEP": 2.0**-14,
    # A Newton-KKT stage has converged (once feasible) when the reduced gradient of the Lagrangian
    # is below KKT_RTOL * max(|y|, 1) (first-order optimality of the minimum-norm change).
    "KKT_RTOL": 1e-10,
    # Linear constraints (curve and surface edits) must hold after the solve to this relative
    # accuracy, else the system was too ill-conditioned and ConstraintError is raised instead of
    # returning a wrong result.
    "LINEAR_CHECK_RTOL": 1e-9,
    # ---- hierarchical (course ch. 5) -----------------------------------------------------------
    # A normal is degenerate where |S_u x S_v| <= FRAME_DEGENERACY (|S_u|^2 + |S_v|^2): ~6 digits
    # above round-off in the cross product, far below any real surface's tangent angle.
    "FRAME_DEGENERACY": 1e-10,
    # Relative step (of the domain size) towards the domain centre at which a degenerate frame is
    # re-evaluated. The frame found there approximates the limit frame to O(FRAME_NUDGE).
    "FRAME_NUDGE": 1e-6,
    # HierarchicalSurface.drag_point stops once the point is this close to the target, relative to
    # max(1, |target|): the linear solve is exact to ~1e-14, and with frame offsets each further
    # iteration only corrects the turn of finer details ...
    "EDIT_POINT_RTOL": 1e-11,
    # ... after at most this many linearised solves (14 measured for details of 0.1 on a unit
    # patch, residual factor 0.16 per step; 40 leave room for a factor of ~0.5).
    "EDIT_POINT_MAX_ITER": 40,
    # ---- topology (course ch. 8) ---------------------------------------------------------------
    # How far (relative to the circumradius 1) a domain point may lie outside the regular n-gon
    # and still be accepted (round-off in callers' arithmetic); the Wachspress coordinates are
    # smooth across the sides, so such points evaluate to the analytic continuation.
    "SPATCH_DOMAIN_SLACK": 1e-10,
    # Largest number of sides of an S-patch. Beyond it the Wachspress denominator (degree n - 3)
    # and the number of control points grow without practical use; the course stops at 8.
    "SPATCH_MAX_SIDES": 64,
    # Highest derivative order SPatch.derivatives computes: its Taylor-mode jets cost about order**6
    # per point (measured 0.43 s at order 20, 2.3 s at 25 for a 5-sided depth-3 patch), so order 99
    # would run for hours; a request above it is refused at once.
    "SPATCH_MAX_DERIVATIVE_ORDER": 24,
    # S-patch conversion: default maximum deviation of an approximated piece, relative to the
    # diagonal of the patch's control-point bounding box (tol= overrides it with an absolute value),
    # with B-spline pieces of degree SPATCH_APPROX_DEGREE of at most SPATCH_APPROX_MAX_POLES poles
    # per direction (else ToleranceError) where the exact bidegree exceeds MAX_DEGREE.
    "SPATCH_APPROX_TOL": 1e-7,
    "SPATCH_APPROX_DEGREE": 5,
    "SPATCH_APPROX_MAX_POLES": 80,
    # Relative tolerance (to the largest homogeneous coefficient) within which the degree
    # reduction of the 4-sided pieces (exact in theory) must reproduce the coefficients on
    # re-elevation (round-off measured: ~1e-15); otherwise the pieces are kept at bidegree 2d.
    "SPATCH_REDUCTION_TOL": 1e-13,
    # Parameter samples per direction and piece at which a conversion's deviation is measured.
    "SPATCH_CHECK_SAMPLES": 41,
    # Largest vertex valence of a generalized B-spline mesh: the S-patch of a valence-n vertex has
    # C(n + 4, 5) control points (15 504 at n = 16), all evaluated at every point.
    "MAX_VALENCE": 16,
    # Relative disagreement (to the size of the vertex's Bézier net) allowed between the two
    # computations of a generalized-surface control point fixed by two sides; round-off gives
    # ~1e-15, larger means a bug, and raises.
    "GENERALIZED_CONSISTENCY_TOL": 1e-9,
    # n-sided fill: the interior fairing systems of the central split's patches with at most this
    # many free poles keep their factors (least recently used, 16 systems: a hole's patches share
    # one layout). A 1024-unknown system's coupling block and factors take ~2.1 MB (3600: 12 MB),
    # so the cache stays under ~35 MB.
    "FILL_FAIR_CACHE_FREE": 1024,
    # Larger systems are kept for one hole only (:class:`~.topology.nsided_patches.FairSystems`: the
    # central split's two layouts share its patches' knots and free poles, so their factors), up to
    # this many factor entries in all: SuperLU's factors took 10-21 bytes an entry on linkrods'
    # patches (a 100 344-unknown system: 23.4 million entries, 260 MB), so ~400 MB at most.
    "FILL_FAIR_KEEP_NNZ": 32_000_000,
    # Relative singular-value cut-off of the small least-squares solves (anything out of the
    # fields' plane, a corner incompatibility, is dropped, not amplified) ...
    "FILL_RCOND": 1e-9,
    # ... and the fraction of the largest singular value below which one counts as zero in the kite
    # domain relation.
    "FILL_NULL_RTOL": 1e-10,
    # Largest gap (relative to the size of the loop's bounding box) between the end of one side and
    # the start of the next for a hole's loop to count as closed.
    "FILL_CLOSURE_TOL": 1e-6,
    # Smallest angle (degrees) between the two sides at a hole corner, and between a side's tangent
    # and its neighbour's cross derivative; below it the corner/side is degenerate and refused.
    "FILL_MIN_CORNER_ANGLE": 2.0,
    # At a hole corner the tangent planes of the two neighbours must agree (sine of the angle by
    # which one neighbour's boundary tangent leaves the other's tangent plane); above this the
    # neighbours meet at a sharp edge and no surface is G1 to both, so the hole is refused.
    "FILL_CORNER_PLANE_TOL": 0.02,
    # Self-check of the exact representations (relative to the function's size): a spline or
    # polynomial placed into a knot space that holds it must come back to round-off.
    "FILL_REPRESENT_TOL": 1e-9,
    # Twist mismatch (relative, see HoleFill.twist_mismatch) above which a corner is treated as
    # incompatible: its twist pole is averaged and confined to a corner span of parameter length
    # FILL_CORNER_SPAN (the G1 error left near the corner is proportional to it).
    "FILL_TWIST_TOL": 1e-8,
    "FILL_CORNER_SPAN": 0.02,
    # Largest corner-twist coefficient (the ribbon coefficients' derivatives at a hole corner) relative
    # to the coefficients themselves; beyond it (a wiggly fitted cross field) the coefficients ramp
    # linearly to the side's midpoint instead and the unmet twist is reported as a mismatch.
    "FILL_MAX_TWIST_RATIO": 20.0,
    # Most sides of a hole (the construction works for any n: 48 sides measured G1 to 5e-10 deg in
    # 6 s; this bounds the output size, n patches, and the time).
    "FILL_MAX_SIDES": 96,
    # An interior knot of a side within this (relative to the side's parameter range) of an end of
    # the side, or of the half side a corner patch covers, is that end: no sliver span is made.
    "FILL_KNOT_END_TOL": 1e-12,
    # A side's cross field must have the curve's domain within this (absolute and relative).
    "FILL_DOMAIN_TOL": 1e-12,
    # A rational side whose end weights differ from 1 by more than this is rescaled (times a linear
    # factor: the same curve) to end weights 1 in working coordinates; closer, it is left as it is.
    "FILL_END_WEIGHT_TOL": 1e-15,
    # A cut of a loop of one or two sides (on [0, 1]) within this of a knot is moved onto the knot:
    # a sliver span left by the cut would make the fill's knot spaces singular.
    "FILL_CUT_SNAP": 1e-6,
    # A knot of low continuity within this of a side's middle (parameter, on [0, 1]) is at the
    # middle: the internal edge then leaves the side half a span away instead.
    "FILL_SPLIT_KNOT_TOL": 1e-9,
    # Smallest angle (degrees) between an internal edge and its side at the side's midpoint: where
    # the centre lies (nearly) along the side (a tapering sliver of a hole), the edge leaves the side
    # at this angle and turns towards the centre on its way (its Hermite curve), instead of leaving
    # the hole.
    "FILL_MIN_EDGE_ANGLE": 30.0,
    # Self-check of an internal edge's G1 data (relative to its cross fields' size): the second
    # cross field must meet its end data when the corner conditions hold; round-off gives ~1e-15,
    # larger means a bug, and raises.
    "FILL_EDGE_CONSISTENCY_TOL": 1e-7,
    # measure_fill: a normal S_u x S_v no longer than this times |S_u| |S_v| (the sine of the angle
    # between the partials) is degenerate (the corner of a flat hole corner's patch); the limit normal
    # is then taken FILL_NORMAL_STEP of the domain into the patch.
    "FILL_DEGENERATE_NORMAL": 1e-9,
    "FILL_NORMAL_STEP": 1e-7,
    # count_folds: a grid normal shorter than this times the median normal's length is degenerate
    # (a flat hole corner) and counts on neither side of a fold.
    "FILL_FOLD_DEGENERATE": 1e-6,
    # Trimmed hole sides (topology/nsided_sides.py): target angle (degrees) between the fitted
    # cross field's tangent plane and the neighbour's, the 0.01 deg; the fit bisects spans
    # until it is met or the field has FILL_FIT_MAX_SPANS spans.
    "FILL_FIT_ANGLE": 0.01,
    "FILL_FIT_MAX_SPANS": 256,
    # Largest distance (relative to the model's size) of a fitted boundary where edges meeting at a
    # flat corner are merged into one side (the G0 <= 1e-7 of the model size).
    "FILL_FIT_G0": 1e-7,
    # Target relative jump of the normal curvature across a side where a fill is asked to be
    # curvature continuous (G2): CATIA's G2 ratio |k1 - k2| / max(|k1|, |k2|), issue 31's 1 %.
    "FILL_FIT_G2_REL": 0.01,
    # Fraction of a side over which the neighbour's normal is turned into the fill's corner plane
    # where the two neighbours of a corner do not share a tangent plane (G1 is lost only there).
    "FILL_CORNER_BLEND": 0.1,
    # Fraction of the G0 target (FILL_FIT_G0 * size) by which a G0-only hole side may move near a
    # corner where it meets a G1 side, to turn its end tangent into the G1 neighbour's tangent plane
    # (nsided_sides.turn_end_tangent): with the tangent left as it was, no surface through both
    # sides is closer to that neighbour at the corner than the tangent's angle out of its plane.
    "FILL_CORNER_TURN_G0": 0.5,
    # Plate fill (topology/plate_fill.py): largest angle (degrees) between a G1 side's neighbour
    # normal and the reference plane's normal; beyond it the height field's slope is too steep to fit
    # (at 90 the neighbour stands vertical, beyond it turns back over the hole).
    "FILL_PLATE_MAX_TILT": 80.0,
    # ... weight of the thin-plate energy relative to the data term's trace (the data rows are in
    # units of the targets): it decides what no boundary sample reaches (the inside). Its bias on the
    # data is taken off by up to FILL_PLATE_ITERATIONS steps of iterated Tikhonov regularisation,
    # stopped by the samples between the fit's (a basis function that only grazes the loop would
    # otherwise blow up: 13 mm off on a 19 mm screw's sliver hole with 1e-9 and 64 spans).
    # 1e-7: sliver 3.4e-6 at 62 x 30 spans (1e-9: 3.0e-5); sphere hole (R 2, h 0.3) met at 8 x 6.
    "FILL_PLATE_SMOOTHING": 1e-7,
    "FILL_PLATE_ITERATIONS": 6,
    # ... most knot spans per direction of the plate (bisected where samples miss the targets).
    "FILL_PLATE_MAX_SPANS": 128,
    # Refill of a model's hole (occsurf.bridge.modeling.refill_*). Along a hole edge the neighbour is
    # sampled at uniform parameters plus FILL_EDGE_END_SAMPLES clustered at each end, at fractions
    # of the edge's range from FILL_EDGE_END_NEAREST to FILL_EDGE_END_FARTHEST (geometric) ...
    "FILL_EDGE_END_SAMPLES": 8,
    "FILL_EDGE_END_NEAREST": 1e-4,
    "FILL_EDGE_END_FARTHEST": 5e-2,
    # ... where |S_u x S_v| is at most this times |S_u| |S_v| (the sine of the angle between the
    # partials: a pole) the normal is OCC's limit normal (GeomLProp_SLProps at this resolution) ...
    "FILL_EDGE_NORMAL_DEGENERATE": 1e-12,
    "FILL_EDGE_NORMAL_RESOLUTION": 1e-9,
    # ... and an edge with fewer samples of a defined normal is refused.
    "FILL_EDGE_MIN_NORMALS": 8,
    # Samples along an edge at which the angle between its two faces is taken (refill_loop.joint_angle).
    "FILL_JOINT_SAMPLES": 9,
    # Which side of a face a 3-D direction points to: a step of this length in the face's (u, v)
    # along it, classified with BRepClass_FaceClassifier at FILL_SIDE_CLASSIFY_TOL; on the face's
    # boundary, up to FILL_SIDE_STEP_TRIES steps, each FILL_SIDE_STEP_GROWTH times the one before.
    "FILL_SIDE_STEP": 1e-4,
    "FILL_SIDE_STEP_GROWTH": 10,
    "FILL_SIDE_STEP_TRIES": 3,
    "FILL_SIDE_CLASSIFY_TOL": 1e-9,
    # A neighbour's trace drops points closer than this (relative to the polyline's length) to the
    # one before: the chord-length parameters of the side's fit must increase.
    "FILL_TRACE_REPEAT": 1e-12,
    # Two traces' end tangents are parallel (a flat joint inside a side, not a corner) when the
    # square of the sine of their angle is at most this (refill_traces._corner_point).
    "FILL_TRACE_PARALLEL": 1e-6,
    # A side's fit short of samples asks for this many times as many per round (refill_traces.follow_traces).
    "FILL_TRACE_RESAMPLE_FACTOR": 4,
    # A side is closed (a round hole: its samples at the seam are put on the right end) when its
    # ends meet within this, relative to its largest control point coordinate (at least 1).
    "FILL_SEAM_TOL": 1e-9,
    # ... a sample in the first half of the edge that lies in the last FILL_SEAM_WINDOW of the side's
    # domain belongs at its start, and conversely.
    "FILL_SEAM_WINDOW": 0.25,
    # Edges merged into one side that cannot be joined exactly are fitted through samples of each:
    # TRACE_SAMPLES_PER_POLE per pole, at least this many ...
    "FILL_MERGE_MIN_SAMPLES": 121,
    # ... they are joined exactly (one B-spline) when consecutive ones meet within this fraction of
    # the G0 target; each piece's arc length, which sets its parameter interval, from this many samples.
    "FILL_JOIN_GAP": 1e-3,
    "FILL_JOIN_LENGTH_SAMPLES": 257,
    # A side of uneven speed (refill_sides._even_speed): its speed sampled at least this many times,
    # and FILL_SPEED_SAMPLES_PER_SPAN per knot span; its arc length by Gauss-Legendre with this many
    # points between samples; a stretch adding less than FILL_SPEED_ZERO of the length adds no sample.
    "FILL_SPEED_SAMPLES": 1024,
    "FILL_SPEED_SAMPLES_PER_SPAN": 16,
    "FILL_SPEED_GAUSS_POINTS": 5,
    "FILL_SPEED_ZERO": 1e-14,
    # A side's normal at a hole corner more than this many degrees out of the corner's plane is
    # turned into it (refill_sides._corner_treatment).
    "FILL_CORNER_NORMAL_DEG": 1e-6,
    # Tolerance of the OCC faces made of the central split's patches (make_face).
    "FILL_PATCH_FACE_TOL": 1e-7,
    # The plates' G0 target is FILL_FIT_G0 * size, but at most this fraction of the sewing tolerance
    # (the face must sew in; plate_face refuses beyond SEW_TOLERANCE).
    "FILL_PLATE_SEW_SHARE": 0.5,
    # A filled model that sews in invalid is sewn again at half the tolerance, up to this many times
    # (never below the fill's own G0).
    "FILL_RESEW_HALVINGS": 6,
    # ---- quality (course ch. 9, 11-2) ----------------------------------------------------------
    # A point is flat (curvature_map kind "radius" is inf) when max(|k1|, |k2|) * size is at most
    # this; size is the diagonal of the sampled points' bounding box (scale-free).
    "QUALITY_FLAT_CURVATURE": 1e-9,
    # Default minimum draft angle of classify_draft, degrees (a common moulding minimum).
    "QUALITY_MIN_DRAFT_DEG": 1.0,
    # Inflections of a comb are located to this fraction of the curve's parameter range (bracketed
    # root finding on the signed curvature).
    "QUALITY_INFLECTION_TOL": 1e-12,
    # Section points are refined by Newton onto the exact surface-plane intersection until their
    # distance to the plane is at most this times the model size ...
    "QUALITY_SECTION_TOL": 1e-10,
    # ... in at most this many steps (points that do not converge are dropped and counted).
    "QUALITY_SECTION_NEWTON_STEPS": 30,
    # Seed grid of a section: at least this many cells per parameter direction of a face, and at
    # least QUALITY_SECTION_CELLS_PER_SPAN per non-empty knot span.
    "QUALITY_SECTION_GRID": 48,
    "QUALITY_SECTION_CELLS_PER_SPAN": 6,
    # ... but at most this many (faces with hundreds of knot spans).
    "QUALITY_SECTION_MAX_CELLS": 256,
    # Section polylines of neighbouring faces whose ends lie within this distance (relative to the
    # model size) are joined into one chain.
    "QUALITY_CHAIN_TOL": 1e-6,
    # face_flags. A sign change of the mean curvature counts as a wiggle only where |H| * size
    # exceeds this on both sides (smaller is round-off on a flat or developable face).
    "QUALITY_WIGGLE_CURVATURE": 1e-3,
    # Flat spot: max(|k1|, |k2|) below this fraction of the face's median on a face that is curved
    # (median max|k| * size above QUALITY_WIGGLE_CURVATURE) ...
    "QUALITY_FLAT_SPOT_RATIO": 0.02,
    # ... covering at least this fraction of the samples (a single crossing point is not a spot).
    "QUALITY_FLAT_SPOT_AREA": 0.005,
    # Curvature spike: a local maximum of |k1| + |k2| above this multiple of the median of its
    # neighbourhood (a square window QUALITY_SPIKE_WINDOW of the grid's side wide) and above 1/size.
    "QUALITY_SPIKE_RATIO": 10.0,
    "QUALITY_SPIKE_WINDOW": 0.25,
    # Next to a degenerate point, a spike candidate's neighbourhood is a true cone (whose curvature
    # grows as 1 / distance to the apex: geometry, not a spike) when every tangent plane passes
    # through the apex: |n . (X - apex)| at most this times |X - apex| (the sine of the angle).
    "QUALITY_CONE_APEX_TOL": 1e-6,
    # Near-degenerate normal: |S_u x S_v| / max(|S_u|, |S_v|)^2 (the sine of the angle between the
    # partials) below this, but above NORMAL_ZERO.
    "QUALITY_NEAR_DEGENERATE": 1e-3,
    # Ill-parametrisation: ratio of the largest to the smallest |S_u x S_v| (the Jacobian) over a
    # face's non-degenerate samples above this.
    "QUALITY_JACOBIAN_RATIO": 100.0,
    # Edge continuity (occsurf.bridge.quality.continuity). Dense samples per edge (Chebyshev-Lobatto
    # points of its parameter range, made odd so that the middle is one), before the search ...
    "CONTINUITY_SAMPLES": 33,
    # ... and golden-section iterations of the worst-point search per measure (the bracket of two
    # sample spacings shrinks by 0.618 each).
    "CONTINUITY_REFINE_ITERATIONS": 6,
    # Default matching tolerance of loose faces' edges, relative to the model's bounding-box
    # diagonal: 1e-4 of a 100 mm part is 0.01 mm, ten times CATIA's G0 default and far above IGES's
    # 10-digit round-off, while distinct edges of a 0.1 mm wall stay apart.
    "CONTINUITY_MATCH_RTOL": 1e-4,
    # Curvatures below this times 1 / model size count as zero for the relative G2 jump (a radius
    # a million times the model): between two almost flat faces the ratio is noise.
    "CONTINUITY_CURVATURE_FLOOR": 1e-6,
    # ---- matching (manipulation/matching.py, match_solve.py; course ch. 4) -----------------------
    # Default G0 tolerance of match_surface, relative to the size of the pair (bounding-box diagonal
    # of both nets): 1e-5 mm on a 100 mm part, a hundred times below CATIA's 0.001 mm default.
    "MATCH_G0_RTOL": 1e-7,
    # Refinement rounds of match_surface (each inserts the target's knots, then the midpoints of the
    # spans that still miss a tolerance) and the most poles along the side it may reach.
    "MATCH_MAX_ROUNDS": 8,
    "MATCH_MAX_POLES": 400,
    # Gauss-Newton steps that move a G2 / G3 match from the row-by-row solution to the joint
    # minimum-norm change (measured: 4-5 steps to 1e-12 of the size on 20 x 20 nets).
    "MATCH_MAX_ITERATIONS": 10,
    # Relative singular-value cut-off below which the minimum-norm solve of a match treats a
    # direction as noise (rows normalised) when the exact solution (cut-off 1e-12) would be more than
    # twice as long: the G1 conditions n . S_u = 0 are homogeneous in the second row's offset, and
    # data consistent only to interpolation error (a MatchTarget's normals, 1e-8) add singular values
    # of that size whose direction is the collapse S_u = 0.
    "MATCH_RCOND": 1e-6,
    # ---- lighting (course ch. 10, Warn 1983) ---------------------------------------------------
    # A light's direction (or a normal given to shade) shorter than this cannot be made a unit
    # vector: the direction is refused, the normal's point is shaded NaN. Absolute: directions are
    # unitless.
    "LIGHT_DIRECTION_ZERO": 1e-12,
    # The light's frame takes its x axis from the model's +x projected onto the plane normal to
    # the light's direction; where the sine of the angle between +x and the direction is below
    # this, +x is (nearly) parallel to it and +y is projected instead.
    "LIGHT_FRAME_DEGENERATE": 1e-6,
    # Most lights in one setup (the renderer's fragment shader has uniforms for each).
    "LIGHT_MAX_COUNT": 16,
    # shade() works on blocks of this many points (the temporaries of a block stay in cache) ...
    "LIGHT_BLOCK": 16384,
    # ... on this many threads at once (0: one per CPU; 1: serial). Results do not depend on it.
    "LIGHT_THREADS": 0,
}

# BEGIN typed names (generated from _DEFAULTS; tests/algorithms/test_tolerances_typed.py checks them)
# Each name is read through the module __getattr__ below (the current context's value); these
# annotations, with no value, only tell type checkers and IDEs that the name exists and its type.
KNOT_EQUALITY: float
PARAMETER: float
KNOT_REMOVAL: float
MAX_ARRAY_BYTES: int
NUMBA_MIN_POINTS: int
TRIM_POLYLINE: float
TRIM_POLYLINE_LEVELS: int
TRIM_ON: float
TRIM_LOOP_GAP: float
TRIM_AREA_RTOL: float
TRIM_AREA_LEVELS: int
TRIM_AREA_SINGULAR: float
WEIGHT_SUM: float
MAX_CONDITION: float
CURVATURE_ZERO: float
NORMAL_ZERO: float
ARC_LENGTH: float
ARC_LENGTH_MAX_LEVELS: int
UMBILIC: float
ANGLE_SLACK: float
AXIS_ZERO: float
NETWORK_TOLERANCE: float
DERIVATIVE_TOLERANCE: float
APPROXIMATION_TOLERANCE: float
HOMOGENEOUS_WEIGHT_RTOL: float
GORDON_SAMPLES_PER_SPAN: int
GORDON_NEWTON_STEPS: int
GORDON_STARTS: int
SWEEP_TOLERANCE: float
SWEEP_RMF_STEPS: int
SWEEP_INITIAL_PIECES: int
SWEEP_CHECKS_PER_SPAN: int
SWEEP_VERIFY_PER_SPAN: int
SWEEP_MAX_SECTIONS: int
SWEEP_SPLIT_SAFETY: float
SWEEP_MAX_SPLIT: int
SWEEP_KINK_ANGLE: float
SWEEP_CLOSE_TOL: float
SWEEP_CLOSE_ANGLE: float
SWEEP_MIN_SPAN: float
SCHOENBERG_WHITNEY: float
FIT_GCV_MIN_LOG10: float
FIT_GCV_MAX_LOG10: float
FIT_GCV_EXACT_TRACE: int
FIT_GCV_PROBES: int
FIT_MISSING_SMOOTHING: float
FIT_SCATTERED_SMOOTHING: float
FIT_PROJECTION_STEP: float
FIT_PROJECTION_MAX_ITER: int
FIT_EVALUATIONS_PER_DATUM: int
FIT_MEASURE_BLOCK: int
FIT_ADAPTIVE_MAX_LEVELS: int
FIT_ADAPTIVE_MARGIN: int
FIT_ADAPTIVE_GREED: float
FIT_ADAPTIVE_SWEEPS: int
FIT_ADAPTIVE_MAX_ROUNDS: int
FIT_ADAPTIVE_MAX_COVER: float
FIT_OVERLAY_RCOND: float
FIT_ADAPTIVE_SPAN_POINTS: int
RANK_RTOL: float
CONSISTENCY_RTOL: float
SPARSE_TOL: float
NEWTON_TOL: float
DRAG_MAX_ITERATIONS: int
DRAG_NEWTON_STEPS: int
MIN_CONTINUATION_STEP: float
KKT_RTOL: float
LINEAR_CHECK_RTOL: float
FRAME_DEGENERACY: float
FRAME_NUDGE: float
EDIT_POINT_RTOL: float
EDIT_POINT_MAX_ITER: int
SPATCH_DOMAIN_SLACK: float
SPATCH_MAX_SIDES: int
SPATCH_MAX_DERIVATIVE_ORDER: int
SPATCH_APPROX_TOL: float
SPATCH_APPROX_DEGREE: int
SPATCH_APPROX_MAX_POLES: int
SPATCH_REDUCTION_TOL: float
SPATCH_CHECK_SAMPLES: int
MAX_VALENCE: int
GENERALIZED_CONSISTENCY_TOL: float
FILL_FAIR_CACHE_FREE: int
FILL_FAIR_KEEP_NNZ: int
FILL_RCOND: float
FILL_NULL_RTOL: float
FILL_CLOSURE_TOL: float
FILL_MIN_CORNER_ANGLE: float
FILL_CORNER_PLANE_TOL: float
FILL_REPRESENT_TOL: float
FILL_TWIST_TOL: float
FILL_CORNER_SPAN: float
FILL_MAX_TWIST_RATIO: float
FILL_MAX_SIDES: int
FILL_KNOT_END_TOL: float
FILL_DOMAIN_TOL: float
FILL_END_WEIGHT_TOL: float
FILL_CUT_SNAP: float
FILL_SPLIT_KNOT_TOL: float
FILL_MIN_EDGE_ANGLE: float
FILL_EDGE_CONSISTENCY_TOL: float
FILL_DEGENERATE_NORMAL: float
FILL_NORMAL_STEP: float
FILL_FOLD_DEGENERATE: float
FILL_FIT_ANGLE: float
FILL_FIT_MAX_SPANS: int
FILL_FIT_G0: float
FILL_FIT_G2_REL: float
FILL_CORNER_BLEND: float
FILL_CORNER_TURN_G0: float
FILL_PLATE_MAX_TILT: float
FILL_PLATE_SMOOTHING: float
FILL_PLATE_ITERATIONS: int
FILL_PLATE_MAX_SPANS: int
FILL_EDGE_END_SAMPLES: int
FILL_EDGE_END_NEAREST: float
FILL_EDGE_END_FARTHEST: float
FILL_EDGE_NORMAL_DEGENERATE: float
FILL_EDGE_NORMAL_RESOLUTION: float
FILL_EDGE_MIN_NORMALS: int
FILL_JOINT_SAMPLES: int
FILL_SIDE_STEP: float
FILL_SIDE_STEP_GROWTH: int
FILL_SIDE_STEP_TRIES: int
FILL_SIDE_CLASSIFY_TOL: float
FILL_TRACE_REPEAT: float
FILL_TRACE_PARALLEL: float
FILL_TRACE_RESAMPLE_FACTOR: int
FILL_SEAM_TOL: float
FILL_SEAM_WINDOW: float
FILL_MERGE_MIN_SAMPLES: int
FILL_JOIN_GAP: float
FILL_JOIN_LENGTH_SAMPLES: int
FILL_SPEED_SAMPLES: int
FILL_SPEED_SAMPLES_PER_SPAN: int
FILL_SPEED_GAUSS_POINTS: int
FILL_SPEED_ZERO: float
FILL_CORNER_NORMAL_DEG: float
FILL_PATCH_FACE_TOL: float
FILL_PLATE_SEW_SHARE: float
FILL_RESEW_HALVINGS: int
QUALITY_FLAT_CURVATURE: float
QUALITY_MIN_DRAFT_DEG: float
QUALITY_INFLECTION_TOL: float
QUALITY_SECTION_TOL: float
QUALITY_SECTION_NEWTON_STEPS: int
QUALITY_SECTION_GRID: int
QUALITY_SECTION_CELLS_PER_SPAN: int
QUALITY_SECTION_MAX_CELLS: int
QUALITY_CHAIN_TOL: float
QUALITY_WIGGLE_CURVATURE: float
QUALITY_FLAT_SPOT_RATIO: float
QUALITY_FLAT_SPOT_AREA: float
QUALITY_SPIKE_RATIO: float
QUALITY_SPIKE_WINDOW: float
QUALITY_CONE_APEX_TOL: float
QUALITY_NEAR_DEGENERATE: float
QUALITY_JACOBIAN_RATIO: float
CONTINUITY_SAMPLES: int
CONTINUITY_REFINE_ITERATIONS: int
CONTINUITY_MATCH_RTOL: float
CONTINUITY_CURVATURE_FLOOR: float
MATCH_G0_RTOL: float
MATCH_MAX_ROUNDS: int
MATCH_MAX_POLES: int
MATCH_MAX_ITERATIONS: int
MATCH_RCOND: float
LIGHT_DIRECTION_ZERO: float
LIGHT_FRAME_DEGENERATE: float
LIGHT_MAX_COUNT: int
LIGHT_BLOCK: int
LIGHT_THREADS: int
# END typed names

_OVERRIDES: contextvars.ContextVar[Mapping[str, float]] = contextvars.ContextVar(
    "occsurf_tolerances", default=MappingProxyType({}))


def get(name: str) -> float:
    """The value of tolerance ``name`` in the current context (an override, else the default).

    Raises
    ------
    KeyError
        If ``name`` is not a tolerance of this module.
    """
    try:
        default = _DEFAULTS[name]
    except KeyError:
        raise KeyError(f"tolerances: {name!r} is not a tolerance; known: {', '.join(sorted(_DEFAULTS))}") from None
    return _OVERRIDES.get().get(name, default)


def __getattr__(name: str) -> float:
    # Module attribute access (``tolerances.KNOT_EQUALITY``) reads the current context's value.
    if name in _DEFAULTS:
        return _OVERRIDES.get().get(name, _DEFAULTS[name])
    raise AttributeError(f"module 'occsurf.algorithms.tolerances' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *_DEFAULTS])


def defaults() -> dict[str, float]:
    """Every overridable tolerance with its default value (a copy)."""
    return dict(_DEFAULTS)


@contextlib.contextmanager
def override(**values: float) -> Iterator[None]:
    """Replace tolerances for the ``with`` block, in this thread or task only.

    Parameters
    ----------
    **values : float
        New values keyed by name, e.g. ``override(KNOT_REMOVAL=1e-6)``. Integer limits (iteration
        counts, sizes) keep integer values. ``MAX_DEGREE`` is a kernel limit and cannot be changed.

    Raises
    ------
    UnknownNameError
        If a name is not an overridable tolerance of this module (also a ``KeyError``).
    ArgumentTypeError
        If a value is not a real number, or an integer limit gets a non-integer (also a ``TypeError``).
    InvalidGeometryError
        If a value is NaN or infinite (a NaN tolerance disables every comparison made with it), or
        negative (every entry is a magnitude: a tolerance, an angle, a count; 0 is accepted, e.g.
        "no Newton step" or "exact only").
    """
    from .errors import ArgumentTypeError, InvalidGeometryError, UnknownNameError

    for name, value in values.items():
        if name not in _DEFAULTS:
            raise UnknownNameError(f"override: {name!r} is not a tolerance; known: {', '.join(sorted(_DEFAULTS))}")
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ArgumentTypeError(f"override: {name} must be a real number, got {value!r}")
        if not math.isfinite(value):
            raise InvalidGeometryError(f"override: {name} must be finite, got {value!r}")
        if value < 0:
            raise InvalidGeometryError(f"override: {name} must not be negative, got {value!r}")
        if isinstance(_DEFAULTS[name], int) and not float(value).is_integer():
            raise ArgumentTypeError(f"override: {name} is an integer limit, got {value!r}")

    typed = {k: type(_DEFAULTS[k])(v) for k, v in values.items()}
    token = _OVERRIDES.set(MappingProxyType({**_OVERRIDES.get(), **typed}))
    try:
        yield
    finally:
        _OVERRIDES.reset(token)
