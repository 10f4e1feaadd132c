"""Warn's lighting model (course ch. 10): closed forms, invariants, validation, the lights file."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from occsurf.algorithms import tolerances
from occsurf.algorithms.errors import ExchangeError, InvalidGeometryError
from occsurf.algorithms.lighting import (
    PRESETS,
    LightingSetup,
    Material,
    WarnLight,
    dump_lights,
    dumps_lights,
    highlight_check,
    key_light_with_flaps,
    light_factor,
    light_frame,
    load_lights,
    loads_lights,
    preset,
    setup_from_dict,
    shade,
    studio_three_point,
)

from .strategies import test_settings

SETTINGS = test_settings(30)
MATTE = Material(color=(1.0, 1.0, 1.0), diffuse=1.0, specular=0.0)
coord = st.floats(-10, 10, allow_nan=False)
vec = st.tuples(coord, coord, coord)


def _plane(n: int = 41, half: float = 5.0) -> tuple[np.ndarray, np.ndarray]:
    """Points of the plane z = 0 on a grid, and their normals (+z)."""
    x, y = np.meshgrid(np.linspace(-half, half, n), np.linspace(-half, half, n), indexing="ij")
    P = np.stack([x, y, np.zeros_like(x)], axis=-1)
    return P, np.broadcast_to([0.0, 0.0, 1.0], P.shape)


# ---------------------------------------------------------------------------------------- closed forms
def test_plain_point_light_is_lambert_plus_phong() -> None:
    """n = 0, no cone, no flaps: the textbook point light, written out independently."""
    rng = np.random.default_rng(1)
    P = rng.normal(size=(500, 3))
    N = rng.normal(size=(500, 3))
    E = np.array([3.0, -4.0, 5.0])
    light = WarnLight(position=(2.0, 1.0, 6.0), direction=(0, 0, -1), color=(1.0, 0.5, 0.25), intensity=0.8)
    mat = Material(color=(0.6, 0.7, 0.8), diffuse=0.9, specular=0.4, shininess=13.0)
    got = shade(P, N, E, [light], mat, two_sided=False)
    n = N / np.linalg.norm(N, axis=1, keepdims=True)
    L = np.asarray(light.position) - P
    L /= np.linalg.norm(L, axis=1, keepdims=True)
    V = E - P
    V /= np.linalg.norm(V, axis=1, keepdims=True)
    NL = np.sum(n * L, axis=1)
    R = 2 * NL[:, None] * n - L
    spec = np.where(NL > 0, np.maximum(np.sum(R * V, axis=1), 0) ** 13.0, 0)
    want = light.rgb * (0.9 * np.asarray(mat.color) * np.maximum(NL, 0)[:, None] + 0.4 * spec[:, None])
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-14)


def test_concentration_zero_and_one() -> None:
    """n = 0 reproduces the plain light exactly (the factor is 1 everywhere, even behind the light);
    n = 1 is the plain light times cos(gamma) (a Lambertian reflector), 0 behind it."""
    P, N = _plane()
    pos, d = np.array([1.0, -2.0, 4.0]), np.array([0.3, 0.2, -1.0])
    plain = WarnLight(position=tuple(pos), direction=(0, 0, 1))  # points away: irrelevant for n = 0
    n0 = WarnLight(position=tuple(pos), direction=tuple(d), concentration=0)
    n1 = WarnLight(position=tuple(pos), direction=tuple(d), concentration=1)
    E = [0.0, 0.0, 10.0]
    base = shade(P, N, E, [plain], MATTE)
    np.testing.assert_array_equal(shade(P, N, E, [n0], MATTE), base)
    ray = P - pos
    cos_g = ray @ (d / np.linalg.norm(d)) / np.linalg.norm(ray, axis=-1)
    np.testing.assert_allclose(shade(P, N, E, [n1], MATTE), base * np.maximum(cos_g, 0)[..., None], atol=1e-14)


def test_concentration_is_cos_power() -> None:
    pos = np.array([0.0, 0.0, 5.0])
    light = WarnLight(position=tuple(pos), direction=(0, 0, -1), concentration=7.5)
    P, _ = _plane(21)
    ray = P - pos
    cos_g = -ray[..., 2] / np.linalg.norm(ray, axis=-1)
    np.testing.assert_allclose(light_factor(P, light), cos_g ** 7.5, rtol=1e-12)


def test_pixels_outside_a_flap_are_ambient_only() -> None:
    P, N = _plane(81)
    light = WarnLight(position=(0.0, 0.0, 10.0), direction=(0, 0, -1), flaps={"x": [-1.0, 2.0], "y": [-3.0, None]})
    setup = LightingSetup(lights=(light,), ambient=0.07, material=MATTE)
    rgb = shade(P, N, [0.0, 0.0, 20.0], setup)
    F = light.frame  # straight down: x = +x, y = z x x = -y
    q = (P - np.array([0.0, 0.0, 10.0])) @ F.T
    inside = (q[..., 0] >= -1) & (q[..., 0] <= 2) & (q[..., 1] >= -3)
    assert inside.any() and (~inside).any()
    np.testing.assert_array_equal(rgb[~inside], 0.07)
    assert np.all(rgb[inside] > 0.07 + 0.05)


def test_soft_flap_edge_is_a_smoothstep_inside_the_flap() -> None:
    light = WarnLight(position=(0.0, 0.0, 10.0), direction=(0, 0, -1), flaps={"x": [-1.0, 2.0]}, flap_edge=0.5)
    x = np.linspace(-2, 3, 501)
    P = np.stack([x, np.zeros_like(x), np.zeros_like(x)], axis=-1)
    t_lo = np.clip((x + 1.0) / 0.5, 0, 1)
    t_hi = np.clip((2.0 - x) / 0.5, 0, 1)
    want = t_lo * t_lo * (3 - 2 * t_lo) * t_hi * t_hi * (3 - 2 * t_hi)
    np.testing.assert_allclose(light_factor(P, light), want, atol=1e-12)
    assert np.all(light_factor(P, light)[(x < -1) | (x > 2)] == 0)  # still nothing outside the flaps
    doc = json.loads(dumps_lights(LightingSetup(lights=(light,))))
    assert doc["lights"][0]["flaps"]["edge"] == 0.5
    assert loads_lights(json.dumps(doc)).lights[0] == light
    with pytest.raises(InvalidGeometryError, match=r"lights\[0\]\.flaps\.edge"):
        loads_lights('{"lights": [{"direction": [0, 0, 1], "flaps": {"x": [0, 1], "edge": -1}}]}')


def test_flap_frame_convention() -> None:
    """x = the model's +x projected; +y where the direction is along x; y = z x x."""
    F = light_frame([0.0, 0.0, -2.0])
    np.testing.assert_allclose(F, [[1, 0, 0], [0, -1, 0], [0, 0, -1]], atol=1e-15)
    F = light_frame([3.0, 0.0, 0.0])
    np.testing.assert_allclose(F, [[0, 1, 0], [0, 0, 1], [1, 0, 0]], atol=1e-15)
    d = np.array([1.0, 2.0, -2.0]) / 3
    F = light_frame(d)
    np.testing.assert_allclose(F @ F.T, np.eye(3), atol=1e-14)
    np.testing.assert_allclose(np.cross(F[0], F[1]), d, atol=1e-14)
    # +x projected: F[0] is parallel to x - (x.d) d
    p = np.array([1.0, 0, 0]) - d[0] * d
    np.testing.assert_allclose(F[0], p / np.linalg.norm(p), atol=1e-14)


def test_degenerate_frame_threshold_is_a_tolerance() -> None:
    d = np.array([1.0, 0.0, 1e-5])  # +x at a sine of 1e-5 from the direction
    np.testing.assert_allclose(light_frame(d)[0], [0.0, 0.0, -1.0], atol=1e-4)  # +x projected
    with tolerances.override(LIGHT_FRAME_DEGENERATE=1e-4):
        F = light_frame(d)
    np.testing.assert_allclose(F[0], [0.0, 1.0, 0.0], atol=1e-9)  # now degenerate: +y projected


def test_cone_edge_falls_off_as_smoothstep() -> None:
    """Full light to angle - edge, none from the angle on, 3t^2 - 2t^3 in the angle between."""
    light = WarnLight(position=(0.0, 0.0, 0.0), direction=(0, 0, 1), cone_angle_deg=30, cone_edge_deg=6)
    gam = np.radians(np.linspace(0, 40, 401))
    P = np.stack([np.sin(gam), np.zeros_like(gam), np.cos(gam)], axis=-1) * 3.0
    t = np.clip((np.radians(30) - gam) / np.radians(6), 0, 1)
    np.testing.assert_allclose(light_factor(P, light), t * t * (3 - 2 * t), atol=1e-12)
    g = np.degrees(gam)
    assert np.all(light_factor(P, light)[g <= 24 - 1e-9] == 1) and np.all(light_factor(P, light)[g >= 30] == 0)
    hard = WarnLight(position=(0.0, 0.0, 0.0), direction=(0, 0, 1), cone_angle_deg=30)
    away = np.abs(g - 30) > 1e-6  # exactly on the edge: either side, by round-off
    np.testing.assert_array_equal(light_factor(P, hard)[away], (g[away] < 30).astype(float))


def test_falloff_laws() -> None:
    P = np.array([[0.0, 0.0, -r] for r in (0.5, 2.0, 4.0, 8.0)])
    for law, k in (("inverse", 1), ("inverse_square", 2)):
        light = WarnLight(position=(0.0, 0.0, 0.0), direction=(0, 0, -1), falloff=law, falloff_distance=2.0)
        np.testing.assert_allclose(light_factor(P, light), [1.0, 1.0, 0.5 ** k, 0.25 ** k], rtol=1e-14)


@SETTINGS
@given(pos1=vec, pos2=vec, c1=st.tuples(*[st.floats(0, 1)] * 3), c2=st.tuples(*[st.floats(0, 1)] * 3),
       n1=st.floats(0, 20), cone=st.floats(5, 90))
def test_two_lights_equal_the_sum_of_each_alone(pos1, pos2, c1, c2, n1, cone) -> None:
    """Light-source colour blending (§10-7) is additive per channel."""
    P, N = _plane(15)
    a = WarnLight(position=pos1, direction=(0.1, 0.2, -1), color=c1, concentration=n1, flaps={"x": [-2, 3]})
    b = WarnLight(position=pos2, direction=(-0.3, 0.1, -1), color=c2, cone_angle_deg=cone, cone_edge_deg=cone / 4)
    E = [1.0, 2.0, 12.0]
    both = shade(P, N, E, LightingSetup(lights=(a, b), ambient=0.0))
    np.testing.assert_allclose(both, shade(P, N, E, [a]) + shade(P, N, E, [b]), rtol=1e-12, atol=1e-15)


def test_coloured_lights_blend_per_channel() -> None:
    red = WarnLight(position=(-5.0, 0.0, 5.0), direction=(1, 0, -1), color=(1, 0, 0))
    blue = WarnLight(position=(5.0, 0.0, 5.0), direction=(-1, 0, -1), color=(0, 0, 1))
    P, N = _plane(11)
    rgb = shade(P, N, [0, 0, 10], [red, blue], MATTE)
    np.testing.assert_array_equal(rgb[..., 1], 0.0)
    np.testing.assert_allclose(rgb[..., 0], shade(P, N, [0, 0, 10], [red], MATTE)[..., 0], rtol=1e-14)


def test_two_sided_and_degenerate_normals() -> None:
    light = WarnLight(position=(0.0, 0.0, 5.0), direction=(0, 0, -1))
    P = np.zeros((3, 3))
    N = np.array([[0, 0, -1.0], [0, 0, 2.0], [0, 0, 0.0]])
    two = shade(P, N, [0, 0, 3], [light], MATTE)
    assert np.allclose(two[0], two[1]) and np.all(np.isnan(two[2]))
    one = shade(P, N, [0, 0, 3], [light], MATTE, two_sided=False, ambient=0.1)
    np.testing.assert_allclose(one[0], 0.1)


def test_directional_light() -> None:
    light = WarnLight(position=None, direction=(0, 0, -1), flaps={"x": [0, None]})
    P, N = _plane(11)
    rgb = shade(P, N, [0, 0, 10], [light], MATTE)
    np.testing.assert_allclose(rgb[P[..., 0] >= 0], 1.0)
    np.testing.assert_array_equal(rgb[P[..., 0] < 0], 0.0)
    with pytest.raises(InvalidGeometryError, match="position"):
        WarnLight(position=None, direction=(0, 0, -1), concentration=2)


def test_shapes_broadcast_and_blocks_agree() -> None:
    rng = np.random.default_rng(3)
    P = rng.normal(size=(4, 5, 3))
    N = rng.normal(size=(4, 5, 3))
    setup = studio_three_point([0, 0, 0], 3.0)
    full = shade(P, N, [0, -9, 2], setup)
    assert full.shape == (4, 5, 3)
    with tolerances.override(LIGHT_BLOCK=7):
        np.testing.assert_array_equal(shade(P, N, [0, -9, 2], setup), full)
    per_point_eye = shade(P, N, np.broadcast_to([0, -9, 2], P.shape), setup)
    np.testing.assert_allclose(per_point_eye, full, rtol=1e-14)


@pytest.mark.slow
def test_threads_and_float32() -> None:
    """Blocks on threads give the serial result bit for bit; float32 agrees to ~1e-6."""
    rng = np.random.default_rng(4)
    P = rng.normal(size=(50_000, 3)) * 3
    N = rng.normal(size=(50_000, 3))
    setup = key_light_with_flaps([0, 0, 0], 6.0)
    with tolerances.override(LIGHT_BLOCK=1000, LIGHT_THREADS=4):
        threaded = shade(P, N, [1, -8, 5], setup)
    with tolerances.override(LIGHT_BLOCK=1000, LIGHT_THREADS=1):
        serial = shade(P, N, [1, -8, 5], setup)
    np.testing.assert_array_equal(threaded, serial)
    f32 = shade(P, N, [1, -8, 5], setup, dtype=np.float32)
    assert f32.dtype == np.float32
    # a flap edge may fall either side in float32: compare away from the light's discontinuities
    F = setup.lights[0].frame
    q = (P - setup.lights[0].origin) @ F.T
    edge = np.zeros(len(P), bool)
    for k, (lo, hi) in enumerate(setup.lights[0].flaps):
        for b_ in (lo, hi):
            if np.isfinite(b_):
                edge |= np.abs(q[:, k] - b_) < 1e-4 * 6
    np.testing.assert_allclose(f32[~edge], serial[~edge], rtol=0, atol=2e-5)
    with pytest.raises(InvalidGeometryError, match="dtype"):
        shade(P[:2], N[:2], [0, 0, 1], setup, dtype=np.int32)


# ---------------------------------------------------------------------------------------- validation
@pytest.mark.parametrize("kwargs, field", [
    ({"concentration": -1}, "light.concentration"),
    ({"flaps": {"x": [2, 1]}}, "light.flaps.x"),
    ({"flaps": {"w": [0, 1]}}, "light.flaps"),
    ({"cone_angle_deg": 0}, "light.cone.angle_deg"),
    ({"cone_angle_deg": 95}, "light.cone.angle_deg"),
    ({"cone_angle_deg": 20, "cone_edge_deg": 25}, "light.cone.edge_deg"),
    ({"direction": (0, 0, 0)}, "light.direction"),
    ({"direction": (0, 0)}, "light.direction"),
    ({"color": (1, -0.1, 0)}, "light.color"),
    ({"intensity": float("nan")}, "light.intensity"),
    ({"falloff": "cubic"}, "light.falloff"),
    ({"falloff": "inverse"}, "light.falloff_distance"),
])
def test_light_errors_name_the_field(kwargs, field) -> None:
    args = {"position": (0.0, 0.0, 1.0), "direction": (0, 0, -1), **kwargs}
    with pytest.raises(InvalidGeometryError, match=field.replace(".", r"\.")):
        WarnLight(**args)


def test_setup_and_material_errors() -> None:
    with pytest.raises(InvalidGeometryError, match="material.shininess"):
        Material(shininess=-1)
    with pytest.raises(InvalidGeometryError, match="material.color"):
        Material(color=(1.5, 0, 0))
    with pytest.raises(InvalidGeometryError, match="ambient"):
        LightingSetup(ambient=-0.1)
    with pytest.raises(InvalidGeometryError, match=r"lights\[0\]"):
        LightingSetup(lights=("key",))
    with pytest.raises(InvalidGeometryError, match="at most 2"), tolerances.override(LIGHT_MAX_COUNT=2):
        LightingSetup(lights=(WarnLight(position=None, direction=(0, 0, 1)),) * 3)
    with pytest.raises(InvalidGeometryError, match="points"):
        shade(np.zeros((3, 2)), np.zeros((3, 3)), [0, 0, 1], [])
    with pytest.raises(InvalidGeometryError, match="points"):
        shade([[np.nan, 0, 0]], [[0, 0, 1]], [0, 0, 1], [])
    light = WarnLight(position=(0.0, 0.0, 1.0), direction=(0, 0, -1))
    with pytest.raises(dataclasses.FrozenInstanceError):
        light.intensity = 2.0  # type: ignore[misc]  # frozen


# ---------------------------------------------------------------------------------------- file & presets
def test_issue_example_loads() -> None:
    doc = {"ambient": 0.05, "lights": [{"position": [1, 2, 3], "direction": [0, 0, -1], "color": [1, 1, 1],
                                        "intensity": 1.0, "concentration": 0, "cone": {"angle_deg": 30, "edge_deg": 2},
                                        "flaps": {"x": [-1, 1], "y": [-2, 2], "z": [0, 10]}}]}
    setup = setup_from_dict(doc)
    light = setup.lights[0]
    assert light.cone_angle_deg == 30 and light.cone_edge_deg == 2 and light.flaps[2] == (0.0, 10.0)
    assert setup.ambient == (0.05, 0.05, 0.05)


@pytest.mark.parametrize("text, field", [
    ('{"lights": [{"position": [0,0,1], "direction": [0,0,-1], "cone": {"angle_deg": 120}}]}',
     r"lights\[0\]\.cone\.angle_deg"),
    ('{"lights": [{"position": [0,0,1]}]}', r"lights\[0\]\.direction: missing"),
    ('{"lights": [{}, {"direction": [0,0,1], "concentration": -2}]}', r"lights\[0\]\.direction"),
    ('{"lights": [{"direction": [0,0,1]}, {"position": [0,0,1], "direction": [0,0,1], "concentration": -2}]}',
     r"lights\[1\]\.concentration"),
    ('{"lights": [{"direction": [0,0,1], "flaps": {"y": [3, 1]}}]}', r"lights\[0\]\.flaps\.y"),
    ('{"lights": [{"direction": [0,0,1], "colour": [1,0,0]}]}', r"lights\[0\]\.colour: unknown key"),
    ('{"ambient": "dim"}', "ambient"),
    ('{"material": {"shininess": -3}}', r"material\.shininess"),
    ('{"lights": [{"direction": [0,0,1]},]}', "not valid JSON"),
    ('[1, 2]', "lights file: expected a JSON object"),
])
def test_lights_file_errors_name_the_field(text, field) -> None:
    with pytest.raises(InvalidGeometryError, match=field):
        loads_lights(text)


@pytest.mark.parametrize("name", sorted(PRESETS))
def test_presets_round_trip_through_json(tmp_path, name) -> None:
    setup = preset(name, [10.0, -3.0, 2.0], 250.0)
    path = dump_lights(setup, tmp_path / "lights.json")
    assert load_lights(path) == setup
    assert json.loads(dumps_lights(setup))["lights"]
    P, N = _plane(9, 50.0)
    rgb = shade(P + [10.0, -3.0, 2.0], N, [10, -3, 500], setup)
    assert np.all(np.isfinite(rgb)) and rgb.max() > 0.1


def test_presets_scale_with_the_model() -> None:
    small, big = studio_three_point([0, 0, 0], 1.0), studio_three_point([0, 0, 0], 1000.0)
    np.testing.assert_allclose(np.asarray(big.lights[0].position), 1000 * np.asarray(small.lights[0].position))
    key = key_light_with_flaps([0, 0, 0], 10.0).lights[0]
    assert key.has_flaps and key.concentration > 1
    assert len(highlight_check([0, 0, 0], 1.0, count=7).lights) == 7
    with pytest.raises(InvalidGeometryError, match="size"):
        studio_three_point([0, 0, 0], 0.0)
    with pytest.raises(InvalidGeometryError, match="preset"):
        preset("noir", [0, 0, 0], 1.0)


def test_unreadable_lights_file(tmp_path) -> None:
    with pytest.raises(ExchangeError, match="cannot read"):
        load_lights(tmp_path / "missing.json")


def test_key_light_band_is_where_the_flaps_say() -> None:
    """The car-body preset lights a band, not the whole plane (flaps at work)."""
    setup = key_light_with_flaps([0, 0, 0], 10.0)
    P, N = _plane(101, 10.0)
    lit = light_factor(P, setup.lights[0]) > 0
    assert 0.02 < lit.mean() < 0.6
    assert math.isclose(float(np.linalg.norm(setup.lights[0].direction)), 1.0)


# ---------------------------------------------------------------------------------------- concentration, counted from 1
def test_concentration_ratio_one_reproduces_a_plain_light() -> None:
    """The issue's wording: concentration 1 reproduces a plain light - with the concentration counted
    as C = n + 1 (WarnLight.concentration_ratio); Warn's exponent n = 0 is the same light."""
    P, N = _plane()
    pos, d = (1.0, -2.0, 4.0), (0.3, 0.2, -1.0)
    E = [0.0, 0.0, 10.0]
    plain = shade(P, N, E, [WarnLight(position=pos, direction=(0, 0, 1))], MATTE)
    c1 = WarnLight.with_concentration_ratio(1, position=pos, direction=d)
    assert c1.concentration == 0 and c1.concentration_ratio == 1
    np.testing.assert_array_equal(shade(P, N, E, [c1], MATTE), plain)
    np.testing.assert_array_equal(light_factor(P - [0.0, 0.0, 9.0], c1), 1.0)  # behind the light too
    doc = {"lights": [{"position": list(pos), "direction": list(d), "concentration_ratio": 1}]}
    assert setup_from_dict(doc).lights[0] == c1
    # C = n + 1 for every n: C = 2 is Warn's n = 1 (cos), C = 41 his n = 40
    for ratio in (2.0, 3.5, 41.0):
        a = WarnLight.with_concentration_ratio(ratio, position=pos, direction=d)
        b = WarnLight(position=pos, direction=d, concentration=ratio - 1)
        assert a == b and a.concentration_ratio == ratio
        doc["lights"][0]["concentration_ratio"] = ratio
        assert setup_from_dict(doc).lights[0] == b
    # written back with Warn's exponent
    assert json.loads(dumps_lights(setup_from_dict(doc)))["lights"][0]["concentration"] == 40.0


@pytest.mark.parametrize("n", [0.0, 1.0, 7.5, 40.0])
def test_concentration_ratio_is_peak_over_mean_intensity(n) -> None:
    """The meaning documented for C: the intensity on the axis over the mean intensity across the
    directions the light reaches (the whole sphere for n = 0, the half-space in front for n > 0),
    integrated numerically over a fine grid of directions."""
    light = WarnLight(position=(0.0, 0.0, 0.0), direction=(0, 0, 1), concentration=n)
    k = 4000
    gamma = (np.arange(k) + 0.5) * np.pi / k  # midpoint rule in the polar angle from the axis
    dirs = np.stack([np.sin(gamma), np.zeros(k), np.cos(gamma)], axis=-1)
    intensity = light_factor(dirs, light)
    solid = np.sin(gamma)  # the solid angle of each ring (axisymmetric), up to a common factor
    lit = intensity > 0
    mean = np.sum(intensity * solid) / np.sum(solid[lit])
    assert math.isclose(intensity[0] / mean, light.concentration_ratio, rel_tol=1e-4)


def test_concentration_ratio_errors_name_the_field() -> None:
    with pytest.raises(InvalidGeometryError, match=r"light\.concentration_ratio: expected 1 <= "):
        WarnLight.with_concentration_ratio(0.5, position=(0.0, 0.0, 1.0), direction=(0, 0, -1))
    with pytest.raises(InvalidGeometryError, match=r"light\.concentration_ratio: give either"):
        WarnLight.with_concentration_ratio(2, position=(0.0, 0.0, 1.0), direction=(0, 0, -1), concentration=1)
    with pytest.raises(InvalidGeometryError, match=r"light\.concentration_ratio: expected a finite number"):
        WarnLight.with_concentration_ratio("high", position=(0.0, 0.0, 1.0), direction=(0, 0, -1))
    for text, field in [
        ('{"lights": [{"position": [0,0,1], "direction": [0,0,-1], "concentration_ratio": 0}]}',
         r"lights\[0\]\.concentration_ratio: expected 1 <="),
        ('{"lights": [{"position": [0,0,1], "direction": [0,0,-1], "concentration_ratio": 2, "concentration": 1}]}',
         r"lights\[0\]\.concentration_ratio: give either"),
        ('{"lights": [{"direction": [0,0,-1], "concentration_ratio": 3}]}', r"lights\[0\]\.position"),
    ]:
        with pytest.raises(InvalidGeometryError, match=field):
            loads_lights(text)
    # a directional light may give C = 1 (n = 0): nothing to measure an angle from is needed
    assert loads_lights('{"lights": [{"direction": [0,0,-1], "concentration_ratio": 1}]}').lights[0].concentration == 0


# ---------------------------------------------------------------------------------------- compiled kernel
try:
    import numba  # noqa: F401

    HAVE_NUMBA = True
except ImportError:
    HAVE_NUMBA = False

needs_numba = pytest.mark.skipif(not HAVE_NUMBA, reason="numba is not installed (optional)")
kernel_must_run = pytest.mark.filterwarnings("error:occsurf. numba lighting kernel failed:RuntimeWarning")


def _every_control(seed: int) -> LightingSetup:
    """Lights using every control: concentration (integer and not), hard and soft cones, hard and
    soft flaps, both fall-offs, a directional light with flaps, a coloured light."""
    rng = np.random.default_rng(seed)
    lights = [
        WarnLight(position=tuple(rng.uniform(-3, 3, 2)) + (6.0,), direction=(0.1, 0.2, -1), concentration=3.0,
                  cone_angle_deg=35, cone_edge_deg=9, flaps={"x": [-2.5, 3.0], "y": [-4.0, None]}),
        WarnLight(position=(-3.0, 2.0, 5.0), direction=(0.5, -0.2, -1.0), color=(0.5, 0.4, 0.1), concentration=2.7,
                  flaps={"x": [-1.0, 1.0], "z": [0.0, 7.0]}, flap_edge=0.6, falloff="inverse_square",
                  falloff_distance=4.0),
        WarnLight(position=(2.0, -2.0, 3.0), direction=(-0.2, 0.3, -1.0), cone_angle_deg=25, falloff="inverse",
                  falloff_distance=2.0),
        WarnLight(position=None, direction=(0.3, 0.2, -1.0), color=(0.1, 0.2, 0.6), flaps={"y": [-1.0, 2.0]},
                  flap_edge=float(rng.uniform(0, 0.5))),
    ]
    mat = Material(color=(0.8, 0.7, 0.6), diffuse=0.8, specular=0.3, shininess=float(rng.choice([20.0, 13.5, 0.0, 1.0])))
    return LightingSetup(lights=tuple(lights), ambient=(0.05, 0.06, 0.04), material=mat, two_sided=bool(seed % 2))


def _points(seed: int, m: int = 20_000) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(100 + seed)
    P = rng.uniform(-5, 5, (m, 3)) * [1, 1, 0.4]
    N = rng.normal(size=(m, 3))
    N[:50] = 0.0  # degenerate normals: NaN rows
    P[50] = (-3.0, 2.0, 5.0)  # a point at a light: no light from it
    return P, N


@pytest.mark.slow
@needs_numba
@kernel_must_run
@pytest.mark.parametrize("seed", range(6))
def test_compiled_kernel_matches_the_numpy_reference(seed, monkeypatch) -> None:
    """Both paths on every control, degenerate normals and a point at a light: the same numbers
    to 1e-13 (the kernel repeats the reference's operations; pow and acos may differ in an ulp)."""
    monkeypatch.delenv("OCCSURF_NO_NUMBA", raising=False)  # the compiled path, whatever the environment
    setup = _every_control(seed)
    P, N = _points(seed)
    E = [1.0, -8.0, 12.0] if seed < 3 else P + [0.5, -3.0, 9.0]  # one eye, or one per point
    with tolerances.override(NUMBA_MIN_POINTS=0):
        fast = shade(P, N, E, setup)
    monkeypatch.setenv("OCCSURF_NO_NUMBA", "1")
    ref = shade(P, N, E, setup)
    assert np.array_equal(np.isnan(fast), np.isnan(ref)) and np.isnan(ref[:50]).all()
    np.testing.assert_allclose(fast, ref, rtol=1e-13, atol=1e-15)
    assert np.all(fast[51:] > 0)  # a picture, not zeros


@needs_numba
@kernel_must_run
def test_compiled_kernel_is_bit_identical_on_integer_exponents(monkeypatch) -> None:
    """Integer exponents, hard cones and flaps use no transcendental function besides sqrt: the two
    paths give the same bits (the kernel repeats the reference's operations in its order)."""
    monkeypatch.delenv("OCCSURF_NO_NUMBA", raising=False)  # the compiled path, whatever the environment
    light = WarnLight(position=(0.5, -1.0, 6.0), direction=(0.0, 0.2, -1.0), concentration=3.0, cone_angle_deg=32,
                      flaps={"x": [-2.5, 3.0]}, flap_edge=0.3, falloff="inverse", falloff_distance=3.0)
    setup = studio_three_point([0, 0, 0], 8.0).replace(lights=(light, *studio_three_point([0, 0, 0], 8.0).lights))
    P, N = _points(7)
    with tolerances.override(NUMBA_MIN_POINTS=0):
        fast = shade(P, N, [1, -9, 4], setup)
    monkeypatch.setenv("OCCSURF_NO_NUMBA", "1")
    np.testing.assert_array_equal(fast, shade(P, N, [1, -9, 4], setup))


@pytest.mark.slow
@needs_numba
@kernel_must_run
def test_compiled_kernel_threads_blocks_float32_and_threshold(monkeypatch) -> None:
    """Any block size and thread count give the same bits; float32 output is the float64 result
    rounded; below NUMBA_MIN_POINTS (read at call time) the NumPy path runs."""
    monkeypatch.delenv("OCCSURF_NO_NUMBA", raising=False)  # the compiled path, whatever the environment
    from occsurf.algorithms.lighting import _kernels

    setup = _every_control(1)
    P, N = _points(1, 9_999)
    with tolerances.override(NUMBA_MIN_POINTS=0, LIGHT_THREADS=1, LIGHT_BLOCK=100_000):
        serial = shade(P, N, [1, -8, 12], setup)
    with tolerances.override(NUMBA_MIN_POINTS=0, LIGHT_THREADS=3, LIGHT_BLOCK=777):
        np.testing.assert_array_equal(shade(P, N, [1, -8, 12], setup), serial)
        f32 = shade(P, N, [1, -8, 12], setup, dtype=np.float32)
    assert f32.dtype == np.float32
    np.testing.assert_array_equal(f32, serial.astype(np.float32))
    calls = []
    real = _kernels.run
    monkeypatch.setattr(_kernels, "run", lambda *a: calls.append(1) or real(*a))
    with tolerances.override(NUMBA_MIN_POINTS=len(P) + 1):
        shade(P, N, [1, -8, 12], setup)
    assert calls == []
    with tolerances.override(NUMBA_MIN_POINTS=len(P)):
        shade(P, N, [1, -8, 12], setup)
    assert calls


@needs_numba
def test_a_failing_kernel_falls_back_to_numpy(monkeypatch) -> None:
    from occsurf.algorithms.lighting import _kernels

    setup = _every_control(2)
    P, N = _points(2, 2000)
    monkeypatch.setenv("OCCSURF_NO_NUMBA", "1")
    ref = shade(P, N, [1, -8, 12], setup)
    monkeypatch.delenv("OCCSURF_NO_NUMBA")

    def broken(*args):
        raise TypeError("no matching signature")

    monkeypatch.setitem(_kernels._state, "kernel", broken)
    monkeypatch.setitem(_kernels._state, "loaded", True)
    with tolerances.override(NUMBA_MIN_POINTS=0), pytest.warns(RuntimeWarning, match="lighting kernel failed"):
        got = shade(P, N, [1, -8, 12], setup)
    np.testing.assert_array_equal(got, ref)
    assert _kernels._state["kernel"] is None
