// The mesh readers in process on generated hostile files (mesh_mutations.h): each must load or
// refuse every mutation with an error Status naming the file, short and printable; a mesh that
// loads is built, queried and traced, none of which may crash. CI also runs it under ASan +
// UBSan (scripts/check.sh sanitize), where a report fails it.
#include <cctype>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "gwnrt/io/mesh_io.h"
#include "gwnrt/model/model.h"
#include "gwnrt/query/batch.h"
#include "mesh_mutations.h"

namespace gwnrt {
namespace {

// A message a user can read: starts with the file, short, printable (tokens from the file are
// quoted and cut, never copied raw).
void expect_readable_error(const Status& s, const std::string& path, const std::string& recipe) {
  EXPECT_EQ(s.message().rfind(path, 0), 0u) << recipe << ": the message should start with the path: " << s.message();
  EXPECT_LT(s.message().size(), path.size() + 300) << recipe << ": " << s.message();
  for (const char c : s.message())
    EXPECT_TRUE(static_cast<unsigned char>(c) >= 0x20 && c != 0x7f) << recipe << ": unprintable byte in the message";
}

// Builds the model of a mesh that loaded, queries every field by every method at points inside,
// on, near and far from it, and traces rays through it: none may crash (the values themselves are
// the accuracy tests' business).
void exercise_model(Mesh mesh, const std::string& recipe) {
  GwnModel model;
  const Status built = GwnModel::build(std::move(mesh), model);
  if (!built.ok()) {
    EXPECT_FALSE(built.message().empty()) << recipe;
    return;
  }
  const Aabb box = model.bounds();
  const vec3 centre = box.centre(), size = box.hi - box.lo;
  const std::vector<vec3> points = {
      centre,
      box.lo,
      box.hi,
      model.mesh().positions[model.mesh().triangles[0].x],
      (model.mesh().positions[model.mesh().triangles[0].x] + model.mesh().positions[model.mesh().triangles[0].y]) *
          0.5f,
      centre + 1e3f * size,
      vec3(0.0f)};
  std::vector<PointResult> results(points.size());
  for (const WindingMethod method :
       {WindingMethod::kAuto, WindingMethod::kCrossing, WindingMethod::kTaylor, WindingMethod::kBrute}) {
    QueryRequest request;
    request.method = method;
    request.fields = kFieldW | kFieldGradient | kFieldHessian | kFieldUnsignedDistance | kFieldBoundaryDistance |
                     kFieldSignedDistance | kFieldPseudoDistance | kFieldSheetDistance | kFieldProjection |
                     kFieldHarnackBound;
    const Status s = evaluate_points(model, points, request, results);
    EXPECT_TRUE(s.ok() || !s.message().empty()) << recipe;
  }
  std::vector<Ray> rays;
  for (const vec3& from : {box.lo - size, box.hi + size, centre}) {
    Ray r;
    r.origin = from;
    r.direction = from == centre ? vec3(0, 0, 1) : centre - from;
    if (r.direction == vec3(0.0f)) r.direction = vec3(1, 0, 0);
    rays.push_back(r);
  }
  std::vector<RayHit> hits(rays.size());
  for (const TraceMode mode : {TraceMode::kWindingNumber, TraceMode::kSolidAngle}) {
    TraceOptions options;
    options.mode = mode;
    options.max_steps = 256;
    const Status s = trace_rays(model, rays, options, hits);
    EXPECT_TRUE(s.ok() || !s.message().empty()) << recipe;
  }
}

TEST_F(FuzzDir, MeshReadersRefuseOrLoadEveryMutation) {
  size_t loaded = 0, refused = 0;
  for (const Generated& g : generate(8)) {
    SCOPED_TRACE(g.recipe);
    const std::string path = write("input" + g.ext, g.bytes);
    Mesh mesh;
    MeshLoadReport report;
    Status s;
    EXPECT_NO_THROW(s = load_mesh(path, mesh, &report));
    if (!s.ok()) {
      ++refused;
      expect_readable_error(s, path, g.recipe);
      // Every OBJ syntax error names its line ("path:N: ..."); PLY ones name the line or element.
      if (g.ext == ".obj" && s.code() == StatusCode::kParseError) {
        const std::string& m = s.message();
        const bool line = m.size() > path.size() + 1 && m[path.size()] == ':' &&
                          std::isdigit(static_cast<unsigned char>(m[path.size() + 1]));
        EXPECT_TRUE(line) << g.recipe << ": " << m;
      }
      continue;
    }
    ++loaded;
    ASSERT_TRUE(validate_mesh(mesh).ok()) << g.recipe;
    EXPECT_EQ(report.triangle_count, mesh.triangles.size()) << g.recipe;
    exercise_model(std::move(mesh), g.recipe);
  }
  // Both outcomes occur (the mutations are neither all fatal nor all harmless).
  EXPECT_GT(loaded, 50u);
  EXPECT_GT(refused, 200u);
}

}  // namespace
}  // namespace gwnrt
