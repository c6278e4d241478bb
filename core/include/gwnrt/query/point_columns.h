// PointColumns: evaluate_points' results written field by field into caller-owned arrays (one
// row per point, structure of arrays), for callers that hand the arrays on (the Python module's
// numpy arrays, a file writer). A PointResult is 116 bytes; asking for w alone then writes 4
// bytes a point instead of 116, and the caller's arrays need no second copy. Host-and-device.
#pragma once

#include <cstddef>
#include <cstdint>

#include "gwnrt/query/point_query.h"

namespace gwnrt {

// Each pointer is null (the column is not wanted) or holds one row per point of the batch. A
// column given for a field the request does not compute receives PointResult's defaults.
struct PointColumns {
  float* w = nullptr;
  float* gradient = nullptr;  // 3 a point
  float* hessian = nullptr;   // 9 a point: the symmetric matrix in full, row by row
  float* unsigned_distance = nullptr;
  uint32_t* nearest_triangle = nullptr;
  float* barycentrics = nullptr;  // 2 a point: (u, v) of the closest point on nearest_triangle
  float* boundary_distance = nullptr;
  uint32_t* nearest_boundary_segment = nullptr;
  float* sdf = nullptr;
  float* sdf1 = nullptr;  // SignedDistance::first_order
  float* sdf2 = nullptr;  // SignedDistance::second_order
  float* sheet_distance = nullptr;
  uint32_t* sheet_triangle = nullptr;
  uint8_t* sdf_piece = nullptr;  // DistancePiece
  float* projection = nullptr;   // 3 a point
  uint32_t* projection_iterations = nullptr;
  uint8_t* projection_converged = nullptr;
  float* projection_residual = nullptr;
  float* harnack_bound = nullptr;
};

// Every column of `c`, given or not, as visit(pointer, values a row): for callers that handle the
// columns as whole arrays (the CUDA backend allocates the given ones on the device and copies them
// down). The member list above, once more: keep the two in step.
template <class Columns, class Visit>
void for_each_point_column(Columns& c, Visit&& visit) {
  visit(c.w, 1);
  visit(c.gradient, 3);
  visit(c.hessian, 9);
  visit(c.unsigned_distance, 1);
  visit(c.nearest_triangle, 1);
  visit(c.barycentrics, 2);
  visit(c.boundary_distance, 1);
  visit(c.nearest_boundary_segment, 1);
  visit(c.sdf, 1);
  visit(c.sdf1, 1);
  visit(c.sdf2, 1);
  visit(c.sheet_distance, 1);
  visit(c.sheet_triangle, 1);
  visit(c.sdf_piece, 1);
  visit(c.projection, 3);
  visit(c.projection_iterations, 1);
  visit(c.projection_converged, 1);
  visit(c.projection_residual, 1);
  visit(c.harnack_bound, 1);
}
static_assert(sizeof(PointColumns) == 19 * sizeof(void*), "a member added to PointColumns: add it above too");

GWNRT_HD inline void store_vec3(float* column, size_t i, const vec3& v) {
  column[3 * i] = v.x;
  column[3 * i + 1] = v.y;
  column[3 * i + 2] = v.z;
}

// Row i of every given column from r.
GWNRT_HD inline void store_point_result(const PointColumns& c, size_t i, const PointResult& r) {
  if (c.w) c.w[i] = r.w;
  if (c.gradient) store_vec3(c.gradient, i, r.gradient);
  if (c.hessian) {
    const sym3& h = r.hessian;
    const float full[9] = {h.xx, h.xy, h.xz, h.xy, h.yy, h.yz, h.xz, h.yz, h.zz};
    for (int k = 0; k < 9; ++k) c.hessian[9 * i + k] = full[k];
  }
  if (c.unsigned_distance) c.unsigned_distance[i] = r.unsigned_distance;
  if (c.nearest_triangle) c.nearest_triangle[i] = r.nearest_triangle;
  if (c.barycentrics) {
    c.barycentrics[2 * i] = r.bary_u;
    c.barycentrics[2 * i + 1] = r.bary_v;
  }
  if (c.boundary_distance) c.boundary_distance[i] = r.boundary_distance;
  if (c.nearest_boundary_segment) c.nearest_boundary_segment[i] = r.nearest_boundary_segment;
  if (c.sdf) c.sdf[i] = r.sdf.distance;
  if (c.sdf1) c.sdf1[i] = r.sdf.first_order;
  if (c.sdf2) c.sdf2[i] = r.sdf.second_order;
  if (c.sheet_distance) c.sheet_distance[i] = r.sdf.sheet_distance;
  if (c.sheet_triangle) c.sheet_triangle[i] = r.sdf.sheet_triangle;
  if (c.sdf_piece) c.sdf_piece[i] = uint8_t(r.sdf.piece);
  if (c.projection) store_vec3(c.projection, i, r.projection.point);
  if (c.projection_iterations) c.projection_iterations[i] = r.projection.iterations;
  if (c.projection_converged) c.projection_converged[i] = r.projection.converged ? 1 : 0;
  if (c.projection_residual) c.projection_residual[i] = r.projection.residual;
  if (c.harnack_bound) c.harnack_bound[i] = r.harnack_bound;
}

}  // namespace gwnrt
