// Exact predicates on float coordinates: a double evaluation with a forward error bound decides
// almost every call; the rest are decided by expansion arithmetic (numbers as sums of
// non-overlapping doubles, after Shewchuk 1997), which is exact for every finite float input
// (products of three float differences neither overflow nor underflow in double). The
// self-intersection count (meshing/mesh_quality.h) is built on them.
#pragma once

#include <array>

#include "gwnrt/base/hd.h"

namespace gwnrt {

namespace exact {

// The sign of det[b − a, c − a, d − a]: +1 when d lies on the side of the plane through a, b, c
// that (b − a) × (c − a) points to (a, b, c counter-clockwise seen from d), −1 on the other, 0
// when the four points are coplanar.
int orient3d(const vec3& a, const vec3& b, const vec3& c, const vec3& d);
// The sign of det[b − a, c − a]: +1 when a, b, c turn counter-clockwise.
int orient2d(const glm::vec2& a, const glm::vec2& b, const glm::vec2& c);
// The same, always by expansion arithmetic (no filter): for tests of that path.
int orient3d_expansion(const vec3& a, const vec3& b, const vec3& c, const vec3& d);
int orient2d_expansion(const glm::vec2& a, const glm::vec2& b, const glm::vec2& c);
// Whether the three points are collinear (the triangle has zero area): every coordinate-plane
// projection has orientation 0.
bool collinear(const vec3& a, const vec3& b, const vec3& c);

using Triangle = std::array<vec3, 3>;
// The pair test of count_self_intersections: whether p and q intersect other than in the
// vertices and edge they share (by equal positions). False when either has zero area.
bool triangles_intersect(const Triangle& p, const Triangle& q);
// The same for triangles known to have non-zero area (count_self_intersections filters them
// once, not once per pair).
bool triangles_of_nonzero_area_intersect(const Triangle& p, const Triangle& q);

}  // namespace exact

}  // namespace gwnrt
