"""Independent float64 numpy references for the Python binding tests: the generalized winding
number (van Oosterom-Strackee), its finite-difference derivatives, point-triangle distance
(Ericson's region method), point-segment distance, boundary edges and Moller-Trumbore ray
casting. Nothing here calls gwnrt. Not a test file (pytest collects test_*.py only)."""

import numpy as np

FOUR_PI = 4.0 * np.pi


def _corners(vertices, faces):
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    return v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]


def _dot(x, y):
    return np.einsum("...i,...i->...", x, y)


def winding_number(vertices, faces, points, chunk=256):
    """w(p) = sum over triangles of Omega(p) / (4 pi), Omega = 2 atan2(det[a, b, c],
    |a||b||c| + (a.b)|c| + (b.c)|a| + (c.a)|b|), a, b, c the corners minus p; in float64."""
    a0, b0, c0 = _corners(vertices, faces)
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    out = np.empty(len(p))
    for s in range(0, len(p), chunk):
        q = p[s:s + chunk, None, :]
        a, b, c = a0[None] - q, b0[None] - q, c0[None] - q
        la, lb, lc = (np.linalg.norm(x, axis=-1) for x in (a, b, c))
        det = _dot(a, np.cross(b, c))
        den = la * lb * lc + _dot(a, b) * lc + _dot(b, c) * la + _dot(c, a) * lb
        out[s:s + chunk] = (2.0 * np.arctan2(det, den)).sum(axis=1) / FOUR_PI
    return out


def gradient_fd(vertices, faces, points, h=1e-5):
    """grad w by central differences of the float64 w (truncation O(h^2), rounding ~1e-16/h)."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    g = np.empty_like(p)
    for i in range(3):
        e = np.zeros(3)
        e[i] = h
        g[:, i] = (winding_number(vertices, faces, p + e) - winding_number(vertices, faces, p - e)) / (2 * h)
    return g


def hessian_fd(vertices, faces, points, h=1e-3):
    """H_w by second central differences of the float64 w (truncation O(h^2), rounding ~1e-16/h^2)."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    w0 = winding_number(vertices, faces, p)
    hess = np.empty((len(p), 3, 3))
    eye = np.eye(3) * h
    for i in range(3):
        wp = winding_number(vertices, faces, p + eye[i])
        wm = winding_number(vertices, faces, p - eye[i])
        hess[:, i, i] = (wp - 2.0 * w0 + wm) / (h * h)
        for j in range(i + 1, 3):
            d = (winding_number(vertices, faces, p + eye[i] + eye[j])
                 - winding_number(vertices, faces, p + eye[i] - eye[j])
                 - winding_number(vertices, faces, p - eye[i] + eye[j])
                 + winding_number(vertices, faces, p - eye[i] - eye[j])) / (4.0 * h * h)
            hess[:, i, j] = hess[:, j, i] = d
    return hess


def closest_point_on_triangles(p, a, b, c):
    """Ericson's region method (Real-Time Collision Detection, 5.1.5), vectorised: p, a, b, c
    broadcast to (..., 3). Returns (closest point, u, v) with closest = (1-u-v) a + u b + v c."""
    p, a, b, c = np.broadcast_arrays(*(np.asarray(x, dtype=np.float64) for x in (p, a, b, c)))
    ab, ac, ap, bp, cp = b - a, c - a, p - a, p - b, p - c
    d1, d2 = _dot(ab, ap), _dot(ac, ap)
    d3, d4 = _dot(ab, bp), _dot(ac, bp)
    d5, d6 = _dot(ab, cp), _dot(ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2

    def ratio(n, d):
        return np.divide(n, d, out=np.zeros_like(n), where=d != 0)

    zero, one = np.zeros_like(d1), np.ones_like(d1)
    t_ab = ratio(d1, d1 - d3)
    t_ac = ratio(d2, d2 - d6)
    t_bc = ratio(d4 - d3, (d4 - d3) + (d5 - d6))
    total = va + vb + vc
    u_in, v_in = ratio(vb, total), ratio(vc, total)
    regions = [
        (d1 <= 0) & (d2 <= 0),  # vertex a
        (d3 >= 0) & (d4 <= d3),  # vertex b
        (vc <= 0) & (d1 >= 0) & (d3 <= 0),  # edge ab
        (d6 >= 0) & (d5 <= d6),  # vertex c
        (vb <= 0) & (d2 >= 0) & (d6 <= 0),  # edge ac
        (va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0),  # edge bc
    ]
    u = np.select(regions, [zero, one, t_ab, zero, zero, 1.0 - t_bc], default=u_in)
    v = np.select(regions, [zero, zero, zero, one, t_ac, t_bc], default=v_in)
    q = a + u[..., None] * ab + v[..., None] * ac
    return q, u, v


def point_triangle_distances(vertices, faces, points):
    """(k, m) float64 distances from each point to each triangle."""
    a, b, c = _corners(vertices, faces)
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)[:, None, :]
    q, _, _ = closest_point_on_triangles(p, a[None], b[None], c[None])
    return np.linalg.norm(q - p, axis=-1)


def unsigned_distance(vertices, faces, points, chunk=128):
    """(distance, nearest triangle) by brute force over every triangle, in float64."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    dist = np.empty(len(p))
    tri = np.empty(len(p), dtype=np.int64)
    for s in range(0, len(p), chunk):
        d = point_triangle_distances(vertices, faces, p[s:s + chunk])
        tri[s:s + chunk] = d.argmin(axis=1)
        dist[s:s + chunk] = d.min(axis=1)
    return dist, tri


def boundary_edges(faces):
    """(e, 2) undirected edges used by exactly one triangle."""
    f = np.asarray(faces, dtype=np.int64)
    edges = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    unique, counts = np.unique(edges, axis=0, return_counts=True)
    return unique[counts == 1]


def segment_distance(vertices, edges, points):
    """(k,) float64 distance from each point to the nearest of the segments (+inf without any)."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if len(edges) == 0:
        return np.full(len(p), np.inf)
    v = np.asarray(vertices, dtype=np.float64)
    a, b = v[edges[:, 0]][None], v[edges[:, 1]][None]
    ab = b - a
    t = np.clip(_dot(p[:, None] - a, ab) / _dot(ab, ab), 0.0, 1.0)
    q = a + t[..., None] * ab
    return np.linalg.norm(q - p[:, None], axis=-1).min(axis=1)


def ray_mesh_hits(vertices, faces, origins, directions):
    """Moller-Trumbore in float64: the nearest t > 0 along o + t d over every triangle (inf on a
    miss) and its triangle (-1 on a miss)."""
    a, b, c = _corners(vertices, faces)
    o = np.asarray(origins, dtype=np.float64).reshape(-1, 3)[:, None]
    d = np.asarray(directions, dtype=np.float64).reshape(-1, 3)[:, None]
    e1, e2 = (b - a)[None], (c - a)[None]
    pvec = np.cross(d, e2)
    det = _dot(e1, pvec)
    ok = np.abs(det) > 1e-14
    inv = np.divide(1.0, det, out=np.zeros_like(det), where=ok)
    tvec = o - a[None]
    u = _dot(tvec, pvec) * inv
    qvec = np.cross(tvec, e1)
    v = _dot(d, qvec) * inv
    t = _dot(e2, qvec) * inv
    hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
    t = np.where(hit, t, np.inf)
    tri = t.argmin(axis=1)
    best = t[np.arange(len(t)), tri]
    return best, np.where(np.isfinite(best), tri, -1)


def first_level_crossing(vertices, faces, origin, direction, t_max, level=0.5, samples=2000):
    """The first t in (0, t_max] where the float64 w along o + t d crosses `level` (sampled, then
    bisected), or None. Meant for a stretch of ray that crosses no triangle (w is continuous)."""
    o = np.asarray(origin, dtype=np.float64)
    d = np.asarray(direction, dtype=np.float64)
    ts = np.linspace(0.0, t_max, samples + 1)
    w = winding_number(vertices, faces, o + ts[:, None] * d) - level
    change = np.nonzero(np.sign(w[:-1]) != np.sign(w[1:]))[0]
    if len(change) == 0:
        return None
    lo, hi = ts[change[0]], ts[change[0] + 1]
    f_lo = w[change[0]]
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        f_mid = winding_number(vertices, faces, o + mid * d)[0] - level
        if np.sign(f_mid) == np.sign(f_lo):
            lo, f_lo = mid, f_mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def points_around(vertices, count, seed, pad=0.5):
    """`count` uniform float64 points in the box of `vertices` grown by `pad` times its size on
    each side (a sampling helper, not a reference)."""
    v = np.asarray(vertices, dtype=np.float64)
    lo, hi = v.min(axis=0), v.max(axis=0)
    grow = pad * (hi - lo)
    return np.random.default_rng(seed).uniform(lo - grow, hi + grow, (count, 3))


def box_diagonal(vertices):
    v = np.asarray(vertices, dtype=np.float64)
    return float(np.linalg.norm(v.max(axis=0) - v.min(axis=0)))
