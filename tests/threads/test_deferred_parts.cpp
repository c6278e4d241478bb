// A model built with BuildOptions::defer_parts builds M's tree at once and its
// boundary, cone and sheets on first need, once, whatever the number of threads that need them
// at the same moment. Checked against a model built whole (the same mesh, the same options but
// the deferral): every field and every ray must come out bit for bit the same, since the parts
// are the same arrays built by the same code. In an executable of its own so that the
// ThreadSanitizer build (scripts/check.sh tsan) runs it.
#include <gtest/gtest.h>

#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <thread>
#include <vector>

#include "gwnrt/query/batch.h"
#include "test_util.h"

namespace gwnrt {
namespace {
using namespace test;

GwnModel build_with(const Mesh& mesh, bool defer, bool classify_sheets = true) {
  BuildOptions options;
  options.defer_parts = defer;
  options.classify_sheets = classify_sheets;
  GwnModel model;
  const Status s = GwnModel::build(mesh, model, options);
  EXPECT_TRUE(s.ok()) << s.message();
  return model;
}

QueryRequest request_of(uint32_t fields) {
  QueryRequest request;
  request.fields = fields;
  return request;
}

// Bit for bit, so that NaN fields (sdf1/sdf2 where sdf did not need them) compare equal. Field by
// field: the structs have padding.
bool same(float a, float b) { return std::bit_cast<uint32_t>(a) == std::bit_cast<uint32_t>(b); }
bool same(const vec3& a, const vec3& b) { return same(a.x, b.x) && same(a.y, b.y) && same(a.z, b.z); }

bool same_results(const PointResult& a, const PointResult& b) {
  const sym3 &h = a.hessian, &k = b.hessian;
  return same(a.w, b.w) && same(a.gradient, b.gradient) && same(h.xx, k.xx) && same(h.xy, k.xy) && same(h.xz, k.xz) &&
         same(h.yy, k.yy) && same(h.yz, k.yz) && same(h.zz, k.zz) && same(a.unsigned_distance, b.unsigned_distance) &&
         a.nearest_triangle == b.nearest_triangle && same(a.bary_u, b.bary_u) && same(a.bary_v, b.bary_v) &&
         same(a.boundary_distance, b.boundary_distance) && a.nearest_boundary_segment == b.nearest_boundary_segment &&
         same(a.sdf.distance, b.sdf.distance) && same(a.sdf.first_order, b.sdf.first_order) &&
         same(a.sdf.second_order, b.sdf.second_order) && same(a.sdf.sheet_distance, b.sdf.sheet_distance) &&
         a.sdf.sheet_triangle == b.sdf.sheet_triangle && a.sdf.piece == b.sdf.piece &&
         same(a.projection.point, b.projection.point) && a.projection.iterations == b.projection.iterations &&
         a.projection.converged == b.projection.converged && same(a.projection.residual, b.projection.residual) &&
         same(a.harnack_bound, b.harnack_bound);
}

bool same_hits(const RayHit& a, const RayHit& b) {
  return a.hit == b.hit && a.capped == b.capped && a.invalid == b.invalid && a.kind == b.kind && same(a.t, b.t) &&
         same(a.position, b.position) && same(a.normal, b.normal) && a.triangle == b.triangle && a.steps == b.steps &&
         a.crossings == b.crossings;
}

std::vector<Ray> rays_through(const Aabb& box, size_t count) {
  const std::vector<vec3> origins = sample_points(box, count, 7);
  const std::vector<vec3> targets = sample_points(box, count, 8);
  std::vector<Ray> rays(count);
  for (size_t i = 0; i < count; ++i) {
    const vec3 centre = box.centre();
    rays[i].origin = centre + 3.0f * (origins[i] - centre);  // outside, mostly
    rays[i].direction = targets[i] - rays[i].origin;
  }
  return rays;
}

TEST(DeferredParts, OnlyTheTreeIsBuiltUntilAQueryReadsMore) {
  const Mesh mesh = load_test_mesh("bunny_holes.obj");
  const GwnModel model = build_with(mesh, true);
  EXPECT_EQ(model.built_parts(), uint32_t(kPartTriangles));
  EXPECT_EQ(model.timings().boundary_seconds, 0.0);
  EXPECT_EQ(model.timings().sheet_seconds, 0.0);
  const ModelView bare = model.view();
  EXPECT_EQ(bare.parts, uint32_t(kPartTriangles));
  EXPECT_EQ(bare.cone.triangle_count, 0u);  // not built: the view must say so, and the drivers refuse it

  const std::vector<vec3> points = sample_points(mesh_bounds(mesh), 2000, 3);
  std::vector<PointResult> results(points.size());
  // The distance to M and w by the tree read M alone.
  QueryRequest taylor = request_of(kFieldUnsignedDistance | kFieldW | kFieldGradient);
  taylor.method = WindingMethod::kTaylor;
  ASSERT_TRUE(evaluate_points(model, points, taylor, results).ok());
  EXPECT_EQ(model.built_parts(), uint32_t(kPartTriangles));
  // w by auto chooses with the cone's size: the boundary and cone, not the sheets.
  ASSERT_TRUE(evaluate_points(model, points, request_of(kFieldW), results).ok());
  EXPECT_EQ(model.built_parts(), uint32_t(kPartTriangles | kPartBoundary));
  EXPECT_GT(model.timings().boundary_seconds, 0.0);
  EXPECT_GT(model.boundary().segment_count(), 0u);  // bunny_holes is open
  ASSERT_TRUE(evaluate_points(model, points, request_of(kFieldSheetDistance), results).ok());
  EXPECT_EQ(model.built_parts(), uint32_t(kPartTriangles | kPartBoundary | kPartSheets));
  EXPECT_GT(model.timings().sheet_seconds, 0.0);
  EXPECT_EQ(model.view().sheet_level, 0.5f);
}

TEST(DeferredParts, PartsReadByEachField) {
  for (uint32_t bit = 0; bit < 10; ++bit) {
    const uint32_t field = 1u << bit;
    for (WindingMethod method : {WindingMethod::kAuto, WindingMethod::kCrossing, WindingMethod::kTaylor}) {
      QueryRequest request = request_of(field);
      request.method = method;
      const uint32_t parts = parts_read_by(request);
      const bool winding_alone =
          field == kFieldW || field == kFieldGradient || field == kFieldHessian || field == kFieldPseudoDistance;
      const bool needs_boundary =
          field != kFieldUnsignedDistance && !(winding_alone && method == WindingMethod::kTaylor);
      EXPECT_EQ((parts & kPartBoundary) != 0, needs_boundary) << "field bit " << bit << ", method " << int(method);
      EXPECT_EQ((parts & kPartSheets) != 0, (field & kSheetFields) != 0) << "field bit " << bit;
      EXPECT_TRUE(parts & kPartTriangles);
    }
  }
}

// A view without the boundary read as a closed mesh would give w by crossings 0 or 1 where it is
// fractional: the drivers and validate_request refuse it instead.
TEST(DeferredParts, AViewWithoutThePartsARequestReadsIsRefused) {
  const Mesh mesh = load_test_mesh("bunny_holes.obj");
  const GwnModel model = build_with(mesh, true);
  const ModelView bare = model.view();
  const Status w = validate_request(request_of(kFieldW), &bare);
  EXPECT_FALSE(w.ok());
  EXPECT_NE(w.message().find("boundary and cone are not built"), std::string::npos) << w.message();
  EXPECT_FALSE(validate_trace_view(bare).ok());
  EXPECT_TRUE(validate_request(request_of(kFieldUnsignedDistance), &bare).ok());
  const Status sdf = validate_request(request_of(kFieldSignedDistance), &bare);
  EXPECT_FALSE(sdf.ok());
  // Prepared, the same view is whole.
  ASSERT_TRUE(model.prepare(kPartBoundary | kPartSheets).ok());
  const ModelView whole = model.view();
  EXPECT_TRUE(validate_request(request_of(kFieldSignedDistance | kFieldW), &whole).ok());
  EXPECT_TRUE(validate_trace_view(whole).ok());
}

TEST(DeferredParts, WithoutSheetsTheSignedDistanceIsRefusedUntilALevelIsSet) {
  const Mesh mesh = load_test_mesh("bunny_holes.obj");
  const GwnModel eager = build_with(mesh, false);
  GwnModel model = build_with(mesh, true, false);
  const std::vector<vec3> points = sample_points(mesh_bounds(mesh), 500, 4);
  std::vector<PointResult> results(points.size()), expected(points.size());
  const QueryRequest sdf = request_of(kFieldSignedDistance);
  const Status refused = evaluate_points(model, points, sdf, results);
  EXPECT_FALSE(refused.ok());
  EXPECT_NE(refused.message().find("built without them"), std::string::npos) << refused.message();
  EXPECT_EQ(model.built_parts(), uint32_t(kPartTriangles | kPartBoundary));  // asked, so built
  ASSERT_TRUE(model.set_sheet_level(0.5f).ok());
  ASSERT_TRUE(evaluate_points(model, points, sdf, results).ok());
  ASSERT_TRUE(evaluate_points(eager, points, sdf, expected).ok());
  for (size_t i = 0; i < points.size(); ++i) ASSERT_TRUE(same_results(results[i], expected[i])) << "point " << i;
  // set_sheet_level on a model whose boundary was never built builds it first.
  GwnModel bare = build_with(mesh, true, false);
  ASSERT_TRUE(bare.set_sheet_level(0.5f).ok());
  EXPECT_EQ(bare.built_parts(), uint32_t(kPartTriangles | kPartBoundary | kPartSheets));
  ASSERT_TRUE(evaluate_points(bare, points, sdf, results).ok());
  for (size_t i = 0; i < points.size(); ++i) ASSERT_TRUE(same_results(results[i], expected[i])) << "point " << i;
}

TEST(DeferredParts, TheRequestedSheetLevelIsKnownBeforeTheSheetsAreBuilt) {
  const Mesh mesh = load_test_mesh("bunny_holes.obj");
  BuildOptions options;
  options.defer_parts = true;
  options.sheet_level = 0.3f;
  GwnModel model;
  ASSERT_TRUE(GwnModel::build(mesh, model, options).ok());
  EXPECT_TRUE(std::isnan(model.sheet_level()));  // not classified yet
  EXPECT_EQ(model.requested_sheet_level(), 0.3f);
  ASSERT_TRUE(model.prepare(kPartSheets).ok());
  EXPECT_EQ(model.sheet_level(), 0.3f);
  EXPECT_EQ(model.requested_sheet_level(), 0.3f);
  ASSERT_TRUE(model.set_sheet_level(0.6f).ok());
  EXPECT_EQ(model.sheet_level(), 0.6f);
  EXPECT_EQ(model.requested_sheet_level(), 0.6f);
  EXPECT_FALSE(model.set_sheet_level(kInfinity).ok());
  EXPECT_EQ(model.requested_sheet_level(), 0.6f);  // a refused level is not requested
  // Without sheets: none requested until a level is set.
  GwnModel bare = build_with(mesh, true, false);
  EXPECT_TRUE(std::isnan(bare.requested_sheet_level()));
  ASSERT_TRUE(bare.set_sheet_level(0.5f).ok());
  EXPECT_EQ(bare.requested_sheet_level(), 0.5f);
}

// Many threads ask a deferred model at the same moment, each for different parts (the distance
// to M, w, the boundary distance, the sdf, rays); each gets the answers of the model built whole.
TEST(DeferredParts, ManyThreadsAskingAtOnceBuildEachPartOnce) {
  const Mesh mesh = load_test_mesh("bunny_holes.obj");
  const GwnModel eager = build_with(mesh, false);
  const Aabb box = mesh_bounds(mesh);
  const std::vector<vec3> points = sample_points(box, 300, 5);
  const std::vector<Ray> rays = rays_through(box, 64);
  const uint32_t kinds[] = {kFieldUnsignedDistance, kFieldW | kFieldGradient, kFieldBoundaryDistance,
                            kFieldSignedDistance, kFieldSheetDistance | kFieldHarnackBound};
  constexpr size_t kKinds = std::size(kinds);
  std::vector<std::vector<PointResult>> expected(kKinds, std::vector<PointResult>(points.size()));
  for (size_t k = 0; k < kKinds; ++k)
    ASSERT_TRUE(evaluate_points(eager, points, request_of(kinds[k]), expected[k]).ok());
  TraceOptions trace;
  std::vector<RayHit> expected_hits(rays.size());
  ASSERT_TRUE(trace_rays(eager, rays, trace, expected_hits).ok());

  for (int round = 0; round < 3; ++round) {
    const GwnModel model = build_with(mesh, true);
    constexpr int kThreads = 12;
    std::atomic<int> ready{0};
    std::atomic<int> failures{0};
    std::vector<std::thread> threads;
    for (int t = 0; t < kThreads; ++t)
      threads.emplace_back([&, t] {
        ready.fetch_add(1);
        while (ready.load() < kThreads) std::this_thread::yield();  // all ask at once
        if (t % (kKinds + 1) == kKinds) {
          std::vector<RayHit> hits(rays.size());
          if (!trace_rays(model, rays, trace, hits).ok()) failures.fetch_add(1);
          for (size_t i = 0; i < rays.size(); ++i)
            if (!same_hits(hits[i], expected_hits[i])) failures.fetch_add(1);
          return;
        }
        const size_t k = size_t(t) % (kKinds + 1);
        std::vector<PointResult> results(points.size());
        if (!evaluate_points(model, points, request_of(kinds[k]), results).ok()) failures.fetch_add(1);
        for (size_t i = 0; i < points.size(); ++i)
          if (!same_results(results[i], expected[k][i])) failures.fetch_add(1);
      });
    for (std::thread& thread : threads) thread.join();
    EXPECT_EQ(failures.load(), 0) << "round " << round;
    // The rays asked for the tracer's level-free cells too.
    EXPECT_EQ(model.built_parts(), uint32_t(kPartTriangles | kPartBoundary | kPartSheets | kPartLevelFreeCells));
  }
}

// A model moved after a part was built keeps it, and keeps building the others.
TEST(DeferredParts, AMovedModelKeepsWhatItBuilt) {
  const Mesh mesh = load_test_mesh("bunny_holes.obj");
  GwnModel first = build_with(mesh, true);
  ASSERT_TRUE(first.prepare(kPartBoundary).ok());
  GwnModel moved = std::move(first);
  EXPECT_EQ(moved.built_parts(), uint32_t(kPartTriangles | kPartBoundary));
  ASSERT_TRUE(moved.prepare(kPartSheets).ok());
  EXPECT_EQ(moved.built_parts(), uint32_t(kPartTriangles | kPartBoundary | kPartSheets));
  const GwnModel empty;
  EXPECT_EQ(empty.built_parts(), 0u);
  EXPECT_FALSE(empty.prepare(kPartBoundary).ok());
  EXPECT_TRUE(empty.prepare(0).ok());
}

}  // namespace
}  // namespace gwnrt
