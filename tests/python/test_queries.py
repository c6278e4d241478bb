"""Point queries of gwnrt.Model against independent float64 numpy references (reference_np):
w by every method, its gradient and Hessian, the unsigned and boundary distances, the signed
distance, the Harnack bound and the projection onto S.

gwnrt evaluates in float32 (the brute method sums in double but returns float32), so the
tolerances below are those of float32 results, not of the float64 references."""

import numpy as np
import pytest

import gwnrt
import reference_np as ref


def mesh64(model):
    """The mesh gwnrt holds (its float32 vertices) in float64, for the references."""
    return model.vertices.astype(np.float64), model.faces


def far_points(model, count, seed, min_distance, pad=0.5):
    """Points around the mesh at least `min_distance` (relative to the box diagonal) from it."""
    v, f = mesh64(model)
    p = ref.points_around(v, count, seed, pad)
    d, _ = ref.unsigned_distance(v, f, p)
    return p[d > min_distance * ref.box_diagonal(v)]


SMALL_MESHES = ["tetrahedron", "octahedron", "cube", "open_cube", "soup"]


@pytest.fixture(scope="module", params=SMALL_MESHES)
def small_model(request):
    return gwnrt.Model(request.getfixturevalue(request.param))


@pytest.fixture(scope="module")
def open_cube_model(open_cube):
    return gwnrt.Model(open_cube)


# -- w ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("method, order", [("brute", 2), ("crossing", 2), ("auto", 2), ("taylor", 0),
                                           ("taylor", 1), ("taylor", 2)])
def test_winding_number_small_meshes(small_model, method, order):
    v, f = mesh64(small_model)
    points = far_points(small_model, 600, 1, 0.01)
    expected = ref.winding_number(v, f, points)
    got = small_model.winding_number(points, method=method, order=order)
    assert got.shape == (len(points),) and got.dtype == np.float32
    # brute and crossing are exact up to float32: a handful of terms of size <= 1/2 each rounded to
    # ~6e-8 relative; 1e-5 absolute leaves a wide margin (measured <= 3e-7). On these meshes of at
    # most 40 triangles the tree's leaves are summed exactly, so Taylor meets the same bound
    # (auto takes Taylor on the soup, whose cone is 3 triangles per triangle; measured 9e-5 at
    # order 2, 8e-4 at order 0 there): its looser bound is Taylor's, as on the bunny below.
    tol = 1e-5 if method in ("brute", "crossing") else 2e-3
    np.testing.assert_allclose(got, expected, rtol=0, atol=tol)


def test_winding_number_closed_meshes_are_indicators(closed_mesh):
    # A closed, outward-oriented mesh: w is 1 inside and 0 outside (the reference agrees).
    model = gwnrt.Model(closed_mesh)
    v, f = mesh64(model)
    points = far_points(model, 400, 2, 0.01)
    expected = ref.winding_number(v, f, points)
    np.testing.assert_allclose(expected, np.round(expected), atol=1e-12)
    assert 0 < expected.sum() < len(points)  # both inside and outside points
    for method in ("brute", "crossing", "auto"):
        np.testing.assert_allclose(model.winding_number(points, method=method), expected, atol=1e-5)


@pytest.fixture(scope="module")
def bunny_holes_points(bunny_holes):
    v, f = mesh64(bunny_holes)
    points = far_points(bunny_holes, 500, 3, 0.01, pad=0.3)
    return points, ref.winding_number(v, f, points)


@pytest.mark.parametrize("method", ["brute", "crossing", "auto"])
def test_winding_number_exact_methods_bunny_holes(bunny_holes, bunny_holes_points, method):
    points, expected = bunny_holes_points
    # 3524 float32 terms whose errors add up: measured 1.4e-6 for crossing; 1e-5 leaves room.
    np.testing.assert_allclose(bunny_holes.winding_number(points, method=method), expected, atol=1e-5)


# Taylor is an approximation whose error falls with beta (the accuracy scale) and the order.
# Measured maxima over these points (bunny_holes, >= 1% of the diagonal from the mesh): beta 2:
# 0.025, 0.022, 1.1e-3 for orders 0, 1, 2; beta 8: 4.5e-4, 7e-5, 1.3e-6. The bounds leave 2-15x.
@pytest.mark.parametrize("beta, order, tol", [(2.0, 0, 0.05), (2.0, 1, 0.05), (2.0, 2, 3e-3),
                                              (8.0, 0, 2e-3), (8.0, 1, 5e-4), (8.0, 2, 2e-5)])
def test_winding_number_taylor_bunny_holes(bunny_holes, bunny_holes_points, beta, order, tol):
    points, expected = bunny_holes_points
    got = bunny_holes.winding_number(points, method="taylor", order=order, beta=beta)
    np.testing.assert_allclose(got, expected, atol=tol)


def test_taylor_error_falls_with_beta(bunny_holes, bunny_holes_points):
    points, expected = bunny_holes_points
    errors = [np.abs(bunny_holes.winding_number(points, method="taylor", order=2, beta=b) - expected).max()
              for b in (1.5, 4.0, 8.0)]
    assert errors[0] > errors[1] > errors[2], errors


# -- gradient and Hessian ------------------------------------------------------------------------

def model_and_count(request, large, large_count, small_count):
    """The session's model of the bundled mesh `large` (fewer points: each costs more brute force), or a
    model of the small mesh the fixture is parametrized with."""
    if request.param == large:
        return request.getfixturevalue(large), large_count
    return gwnrt.Model(request.getfixturevalue(request.param)), small_count


# Meshes where grad w is not zero: the open cube, the soup and bunny_holes (on closed meshes w is
# piecewise constant; the test above covers them).
@pytest.fixture(scope="module", params=["open_cube", "soup", "bunny_holes"])
def derivative_case(request):
    model, count = model_and_count(request, "bunny_holes", 60, 200)
    v, f = mesh64(model)
    # At least 5% of the diagonal from the mesh, where the third and fourth derivatives the finite
    # differences truncate stay moderate.
    points = far_points(model, 2 * count, 4, 0.05)[:count]
    return model, v, f, points


# Tolerances relative to the largest reference entry over the batch. The exact methods: float32
# results good to ~1e-6 of the scale (measured 2.5e-7 for the gradient, 1.3e-5 for the Hessian,
# whose finite differences below dominate). 'auto' is exact on the open cube and bunny_holes and
# Taylor at beta 2 on the soup (cone of 3 triangles per triangle; measured 1.8e-5). Taylor is
# checked at beta 8, where it is accurate (measured 2.6e-5 and 3.3e-5 of the scale on
# bunny_holes; at beta 2 its error there is 9% of the gradient's scale: an approximation).
@pytest.mark.parametrize("method, beta, tol", [("brute", 2.0, 1e-5), ("crossing", 2.0, 1e-5),
                                               ("auto", 2.0, 1e-4), ("taylor", 8.0, 2e-4)])
def test_gradient_vs_finite_differences(derivative_case, method, beta, tol):
    model, v, f, points = derivative_case
    # Central differences of the float64 w with h = 1e-5: truncation h^2 |w'''| / 6 and rounding
    # ~1e-16 / h, both < 1e-8 of the gradient's scale at these distances.
    expected = ref.gradient_fd(v, f, points, h=1e-5)
    got = model.gradient(points, method=method, beta=beta)
    assert got.shape == (len(points), 3) and got.dtype == np.float32
    np.testing.assert_allclose(got, expected, rtol=0, atol=tol * np.abs(expected).max())


@pytest.mark.parametrize("method, beta, tol", [("brute", 2.0, 1e-4), ("crossing", 2.0, 1e-4),
                                               ("auto", 2.0, 1e-4), ("taylor", 8.0, 5e-4)])
def test_hessian_vs_finite_differences(derivative_case, method, beta, tol):
    model, v, f, points = derivative_case
    # Second differences of the float64 w with h = 1e-3: truncation h^2 |w''''| / 12 (points >= 5%
    # of the diagonal away) and rounding ~1e-16 / h^2: measured 1.3e-5 of the Hessian's scale.
    expected = ref.hessian_fd(v, f, points, h=1e-3)
    got = model.hessian(points, method=method, beta=beta)
    assert got.shape == (len(points), 3, 3) and got.dtype == np.float32
    np.testing.assert_array_equal(got, np.transpose(got, (0, 2, 1)))  # symmetric
    np.testing.assert_allclose(got, expected, rtol=0, atol=tol * np.abs(expected).max())


def test_query_fields_equal_single_calls(derivative_case):
    model, _, _, points = derivative_case
    r = model.query(points, ["w", "gradient", "hessian"], method="crossing")
    assert set(r) == {"w", "gradient", "hessian"}
    # Not bit for bit: the core evaluates w by another rounding path when derivatives are asked for
    # too (measured 1.3e-6 on bunny_holes); the gradient and Hessian agree exactly.
    np.testing.assert_allclose(r["w"], model.winding_number(points, method="crossing"), atol=1e-5)
    np.testing.assert_array_equal(r["gradient"], model.gradient(points, method="crossing"))
    np.testing.assert_array_equal(r["hessian"], model.hessian(points, method="crossing"))


# -- unsigned and boundary distance ----------------------------------------------------------------

@pytest.fixture(scope="module", params=SMALL_MESHES + ["bunny_holes"])
def distance_case(request):
    model, count = model_and_count(request, "bunny_holes", 300, 500)
    v, f = mesh64(model)
    # Include points on and very near the mesh: the distance has no singularity there.
    points = ref.points_around(v, count, 5, pad=0.3)
    on = f[np.arange(20) % len(f)]
    points[:20] = 0.5 * v[on[:, 0]] + 0.3 * v[on[:, 1]] + 0.2 * v[on[:, 2]]
    return model, v, f, points


def distance_tolerance(v):
    # float32 positions carry ~6e-8 relative rounding of the coordinates (which reach about the box
    # size); 1e-6 of the diagonal is 15 ulps of that, measured <= 1e-6 on bunny_holes (diagonal 15.8).
    return 1e-6 * ref.box_diagonal(v) + 1e-7


def test_unsigned_distance_vs_brute_force(distance_case):
    model, v, f, points = distance_case
    expected, _ = ref.unsigned_distance(v, f, points)
    r = model.unsigned_distance(points)
    assert r.distance.shape == (len(points),) and r.distance.dtype == np.float32
    assert r.triangle.dtype == np.int32 and r.barycentrics.shape == (len(points), 2)
    tol = distance_tolerance(v)
    np.testing.assert_allclose(r.distance, expected, rtol=1e-6, atol=tol)
    # The triangle returned is a nearest one (ties on shared edges may pick either).
    assert ((r.triangle >= 0) & (r.triangle < len(f))).all()
    a, b, c = (v[f[r.triangle, i]] for i in range(3))
    closest, _, _ = ref.closest_point_on_triangles(points, a, b, c)
    np.testing.assert_allclose(np.linalg.norm(closest - points, axis=1), expected, rtol=1e-6, atol=tol)
    # The barycentrics: inside the triangle, and they rebuild its closest point to the point.
    u, w = r.barycentrics.astype(np.float64).T
    assert (u >= -1e-6).all() and (w >= -1e-6).all() and (u + w <= 1 + 1e-6).all()
    rebuilt = (1 - u - w)[:, None] * a + u[:, None] * b + w[:, None] * c
    np.testing.assert_allclose(rebuilt, closest, atol=10 * tol)
    np.testing.assert_allclose(np.linalg.norm(rebuilt - points, axis=1), expected, rtol=1e-6, atol=tol)


def test_boundary_distance_vs_brute_force(distance_case):
    model, v, f, points = distance_case
    edges = ref.boundary_edges(f)
    r = model.boundary_distance(points)
    assert r.distance.dtype == np.float32 and r.segment.dtype == np.int32
    assert model.boundary_segment_count == len(edges)
    if len(edges) == 0:  # closed: no boundary curve
        assert np.isposinf(r.distance).all()
        assert (r.segment == -1).all()
        return
    expected = ref.segment_distance(v, edges, points)
    np.testing.assert_allclose(r.distance, expected, rtol=1e-6, atol=distance_tolerance(v))
    assert ((r.segment >= 0) & (r.segment < len(edges))).all()


def test_open_cube_boundary_is_the_hole(open_cube_model):
    # The hole's rim: the square z = 1, |x|, |y| <= 1. At (0, 0, 1 + h) it is sqrt(1 + h^2) away.
    h = np.array([0.0, 0.5, 2.0])
    points = np.column_stack([np.zeros(3), np.zeros(3), 1 + h])
    got = open_cube_model.boundary_distance(points).distance
    np.testing.assert_allclose(got, np.sqrt(1 + h * h), rtol=1e-6)
    assert open_cube_model.boundary_segment_count == 4


# -- signed distance, Harnack bound, projection ----------------------------------------------------

@pytest.fixture(scope="module", params=["tetrahedron", "octahedron", "cube", "bunny"])
def closed_case(request):
    model, count = model_and_count(request, "bunny", 300, 500)
    v, f = mesh64(model)
    points = ref.points_around(v, count, 6, pad=0.3)
    distance, _ = ref.unsigned_distance(v, f, points)
    keep = distance > 1e-4 * ref.box_diagonal(v)  # off the surface, where the sign is defined
    return model, v, f, points[keep], distance[keep], ref.winding_number(v, f, points[keep])


def test_signed_distance_closed_mesh(closed_case):
    model, v, _, points, distance, w = closed_case
    r = model.signed_distance(points)
    assert r.sdf.shape == (len(points),) and r.sdf.dtype == np.float32 and r.piece.dtype == np.uint8
    # For a closed mesh S is the mesh: |sdf| is the distance to it, negative inside (w = 1).
    np.testing.assert_allclose(np.abs(r.sdf), distance, rtol=1e-6, atol=distance_tolerance(v))
    np.testing.assert_array_equal(r.sdf < 0, w > 0.5)
    assert ((w > 0.5) & (r.sdf < 0)).any() and ((w < 0.5) & (r.sdf > 0)).any()


def test_harnack_bound_closed_mesh(closed_case):
    model, v, _, points, distance, _ = closed_case
    rho = model.harnack_bound(points)
    assert rho.dtype == np.float32 and (rho >= 0).all()
    # A proven lower bound on the distance to S (= the mesh): float32 slack only.
    tol = distance_tolerance(v)
    assert (rho <= distance + tol).all()
    assert (rho <= np.abs(model.signed_distance(points).sdf) + tol).all()


@pytest.mark.parametrize("name", ["open_cube", "bunny_holes"])
def test_signed_distance_sign_open_mesh(request, name):
    model = request.getfixturevalue(name)
    model = model if isinstance(model, gwnrt.Model) else gwnrt.Model(model)
    v, f = mesh64(model)
    points = ref.points_around(v, 300, 7, pad=0.3)
    w = ref.winding_number(v, f, points)
    keep = np.abs(w - 0.5) > 1e-3  # not on S, where float32 could take either side
    sdf = model.signed_distance(points[keep]).sdf
    # S is the boundary of {w > 1/2}: negative exactly there.
    np.testing.assert_array_equal(sdf < 0, w[keep] > 0.5)
    assert (sdf < 0).any() and (sdf > 0).any()


def test_harnack_bound_open_cube_ball_is_free_of_s(open_cube_model):
    # rho(x) <= distance(x, S): no point of the ball of radius rho around x lies on S, so the numpy
    # w - 1/2 keeps x's sign at every sample of the (slightly shrunk) ball.
    v, f = mesh64(open_cube_model)
    points = ref.points_around(v, 60, 8, pad=0.3)
    rho = open_cube_model.harnack_bound(points).astype(np.float64)
    rng = np.random.default_rng(9)
    dirs = rng.normal(size=(60, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    radii = 0.999 * rng.uniform(0, 1, 60) ** (1 / 3)
    inside = ref.winding_number(v, f, points) > 0.5
    for i in np.nonzero(rho > 0)[0]:
        samples = points[i] + rho[i] * radii[:, None] * dirs
        same_side = (ref.winding_number(v, f, samples) > 0.5) == inside[i]
        assert same_side.all(), f"point {i}: S within the Harnack ball of radius {rho[i]}"
    assert (rho > 0).sum() >= 50


@pytest.mark.parametrize("name", ["open_cube", "bunny_holes"])
def test_project_reaches_the_level_set(request, name):
    model = request.getfixturevalue(name)
    model = model if isinstance(model, gwnrt.Model) else gwnrt.Model(model)
    v, f = mesh64(model)
    points = ref.points_around(v, 300, 10, pad=0.2)
    tolerance = 1e-4
    r = model.project(points, tolerance=tolerance)
    assert r.point.shape == (len(points), 3) and r.converged.dtype == np.bool_
    assert r.converged.sum() >= 30, r.converged.sum()
    reached = r.point[r.converged].astype(np.float64)
    w = ref.winding_number(v, f, reached)
    # Converged means |w - level| <= tolerance by gwnrt's float32 w, itself within ~2e-6 of the
    # float64 w here (see the bunny_holes w test); the residual is w - level.
    assert np.abs(w - 0.5).max() <= tolerance + 1e-5
    np.testing.assert_allclose(r.residual[r.converged], w - 0.5, atol=1e-5)
    assert (r.iterations[r.converged] >= 1).all()


def test_project_on_a_closed_mesh_converges_nowhere(octahedron):
    # A closed mesh's w is 0 or 1: S has no smooth piece to project onto.
    model = gwnrt.Model(octahedron)
    r = model.project(ref.points_around(model.vertices, 50, 11))
    assert not r.converged.any()
