// The TBB batch driver against the single-point path, request and mesh validation, and the
// structural invariants of the BVH and its expansions that the queries rely on.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <numeric>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <tbb/global_control.h>

#include "gwnrt/field/evaluate_winding.h"
#include "gwnrt/field/winding_number.h"
#include "reference/exact_distance.h"
#include "test_util.h"

namespace gwnrt {
namespace {

using test::build_model;
using test::load_test_mesh;
using test::mesh_bounds;
using test::sample_points;

constexpr uint32_t kAllFields =
    kFieldW | kFieldGradient | kFieldHessian | kFieldUnsignedDistance | kFieldBoundaryDistance;

// Bitwise float equality: the batch driver must run the very same arithmetic.
bool same(float a, float b) { return std::bit_cast<uint32_t>(a) == std::bit_cast<uint32_t>(b); }

::testing::AssertionResult identical(const PointResult& a, const PointResult& b) {
  const float fa[] = {a.w,          a.gradient.x,       a.gradient.y, a.gradient.z, a.hessian.xx,        a.hessian.xy,
                      a.hessian.xz, a.hessian.yy,       a.hessian.yz, a.hessian.zz, a.unsigned_distance, a.bary_u,
                      a.bary_v,     a.boundary_distance};
  const float fb[] = {b.w,          b.gradient.x,       b.gradient.y, b.gradient.z, b.hessian.xx,        b.hessian.xy,
                      b.hessian.xz, b.hessian.yy,       b.hessian.yz, b.hessian.zz, b.unsigned_distance, b.bary_u,
                      b.bary_v,     b.boundary_distance};
  for (size_t k = 0; k < std::size(fa); ++k)
    if (!same(fa[k], fb[k]))
      return ::testing::AssertionFailure() << "float field " << k << ": " << fa[k] << " vs " << fb[k];
  if (a.nearest_triangle != b.nearest_triangle) return ::testing::AssertionFailure() << "nearest_triangle differs";
  if (a.nearest_boundary_segment != b.nearest_boundary_segment)
    return ::testing::AssertionFailure() << "nearest_boundary_segment differs";
  return ::testing::AssertionSuccess();
}

QueryRequest request_for(int order, bool exact) {
  QueryRequest r;
  r.fields = kAllFields;
  r.taylor.order = order;
  r.method = exact ? WindingMethod::kBrute : WindingMethod::kTaylor;
  return r;
}

std::vector<PointResult> run_batch(const GwnModel& model, std::span<const vec3> points, const QueryRequest& request) {
  std::vector<PointResult> results(points.size());
  const Status s = evaluate_points(model, points, request, results);
  EXPECT_TRUE(s.ok()) << s.message();
  return results;
}

class BatchOnRealMeshes : public ::testing::TestWithParam<const char*> {};

TEST_P(BatchOnRealMeshes, BitIdenticalToSinglePointsInInputOrder) {
  const GwnModel model = build_model(load_test_mesh(GetParam()));
  const std::vector<vec3> points = sample_points(mesh_bounds(model.mesh()), 5000, 21);
  const ModelView view = model.view();
  for (const bool exact : {false, true}) {
    for (int order = 0; order <= 2; ++order) {
      if (exact && order > 0) break;  // exact ignores the order
      SCOPED_TRACE(exact ? std::string("exact") : "order " + std::to_string(order));
      const QueryRequest request = request_for(order, exact);
      // The brute force on a tenth of the points: it sums every triangle for every field, and
      // was most of this test's time (8x under ASan).
      const std::span<const vec3> some(points.data(), exact ? points.size() / 10 : points.size());
      const std::vector<PointResult> batch = run_batch(model, some, request);
      for (size_t i = 0; i < some.size(); ++i)
        ASSERT_TRUE(identical(batch[i], evaluate_point(view, some[i], request))) << "point " << i;
    }
  }
  // Shuffled input gives the same results, shuffled the same way.
  const QueryRequest request = request_for(2, false);
  const std::vector<PointResult> straight = run_batch(model, points, request);
  std::vector<size_t> perm(points.size());
  std::iota(perm.begin(), perm.end(), size_t(0));
  std::shuffle(perm.begin(), perm.end(), std::mt19937(4));
  std::vector<vec3> shuffled(points.size());
  for (size_t i = 0; i < points.size(); ++i) shuffled[i] = points[perm[i]];
  const std::vector<PointResult> results = run_batch(model, shuffled, request);
  for (size_t i = 0; i < points.size(); ++i) ASSERT_TRUE(identical(results[i], straight[perm[i]])) << "point " << i;
}

TEST_P(BatchOnRealMeshes, LargeBatchVisitedInSpatialOrderAnswersInInputOrder) {
  // Batches of 16384 points and more are evaluated in Morton order (batch.cpp): every result
  // must still be the single-point answer at its own index, also for points far outside the box
  // (clamped to its faces in the order), as far as the drivers serve (validate_points).
  const GwnModel model = build_model(load_test_mesh(GetParam()));
  std::vector<vec3> points = sample_points(mesh_bounds(model.mesh()), 40000, 23);
  points[17] = vec3(kMaxQueryCoordinate, -kMaxQueryCoordinate, 0.0f);
  points[40] = vec3(-kMaxQueryCoordinate, 0.0f, 1e9f);
  const ModelView view = model.view();
  for (const WindingMethod method : {WindingMethod::kTaylor, WindingMethod::kCrossing}) {
    QueryRequest request;
    request.method = method;
    request.fields = kFieldW | kFieldGradient;
    const std::vector<PointResult> batch = run_batch(model, points, request);
    for (size_t i = 0; i < points.size(); ++i)
      ASSERT_TRUE(identical(batch[i], evaluate_point(view, points[i], request)))
          << winding_method_name(method) << " point " << i;
  }
}

TEST_P(BatchOnRealMeshes, ThreadCountDoesNotChangeResults) {
  const GwnModel model = build_model(load_test_mesh(GetParam()));
  const std::vector<vec3> points = sample_points(mesh_bounds(model.mesh()), 5000, 22);
  const QueryRequest request = request_for(2, false);
  std::vector<PointResult> one, two;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = run_batch(model, points, request);
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two = run_batch(model, points, request);
  }
  for (size_t i = 0; i < points.size(); ++i) ASSERT_TRUE(identical(one[i], two[i])) << "point " << i;
}

TEST_P(BatchOnRealMeshes, ColumnsHoldThePointResultsFields) {
  // evaluate_points_to_columns writes each field where the Python module's arrays are: every
  // column equals the PointResult batch's field, bit for bit, at every point (Morton-ordered
  // batch: 20000 points); the Hessian in full, symmetric.
  GwnModel model = build_model(load_test_mesh(GetParam()));
  const std::vector<vec3> points = sample_points(mesh_bounds(model.mesh()), 20000, 24);
  QueryRequest request;
  request.fields = kAllFields | kFieldSignedDistance | kFieldPseudoDistance | kFieldProjection | kFieldHarnackBound;
  const std::vector<PointResult> results = run_batch(model, points, request);
  const size_t n = points.size();
  std::vector<float> w(n), gradient(3 * n), hessian(9 * n), udist(n), bary(2 * n), bdist(n), sdf(n), sdf1(n), sdf2(n),
      sheet(n), projection(3 * n), residual(n), bound(n);
  std::vector<uint32_t> triangle(n), segment(n), sheet_triangle(n), iterations(n);
  std::vector<uint8_t> piece(n), converged(n);
  const PointColumns columns{
      w.data(),          gradient.data(),  hessian.data(),        udist.data(), triangle.data(),
      bary.data(),       bdist.data(),     segment.data(),        sdf.data(),   sdf1.data(),
      sdf2.data(),       sheet.data(),     sheet_triangle.data(), piece.data(), projection.data(),
      iterations.data(), converged.data(), residual.data(),       bound.data()};
  const Status s = evaluate_points_to_columns(model, points, request, columns);
  ASSERT_TRUE(s.ok()) << s.message();
  for (size_t i = 0; i < n; ++i) {
    const PointResult& r = results[i];
    const sym3& h = r.hessian;
    const float expected_hessian[9] = {h.xx, h.xy, h.xz, h.xy, h.yy, h.yz, h.xz, h.yz, h.zz};
    for (int k = 0; k < 9; ++k) ASSERT_TRUE(same(hessian[9 * i + k], expected_hessian[k])) << i;
    for (int a = 0; a < 3; ++a) {
      ASSERT_TRUE(same(gradient[3 * i + a], r.gradient[a])) << i;
      ASSERT_TRUE(same(projection[3 * i + a], r.projection.point[a])) << i;
    }
    const float floats[][2] = {{w[i], r.w},
                               {udist[i], r.unsigned_distance},
                               {bary[2 * i], r.bary_u},
                               {bary[2 * i + 1], r.bary_v},
                               {bdist[i], r.boundary_distance},
                               {sdf[i], r.sdf.distance},
                               {sdf1[i], r.sdf.first_order},
                               {sdf2[i], r.sdf.second_order},
                               {sheet[i], r.sdf.sheet_distance},
                               {residual[i], r.projection.residual},
                               {bound[i], r.harnack_bound}};
    for (const auto& f : floats) ASSERT_TRUE(same(f[0], f[1])) << "point " << i << ": " << f[0] << " vs " << f[1];
    ASSERT_EQ(triangle[i], r.nearest_triangle);
    ASSERT_EQ(segment[i], r.nearest_boundary_segment);
    ASSERT_EQ(sheet_triangle[i], r.sdf.sheet_triangle);
    ASSERT_EQ(iterations[i], r.projection.iterations);
    ASSERT_EQ(piece[i], uint8_t(r.sdf.piece));
    ASSERT_EQ(converged[i], r.projection.converged ? 1 : 0);
  }
  // Only the columns given are written; the same failures as evaluate_points.
  std::vector<float> w_only(n, -7.0f);
  PointColumns just_w;
  just_w.w = w_only.data();
  request.fields = kFieldW;
  ASSERT_TRUE(evaluate_points_to_columns(model, points, request, just_w).ok());
  const std::vector<PointResult> w_results = run_batch(model, points, request);
  for (size_t i = 0; i < n; ++i) ASSERT_TRUE(same(w_only[i], w_results[i].w)) << i;
  std::vector<vec3> bad = points;
  bad[5].y = std::numeric_limits<float>::quiet_NaN();
  const Status refused = evaluate_points_to_columns(model, bad, request, just_w);
  EXPECT_FALSE(refused.ok());
  EXPECT_NE(refused.message().find("point 5"), std::string::npos) << refused.message();
}

// for_each_point_column (the CUDA backend sizes and copies the device columns by it) names every
// member of PointColumns once, each with as many values a row as store_point_result writes:
// columns of 3 rows filled with 0xAB, row 1 stored from a result none of whose bytes is 0xAB,
// must be written whole in row 1 and untouched in rows 0 and 2.
TEST(PointColumnsTable, VisitsEveryColumnWithTheValuesARowHolds) {
  PointResult r;
  r.w = r.unsigned_distance = r.bary_u = r.bary_v = r.boundary_distance = r.harnack_bound = 1.0f;
  r.gradient = r.projection.point = vec3(1.0f);
  r.hessian = sym3{1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f};
  r.nearest_triangle = r.nearest_boundary_segment = r.sdf.sheet_triangle = r.projection.iterations = 1;
  r.sdf.distance = r.sdf.first_order = r.sdf.second_order = r.sdf.sheet_distance = r.projection.residual = 1.0f;
  r.sdf.piece = DistancePiece(1);
  r.projection.converged = true;
  constexpr unsigned char kUnwritten = 0xAB;
  test::AllPointColumns all(3, kUnwritten);
  std::vector<const void*> seen;
  for_each_point_column(all.columns, [&](auto*& column, size_t) { seen.push_back(&column); });
  ASSERT_EQ(seen.size(), sizeof(PointColumns) / sizeof(void*));
  std::sort(seen.begin(), seen.end());
  EXPECT_EQ(std::adjacent_find(seen.begin(), seen.end()), seen.end()) << "a member visited twice";
  store_point_result(all.columns, 1, r);
  for (size_t k = 0; k < all.bytes.size(); ++k) {
    const std::vector<unsigned char>& bytes = all.bytes[k];
    const size_t row = all.row_bytes[k];
    for (size_t b = 0; b < bytes.size(); ++b) {
      const bool in_row_1 = b >= row && b < 2 * row;
      ASSERT_EQ(bytes[b] != kUnwritten, in_row_1) << "column " << k << " (" << row << " bytes a row), byte " << b;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Meshes, BatchOnRealMeshes, ::testing::Values("teapot.obj", "bunny_holes.obj"),
                         [](const auto& info) {
                           std::string name = info.param;
                           return name.substr(0, name.find('.'));
                         });

TEST(Batch, ModelBuiltOnOneOrTwoThreadsAnswersIdentically) {
  // The builder assigns node indices from parallel tasks; that may renumber nodes but must not
  // change any answer.
  const Mesh mesh = load_test_mesh("dragon_vrip_res4.ply");
  GwnModel one, two;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = build_model(mesh);
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two = build_model(mesh);
  }
  const std::vector<vec3> points = sample_points(mesh_bounds(mesh), 2000, 23);
  const QueryRequest request = request_for(2, false);
  const std::vector<PointResult> a = run_batch(one, points, request), b = run_batch(two, points, request);
  for (size_t i = 0; i < points.size(); ++i) ASSERT_TRUE(identical(a[i], b[i])) << "point " << i;
}

TEST(Batch, WindingMethodsByName) {
  // winding_method_named inverts winding_method_name and takes no other name.
  std::set<std::string> names;
  for (uint32_t m = 0; m < kWindingMethodCount; ++m) {
    const char* name = winding_method_name(WindingMethod(m));
    names.insert(name);
    WindingMethod found = WindingMethod((m + 1) % kWindingMethodCount);
    ASSERT_TRUE(winding_method_named(name, found)) << name;
    EXPECT_EQ(found, WindingMethod(m)) << name;
  }
  EXPECT_EQ(names.size(), size_t(kWindingMethodCount));  // no two methods share a name
  WindingMethod untouched = WindingMethod::kTaylor;
  for (const char* other : {"", "Taylor", "exact", "crossings", "brute-force"}) {
    EXPECT_FALSE(winding_method_named(other, untouched)) << other;
    EXPECT_EQ(untouched, WindingMethod::kTaylor);
  }
}

TEST(Batch, RejectsBadRequests) {
  const GwnModel model = build_model(test::make_cube());
  const std::vector<vec3> points(3, vec3(0.0f));
  std::vector<PointResult> results(3);

  std::vector<PointResult> too_few(2);
  Status s = evaluate_points(model, points, QueryRequest{}, too_few);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("3 points"), std::string::npos) << s.message();

  auto expect_rejected = [&](QueryRequest r, const char* what) {
    const Status st = evaluate_points(model, points, r, results);
    EXPECT_FALSE(st.ok()) << what;
    EXPECT_EQ(st.code(), StatusCode::kInvalidArgument) << what;
    EXPECT_FALSE(st.message().empty()) << what;
    EXPECT_FALSE(validate_request(r).ok()) << what;
  };
  QueryRequest r;
  r.taylor.order = 3;
  expect_rejected(r, "order 3");
  r.taylor.order = -1;
  expect_rejected(r, "order -1");
  for (const float beta : {0.0f, -1.0f, std::numeric_limits<float>::quiet_NaN(), kInfinity}) {
    r = QueryRequest{};
    r.taylor.beta = beta;
    expect_rejected(r, ("beta " + std::to_string(beta)).c_str());
  }
  r = QueryRequest{};
  r.taylor.order = 3;
  r.method = WindingMethod::kBrute;  // brute ignores the order, but a bad one is still a caller error
  expect_rejected(r, "order 3 with brute");
  r = QueryRequest{};
  r.method = WindingMethod(7);
  expect_rejected(r, "method 7");

  EXPECT_TRUE(evaluate_points(model, points, QueryRequest{}, results).ok());
  // Nothing to do is not an error.
  EXPECT_TRUE(evaluate_points(model, {}, QueryRequest{}, {}).ok());
}

TEST(ModelBuild, RejectsInvalidMeshesWithAReason) {
  auto expect_rejected = [](Mesh m, const char* expected_words) {
    GwnModel model;
    const Status s = GwnModel::build(std::move(m), model);
    EXPECT_FALSE(s.ok());
    EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
    EXPECT_NE(s.message().find(expected_words), std::string::npos) << s.message();
  };
  expect_rejected(Mesh{}, "no triangles");
  Mesh only_vertices;
  only_vertices.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  expect_rejected(only_vertices, "no triangles");

  Mesh nan_mesh = test::make_cube();
  nan_mesh.positions[5].y = std::numeric_limits<float>::quiet_NaN();
  expect_rejected(nan_mesh, "vertex 5");
  Mesh inf_mesh = test::make_cube();
  inf_mesh.positions[2].z = -kInfinity;
  expect_rejected(inf_mesh, "non-finite");

  Mesh bad_index = test::make_cube();
  bad_index.triangles[7][1] = 8;
  expect_rejected(bad_index, "triangle 7");
}

// Runs every field on a tiny mesh, exact and by the tree, and checks the distances against
// brute force; returns the results of both runs for mesh-specific checks.
void check_tiny_mesh(const Mesh& mesh, const std::function<void(const vec3&, const PointResult&, bool exact)>& more) {
  const GwnModel model = build_model(mesh);
  // Zero-area triangles are left out of the tree (they contribute nothing to w).
  size_t with_area = 0;
  for (const uvec3& t : mesh.triangles)
    with_area += !is_degenerate_triangle(mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]);
  EXPECT_EQ(model.triangle_tree().triangle_ids.size(), with_area);
  const std::vector<vec3> points = sample_points(Aabb{vec3(-1.0f), vec3(2.0f)}, 300, 31);
  for (const bool exact : {false, true}) {
    SCOPED_TRACE(exact ? "exact" : "tree");
    const std::vector<PointResult> results = run_batch(model, points, request_for(2, exact));
    for (size_t i = 0; i < points.size(); ++i) {
      SCOPED_TRACE("point " + std::to_string(i));
      // Float distances of O(1) coordinates.
      EXPECT_NEAR(results[i].unsigned_distance, reference::mesh_distance(mesh, dvec3(points[i])), 1e-5);
      EXPECT_LT(results[i].nearest_triangle, mesh.triangles.size());
      more(points[i], results[i], exact);
    }
  }
}

TEST(ModelBuild, SingleTriangle) {
  Mesh single;
  single.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  single.triangles = {{0, 1, 2}};
  const GwnModel model = build_model(single);
  EXPECT_EQ(model.boundary().segment_count(), 3u);
  check_tiny_mesh(single, [&](const vec3& x, const PointResult& r, bool exact) {
    const WindingSampleExact ref = winding_number_exact(model.triangle_view(), x, false, false);
    // Exact: float rounding on O(1) values. Tree: the triangle is expanded (order 2) only from
    // beyond 3 radii, where the truncation error of one triangle is far below this bound.
    EXPECT_NEAR(r.w, ref.w, exact ? 1e-5 : 2e-4);
    // The rim is the triangle's three edges.
    double rim = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k)
      rim = std::min(rim, glm::length(closest_point_on_segment(dvec3(single.positions[k]),
                                                               dvec3(single.positions[(k + 1) % 3]), dvec3(x))
                                          .point -
                                      dvec3(x)));
    EXPECT_NEAR(r.boundary_distance, rim, 1e-5);  // float query, O(1) coordinates
  });
}

TEST(ModelBuild, OnlyZeroAreaTrianglesIsAClearError) {
  // Nothing would remain to evaluate: the build says so instead of producing an empty tree.
  Mesh flat;
  flat.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 1}};
  flat.triangles = {{0, 1, 2}, {3, 3, 1}, {2, 2, 2}, {0, 1, 0}};
  GwnModel model;
  const Status s = GwnModel::build(flat, model);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("zero area"), std::string::npos) << s.message();
}

TEST(ModelBuild, ZeroAreaTrianglesAddNothingNearTheirLine) {
  // A cube with a collinear and a repeated-corner triangle lying on its bottom face, queried
  // just above that face: w must be the cube's own value there, up to the tree's accuracy.
  Mesh cube = test::make_cube();
  const GwnModel plain = build_model(cube);
  cube.positions.push_back({0, -1, -1});  // on the edge 0-1
  cube.triangles.push_back({0, uint32_t(cube.positions.size() - 1), 1});
  cube.triangles.push_back({3, 3, 1});  // the segment 3-1 across the bottom face
  const GwnModel with_degenerate = build_model(cube);
  QueryRequest request;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> t(0.05f, 0.95f);
  for (int i = 0; i < 200; ++i) {
    const float s = t(rng);
    // Within 1e-5 of the two degenerate triangles' lines, inside the cube.
    const vec3 on_edge(-1 + 2 * s, -1 + 1e-5f, -1 + 1e-5f);
    const vec3 on_diagonal(-1 + 2 * s, 1 - 2 * s, -1 + 1e-5f);
    for (const vec3& x : {on_edge, on_diagonal}) {
      const float ref = evaluate_point(plain.view(), x, request).w;
      // Same tree accuracy on both models; zero-area triangles must not move w by 1e-3.
      EXPECT_NEAR(evaluate_point(with_degenerate.view(), x, request).w, ref, 1e-3f)
          << "x = (" << x.x << ", " << x.y << ", " << x.z << ")";
    }
  }
}

// ---- BVH structure ----

struct BvhChecker {
  const TriangleTree& tree;
  std::vector<int> leaf_hits;
  std::vector<int> node_hits;
  uint32_t max_depth = 0;
  int ball_violations = 0;
  double max_excess_in_centre_ulps = 0;
  std::string first_violation;

  explicit BvhChecker(const TriangleTree& t)
      : tree(t), leaf_hits(t.triangle_ids.size(), 0), node_hits(t.bvh.nodes.size(), 0) {}

  static bool lane_empty(const WideNode& n, int l) { return n.child[l] == kEmptyLane; }

  // Visits node `index`; returns the leaf-order triangles below it.
  std::vector<uint32_t> visit(uint32_t index, uint32_t depth) {
    max_depth = std::max(max_depth, depth);
    EXPECT_LT(index, tree.bvh.nodes.size());
    if (index >= tree.bvh.nodes.size()) return {};
    ++node_hits[index];
    const WideNode& node = tree.bvh.nodes[index];
    const WideNodeExpansion& ex = tree.expansion[index];
    std::vector<uint32_t> all;
    for (int l = 0; l < kBvhWidth; ++l) {
      if (lane_empty(node, l)) {
        EXPECT_EQ(node.count[l], 0u);
        EXPECT_GT(node.lo[0][l], node.hi[0][l]) << "empty lanes must have inverted boxes";
        continue;
      }
      std::vector<uint32_t> below;
      if (node.count[l] > 0) {
        for (uint32_t i = node.child[l]; i < node.child[l] + node.count[l]; ++i) {
          EXPECT_LT(i, leaf_hits.size());
          if (i < leaf_hits.size()) {
            ++leaf_hits[i];
            below.push_back(i);
          }
        }
      } else {
        below = visit(node.child[l], depth + 1);
        // The inner lane's box holds every lane box of its child.
        if (node.child[l] < tree.bvh.nodes.size()) {
          const WideNode& child = tree.bvh.nodes[node.child[l]];
          for (int c = 0; c < kBvhWidth; ++c) {
            if (lane_empty(child, c)) continue;
            for (int a = 0; a < 3; ++a) {
              EXPECT_LE(node.lo[a][l], child.lo[a][c]);
              EXPECT_GE(node.hi[a][l], child.hi[a][c]);
            }
          }
        }
      }
      EXPECT_FALSE(below.empty());
      const dvec3 centre(ex.centre[0][l], ex.centre[1][l], ex.centre[2][l]);
      const double radius = ex.radius[l];
      double worst = 0;
      for (uint32_t t : below)
        for (int k = 0; k < 3; ++k) {
          const vec3& p = tree.vertices[3 * t + k];
          for (int a = 0; a < 3; ++a) {
            EXPECT_LE(node.lo[a][l], p[a]);
            EXPECT_GE(node.hi[a][l], p[a]);
          }
          worst = std::max(worst, glm::length(dvec3(p) - centre));
        }
      // Ball violations are collected rather than failed here, for their own test.
      if (worst > radius) {
        const float c = std::max({std::abs(ex.centre[0][l]), std::abs(ex.centre[1][l]), std::abs(ex.centre[2][l])});
        const double centre_ulp = double(std::nextafter(c, kInfinity)) - c;
        ++ball_violations;
        max_excess_in_centre_ulps = std::max(max_excess_in_centre_ulps, (worst - radius) / centre_ulp);
        if (first_violation.empty())
          first_violation = "node " + std::to_string(index) + " lane " + std::to_string(l) + ": vertex at " +
                            std::to_string(worst) + " from the centre, radius " + std::to_string(radius);
      }
      all.insert(all.end(), below.begin(), below.end());
    }
    return all;
  }
};

class BvhOnRealMeshes : public ::testing::TestWithParam<const char*> {};

TEST_P(BvhOnRealMeshes, StructureIsSound) {
  const GwnModel model = build_model(load_test_mesh(GetParam()));
  const TriangleTree& tree = model.triangle_tree();
  const Mesh& mesh = model.mesh();
  const size_t n = mesh.triangles.size();
  ASSERT_EQ(tree.triangle_ids.size(), n);
  ASSERT_EQ(tree.vertices.size(), 3 * n);
  ASSERT_EQ(tree.expansion.size(), tree.bvh.nodes.size());
  ASSERT_EQ(tree.order1.size(), tree.bvh.nodes.size());
  ASSERT_EQ(tree.order2.size(), tree.bvh.nodes.size());

  std::vector<uint32_t> ids = tree.triangle_ids;
  std::sort(ids.begin(), ids.end());
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(ids[i], i) << "triangle_ids is not a permutation";
  // Leaf-order vertices are the input triangles' corners.
  for (size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k)
      ASSERT_EQ(tree.vertices[3 * i + k], mesh.positions[mesh.triangles[tree.triangle_ids[i]][k]]);

  BvhChecker check(tree);
  const std::vector<uint32_t> all = check.visit(0, 1);
  EXPECT_EQ(all.size(), n);
  for (size_t i = 0; i < n; ++i) EXPECT_EQ(check.leaf_hits[i], 1) << "leaf-order triangle " << i;
  for (size_t i = 0; i < check.node_hits.size(); ++i) EXPECT_EQ(check.node_hits[i], 1) << "node " << i;
  EXPECT_LE(check.max_depth, tree.bvh.depth);
  EXPECT_LE(tree.bvh.depth, uint32_t(kMaxBvhDepth));

  // The segment tree obeys the same rules on its own primitives.
  const SegmentTree& seg = model.boundary_tree();
  std::vector<uint32_t> sids = seg.segment_ids;
  std::sort(sids.begin(), sids.end());
  for (size_t i = 0; i < sids.size(); ++i) ASSERT_EQ(sids[i], i);
  EXPECT_EQ(sids.size(), model.boundary().segment_count());
}

// filter_triangle_tree (the sheet tree of a mesh that is mostly sheets): the base tree's
// topology over a subset, which must hold exactly the kept triangles, keep the structure's
// rules (boxes, balls, every kept triangle in one leaf) and evaluate the subset's w as a built
// tree does (order 2, beta 2: within the 2e-3 of TaylorOnRealMeshes).
TEST_P(BvhOnRealMeshes, FilteredTreeHoldsExactlyTheKeptTriangles) {
  const GwnModel model = build_model(load_test_mesh(GetParam()));
  const Mesh& mesh = model.mesh();
  const size_t n = mesh.triangles.size();
  std::mt19937 rng(77);
  for (const double fraction : {0.0, 0.002, 0.7, 1.0}) {
    std::vector<uint8_t> keep(n, 0);
    std::vector<uint32_t> kept;
    for (uint32_t t = 0; t < n; ++t)
      if (std::uniform_real_distribution<double>(0.0, 1.0)(rng) < fraction || (fraction > 0 && t == n / 2)) {
        keep[t] = 1;
        kept.push_back(t);
      }
    TriangleTree tree;
    ASSERT_TRUE(filter_triangle_tree(model.triangle_tree(), keep, tree).ok());
    std::vector<uint32_t> ids = tree.triangle_ids;
    std::sort(ids.begin(), ids.end());
    ASSERT_EQ(ids, kept) << "fraction " << fraction;
    if (kept.empty()) {
      EXPECT_EQ(tree.view().triangle_count, 0u);
      continue;
    }
    for (size_t i = 0; i < kept.size(); ++i)
      for (int k = 0; k < 3; ++k)
        ASSERT_EQ(tree.vertices[3 * i + k], mesh.positions[mesh.triangles[tree.triangle_ids[i]][k]]);
    BvhChecker check(tree);
    EXPECT_EQ(check.visit(0, 1).size(), kept.size());
    for (size_t i = 0; i < kept.size(); ++i) EXPECT_EQ(check.leaf_hits[i], 1) << "leaf-order triangle " << i;
    for (size_t i = 0; i < check.node_hits.size(); ++i) EXPECT_LE(check.node_hits[i], 1) << "node " << i;
    EXPECT_EQ(check.ball_violations, 0) << check.first_violation;
    EXPECT_LE(check.max_depth, model.triangle_tree().bvh.depth);
    const TriangleTreeView view = tree.view();
    double max_error = 0;
    for (const vec3& x : sample_points(mesh_bounds(mesh), 200, 5)) {
      const double exact = winding_number_exact(view, x).w;
      max_error =
          std::max(max_error, std::abs(double(winding_number_taylor<2, false, false>(view, x, 2.0f).w) - exact));
    }
    EXPECT_LE(max_error, 2e-3) << "fraction " << fraction;
    // Without moments (the sheet tree): the same triangles and nodes, no expansion arrays.
    TriangleTree bare;
    ASSERT_TRUE(filter_triangle_tree(model.triangle_tree(), keep, bare, TreeMoments::kWithout).ok());
    EXPECT_EQ(bare.triangle_ids, tree.triangle_ids);
    EXPECT_EQ(bare.vertices, tree.vertices);
    EXPECT_EQ(bare.bvh.nodes.size(), tree.bvh.nodes.size());
    EXPECT_TRUE(bare.expansion.empty() && bare.order1.empty() && bare.order2.empty());
  }
}

// The far-field test trusts that no vertex below a lane is farther than radius from centre
// (bvh.h). Checked in double on the stored float centre and radius with no slack, since those
// are exactly the numbers the criterion compares.
TEST_P(BvhOnRealMeshes, ExpansionBallsHoldTheirVertices) {
  const GwnModel model = build_model(load_test_mesh(GetParam()));
  const TriangleTree& tree = model.triangle_tree();
  BvhChecker check(tree);
  check.visit(0, 1);
  EXPECT_EQ(check.ball_violations, 0) << "first: " << check.first_violation << "; worst excess "
                                      << check.max_excess_in_centre_ulps << " ulps of the centre's coordinates";
}

INSTANTIATE_TEST_SUITE_P(Meshes, BvhOnRealMeshes, ::testing::Values("bunny.obj", "dragon_vrip_res4.ply", "teapot.obj"),
                         [](const auto& info) {
                           std::string name = info.param;
                           return name.substr(0, name.find('.'));
                         });

}  // namespace
}  // namespace gwnrt
