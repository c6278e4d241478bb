"""Model.trace against independent float64 numpy references (reference_np): Moller-Trumbore
brute force on closed meshes, and the first crossing of the numpy w with 1/2 sampled along rays
that pass through the open cube's hole (the smooth cap)."""

import math
import re

import numpy as np
import pytest

import gwnrt
import reference_np as ref


def mesh64(model):
    return model.vertices.astype(np.float64), model.faces


def rays_at(v, count, seed):
    """Rays from a sphere around the mesh (twice its radius) toward jittered vertices, with
    directions of random length (t is in units of the direction)."""
    rng = np.random.default_rng(seed)
    centre = v.mean(axis=0)
    radius = np.linalg.norm(v - centre, axis=1).max()
    dirs = rng.normal(size=(count, 3))
    origins = centre + 2 * radius * dirs / np.linalg.norm(dirs, axis=1, keepdims=True)
    targets = v[rng.integers(0, len(v), count)] + rng.normal(size=(count, 3)) * 0.3 * radius
    return origins, (targets - origins) * rng.uniform(0.5, 2.0, (count, 1))


def edge_margin(v, f, origins, directions, t, tri):
    """The smallest barycentric of each hit on its triangle (how far from an edge it is)."""
    hit = np.isfinite(t)
    margin = np.full(len(t), np.inf)
    p = origins[hit] + t[hit, None] * directions[hit]
    a, b, c = (v[f[tri[hit], i]] for i in range(3))
    n = np.cross(b - a, c - a)
    area = np.einsum("ij,ij->i", n, n)
    u = np.einsum("ij,ij->i", np.cross(c - p, a - p), n) / area
    w = np.einsum("ij,ij->i", np.cross(a - p, b - p), n) / area
    margin[hit] = np.minimum(np.minimum(u, w), 1 - u - w)
    return margin


@pytest.fixture(scope="module", params=["tetrahedron", "octahedron", "cube", "bunny"])
def closed_model(request):
    model = request.getfixturevalue(request.param)
    return model if isinstance(model, gwnrt.Model) else gwnrt.Model(model)


def test_trace_closed_mesh_vs_moller_trumbore(closed_model):
    v, f = mesh64(closed_model)
    origins, directions = rays_at(v, 300, 1)
    t_ref, tri_ref = ref.ray_mesh_hits(v, f, origins, directions)
    # Rays that graze an edge (within 1e-5 in barycentrics) could go either way in float32.
    keep = edge_margin(v, f, origins, directions, t_ref, tri_ref) > 1e-5
    origins, directions, t_ref, tri_ref = origins[keep], directions[keep], t_ref[keep], tri_ref[keep]
    r = closed_model.trace(origins, directions)
    hit_ref = np.isfinite(t_ref)
    assert 0.2 * len(t_ref) < hit_ref.sum() < 0.8 * len(t_ref)  # both hits and misses
    np.testing.assert_array_equal(r.hit, hit_ref)
    # The hit distance along the ray: float32 ray-triangle intersection, 1e-6 of the box diagonal
    # (measured 2e-7; the Harnack stopping distance epsilon = 1e-5 of it does not apply to sheets).
    length = np.linalg.norm(directions, axis=1)
    diag = ref.box_diagonal(v)
    np.testing.assert_allclose((r.t * length)[hit_ref], (t_ref * length)[hit_ref], rtol=0, atol=1e-6 * diag)
    assert (r.kind[hit_ref] == gwnrt.HIT_SHEET).all()
    np.testing.assert_array_equal(r.triangle[hit_ref], tri_ref[hit_ref])
    np.testing.assert_allclose(r.position[hit_ref], (origins + t_ref[:, None] * directions)[hit_ref],
                               atol=2e-6 * diag)
    # Unit outward normals: the hit triangle's geometric normal.
    n = np.cross(v[f[tri_ref[hit_ref], 1]] - v[f[tri_ref[hit_ref], 0]],
                 v[f[tri_ref[hit_ref], 2]] - v[f[tri_ref[hit_ref], 0]])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    np.testing.assert_allclose(np.linalg.norm(r.normal[hit_ref], axis=1), 1.0, atol=1e-6)
    np.testing.assert_allclose(r.normal[hit_ref], n, atol=1e-5)
    # Misses: no hit, t = inf, no triangle.
    miss = ~hit_ref
    assert np.isposinf(r.t[miss]).all()
    assert (r.kind[miss] == gwnrt.HIT_NONE).all() and (r.triangle[miss] == -1).all()
    assert not r.invalid.any() and not r.capped.any()


def test_trace_exact_mode_agrees(closed_model):
    v, f = mesh64(closed_model)
    origins, directions = rays_at(v, 100, 2)
    a = closed_model.trace(origins, directions)
    b = closed_model.trace(origins, directions, exact=True)
    np.testing.assert_array_equal(a.hit, b.hit)
    np.testing.assert_allclose(a.t[a.hit], b.t[b.hit], rtol=1e-5)


@pytest.fixture(scope="module")
def open_cube_model(open_cube):
    return gwnrt.Model(open_cube)


def hole_rays(count, seed):
    """Unit rays from above the open cube down through its hole (z = 1, |x|, |y| < 1)."""
    rng = np.random.default_rng(seed)
    origins = np.column_stack([rng.uniform(-0.6, 0.6, (count, 2)), np.full(count, 3.0)])
    targets = np.column_stack([rng.uniform(-0.7, 0.7, (count, 2)), np.ones(count)])
    d = targets - origins
    return origins, d / np.linalg.norm(d, axis=1, keepdims=True)


def test_trace_through_the_hole_hits_the_smooth_cap(open_cube_model):
    v, f = mesh64(open_cube_model)
    origins, directions = hole_rays(16, 3)
    r = open_cube_model.trace(origins, directions)
    # The mesh alone would be hit only at the bottom, inside the cube: S caps the hole first.
    t_mesh, _ = ref.ray_mesh_hits(v, f, origins, directions)
    assert r.hit.all() and (r.kind == gwnrt.HIT_SMOOTH).all() and (r.triangle == -1).all()
    assert (r.t < t_mesh - 0.5).all()
    epsilon = 1e-5
    diag = ref.box_diagonal(v)
    # On S: the numpy w at the hit is 1/2. The tracer stops within epsilon * diagonal (3.5e-5) of
    # S, where |grad w| < 1: 1e-3 leaves room (measured 1.6e-5).
    np.testing.assert_allclose(ref.winding_number(v, f, r.position), 0.5, atol=1e-3)
    # The trace against sampling: the first crossing of the numpy w with 1/2 along each ray (no
    # triangle lies before it, so w is continuous there). Within 20 epsilon * diagonal of t
    # (unit directions; the Harnack steps stop short of S by up to epsilon * diagonal over the
    # cosine of the ray's angle to S's normal; measured 2.7e-5).
    for i in range(len(origins)):
        t_cross = ref.first_level_crossing(v, f, origins[i], directions[i], 0.999 * t_mesh[i], samples=300)
        assert t_cross is not None
        assert abs(r.t[i] - t_cross) <= 20 * epsilon * diag, (i, r.t[i], t_cross)
    # Unit normals pointing out of {w > 1/2}: along -grad w.
    np.testing.assert_allclose(np.linalg.norm(r.normal, axis=1), 1.0, atol=1e-6)
    g = ref.gradient_fd(v, f, r.position.astype(np.float64))
    g /= np.linalg.norm(g, axis=1, keepdims=True)
    assert (np.einsum("ij,ij->i", r.normal, -g) > 0.999).all()


def test_trace_hole_centre_crosses_at_the_rim_plane(open_cube_model):
    # By symmetry the open box subtends exactly half the sphere from the hole's centre: w = 1/2 at
    # (0, 0, 1), so the vertical ray through it meets S there.
    v, f = mesh64(open_cube_model)
    assert ref.winding_number(v, f, [[0.0, 0.0, 1.0]])[0] == pytest.approx(0.5, abs=1e-12)
    r = open_cube_model.trace([0.0, 0.0, 3.0], [0.0, 0.0, -1.0])
    assert r.hit[0] and r.kind[0] == gwnrt.HIT_SMOOTH
    assert r.t[0] == pytest.approx(2.0, abs=20 * 1e-5 * ref.box_diagonal(v))


def test_trace_open_cube_walls_are_sheets(open_cube_model):
    # Rays from the side toward the lower half of the cube meet a wall, which S runs along.
    v, f = mesh64(open_cube_model)
    rng = np.random.default_rng(4)
    k = 40
    angle = rng.uniform(0, 2 * np.pi, k)
    origins = np.column_stack([3 * np.cos(angle), 3 * np.sin(angle), rng.uniform(-0.8, 0.0, k)])
    targets = np.column_stack([rng.uniform(-0.5, 0.5, (k, 2)), rng.uniform(-0.8, 0.0, k)])
    directions = targets - origins
    t_ref, tri_ref = ref.ray_mesh_hits(v, f, origins, directions)
    r = open_cube_model.trace(origins, directions)
    assert np.isfinite(t_ref).all() and r.hit.all() and (r.kind == gwnrt.HIT_SHEET).all()
    np.testing.assert_allclose(r.t, t_ref, rtol=1e-6, atol=1e-6)
    np.testing.assert_array_equal(r.triangle, tri_ref)


def test_trace_ray_arguments(open_cube_model):
    # From the centre up: S's cap at z = 1 (t = 1 for a unit direction).
    up = [0.0, 0.0, 1.0]
    r = open_cube_model.trace([[0.0, 0.0, 0.0]] * 3, up, tnear=[0.0, 0.0, 2.0],
                              tfar=[math.inf, 0.5, math.inf])
    assert r.hit.tolist() == [True, False, False]
    assert r.t[0] == pytest.approx(1.0, abs=1e-3) and np.isposinf(r.t[1:]).all()
    # One origin for many directions, and a scalar tfar.
    r = open_cube_model.trace([0.0, 0.0, 0.0], np.array([up, [0.0, 0.0, 2.0]]), tfar=10.0)
    assert r.hit.all() and r.t[1] == pytest.approx(r.t[0] / 2, rel=1e-3)
    # Rays the programs refuse in a ray file are refused here too, by index (they were traced as
    # misses): a zero, NaN or infinite direction, a NaN origin, tnear not finite or above tfar.
    o3, up3 = [[0.0, 0.0, 0.0]] * 3, [up] * 3
    for origins, directions, near, far, why in (
            (o3, [up, [0.0, 0.0, 0.0], up], 0.0, math.inf, "ray 1: direction is zero"),
            (o3, [up, up, [0.0, np.nan, 1.0]], 0.0, math.inf, "ray 2: direction has a non-finite coordinate"),
            (o3, [up, [np.inf, 0.0, 0.0], up], 0.0, math.inf, "ray 1: direction has a non-finite coordinate"),
            ([[np.nan, 0.0, 0.0]] + o3[1:], up3, 0.0, math.inf, "ray 0: origin has a non-finite coordinate"),
            (o3, up3, [0.0, 3.0, 0.0], [math.inf, 2.0, 1.0], "ray 1: tnear exceeds tfar"),
            (o3, up3, [0.0, 0.0, -math.inf], math.inf, "ray 2: tnear is not a finite number"),
            (o3, up3, 0.0, [1.0, np.nan, 1.0], "ray 1: tfar is NaN")):
        with pytest.raises(ValueError, match=re.escape(why)):
            open_cube_model.trace(origins, directions, tnear=near, tfar=far)
    r = open_cube_model.trace(o3, up3, tnear=[0.0, 1.0, 2.0], tfar=[math.inf, 1.0, math.inf])  # tnear = tfar
    assert not r.invalid.any() and r.hit.tolist() == [True, False, False]
    with pytest.raises(ValueError, match="origins has 2 rows"):
        open_cube_model.trace(np.zeros((2, 3)), np.ones((3, 3)))
    with pytest.raises(ValueError, match=r"tfar must be a number or have shape \(2,\)"):
        open_cube_model.trace(np.zeros((2, 3)), up, tfar=[1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match=r"shape \(k, 3\), got \(1, 4\)"):
        open_cube_model.trace([[0.0, 0.0, 0.0, 0.0]], up)
    with pytest.raises(ValueError, match="mode"):
        open_cube_model.trace([0.0, 0.0, 0.0], up, mode="bogus")
    with pytest.raises(ValueError, match="epsilon"):
        open_cube_model.trace([0.0, 0.0, 0.0], up, epsilon=0.0)
    with pytest.raises(ValueError, match="beta"):
        open_cube_model.trace([0.0, 0.0, 0.0], up, beta=-1.0)
    empty = open_cube_model.trace(np.empty((0, 3)), np.empty((0, 3)))
    assert empty.t.shape == (0,) and empty.position.shape == (0, 3) and empty.normal.shape == (0, 3)
