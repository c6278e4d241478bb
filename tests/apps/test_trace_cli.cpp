// gwnrt-trace run as a subprocess: on georeferenced input (MeshLoadOptions::recentre) a mesh and
// rays far from the origin are traced about the mesh's own centre, the hit positions written back
// in the input's coordinates; at a level w never reaches every ray misses, and a warning says why.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli_util.h"
#include "gwnrt/io/mesh_io.h"
#include "gwnrt/query/batch.h"
#include "test_util.h"

namespace gwnrt {
namespace {

using test::cell_double;
using test::quote;
using test::RunResult;
using test::temp_path;

// UTM-like: float steps by 0.25 to 0.5 there (y = 4e6), and GwnModel::build refused such meshes.
using test::kUtm;

std::string holes_mesh_path() { return test::data_path("bunny_holes.obj"); }

class TraceCliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    binary_ = test::program_binary("gwnrt-trace");
    if (binary_.empty()) GTEST_SKIP() << "gwnrt-trace not built next to the tests (expected <build>/bin/gwnrt-trace)";
  }
  // The CSV of a run that must succeed, with its header checked.
  std::vector<std::vector<std::string>> trace(const std::string& mesh, const std::string& rays) {
    const RunResult r = test::run_program(binary_, quote(mesh) + " --rays " + quote(rays));
    EXPECT_TRUE(r.exited);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    auto rows = test::csv_rows(r.out);
    EXPECT_FALSE(rows.empty());
    if (!rows.empty()) {
      EXPECT_EQ(rows[0], (std::vector<std::string>{"hit", "t", "px", "py", "pz", "nx", "ny", "nz", "kind", "tri",
                                                   "steps", "crossings", "capped"}));
    }
    return rows;
  }
  std::string binary_;
};

// 4000 rays at bunny_holes.obj (about (0, 4.8, 0), its box 10 x 9.7 x 7.5) from a sphere of
// radius 14 around it, each aimed at a point of the box: about 60% hit, 3% on the caps over the
// holes (smooth pieces), the rest on sheets. Written with 17 significant digits.
std::vector<std::array<double, 6>> write_bunny_rays(const std::string& path) {
  test::Random random(20250117);
  std::vector<std::array<double, 6>> rays;
  std::ofstream out(path);
  out << std::setprecision(17);
  while (rays.size() < 4000) {
    const vec3 u = random.unit();
    const dvec3 o = dvec3(0, 4.8, 0) + 14.0 * dvec3(u);
    const dvec3 target(random.uniform(-5, 5), random.uniform(0, 9.6f), random.uniform(-3.7f, 3.8f));
    const dvec3 d = target - o;
    rays.push_back({o.x, o.y, o.z, d.x, d.y, d.z});
    out << o.x << " " << o.y << " " << o.z << " " << d.x << " " << d.y << " " << d.z << "\n";
  }
  return rays;
}

// The same hits as about the origin, to the float rounding of the inputs: each run rounds the
// mesh's corners and the rays' origins, in its own model coordinates (within s = |o| + 16 of
// its origin: 30 here), to delta = 2^-24 s, and the origin is not the translation, so the two
// models differ by that rounding. Then, the angle between ray and normal theta:
// - hit or miss the same, but for rays that graze the surface (|cos theta| < 0.05 at the hit);
// - the distance along the ray (t |d|, and the hit positions: the untranslated ones + the
//   translation) to 16 delta / |cos theta| (a surface moved by delta along its normal moves the
//   hit by delta / |cos theta| along the ray; observed up to 1e-6 / |cos theta|, 0.55 of the
//   tolerance), and for a hit on a smooth piece also + 2 eps diagonal / |cos theta|, each run
//   stopping within the tracer's eps (1e-5) box diagonals (15.8) of S; not compared for rays
//   within 1.1 degrees of tangent (|cos theta| < 0.02), where that bound is no bound;
// - the normals: on a sheet, its triangle's, turned by the rounding of its corners, 16 delta,
//   over the triangle's least height (0.062 on the bunny): 5e-4, to 1e-3 (observed 5e-6); on a
//   smooth piece grad w / |grad w|, turned by |H| / |grad w| (about 1 / the distance to the
//   holes' rims, where the caps meet the sheets) times the hit's displacement: 1.6e-3 for a hit
//   moved by 1e-6 at 5e-4 from a rim (ray 3197), to 1e-2.
TEST_F(TraceCliTest, FarOffMeshTracesAsTheSameMeshAtTheOrigin) {
  const std::string near_rays = temp_path("rays.txt"), far_rays = temp_path("utm_rays.txt"),
                    far_mesh = temp_path("utm_bunny.obj");
  const std::vector<std::array<double, 6>> rays = write_bunny_rays(near_rays);
  test::write_translated(near_rays, far_rays, kUtm, false);
  test::write_translated(holes_mesh_path(), far_mesh, kUtm, true);
  const auto a = trace(holes_mesh_path(), near_rays), b = trace(far_mesh, far_rays);
  for (const std::string& f : {near_rays, far_rays, far_mesh}) std::remove(f.c_str());
  ASSERT_EQ(a.size(), rays.size() + 1);
  ASSERT_EQ(b.size(), a.size());

  constexpr double kEpsDiagonal = 1e-5 * 15.76;
  size_t hits = 0, smooth = 0, grazing = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    const std::vector<std::string>&r = a[i + 1], &s = b[i + 1];
    ASSERT_EQ(r.size(), 13u);
    ASSERT_EQ(s.size(), 13u);
    const dvec3 d(rays[i][3], rays[i][4], rays[i][5]);
    const auto cos_at = [&](const std::vector<std::string>& row) {
      return std::fabs(glm::dot(dvec3(cell_double(row[5]), cell_double(row[6]), cell_double(row[7])), d)) /
             glm::length(d);
    };
    if (r[0] != s[0]) {
      const double cos_theta = cos_at(r[0] == "1" ? r : s);
      EXPECT_LT(cos_theta, 0.05) << "ray " << i << " hits in one run only, not grazing";
      ++grazing;
      continue;
    }
    if (r[0] == "0") {
      // All but the steps: the rounding moves the faces of the tracer's level-free cells too, and
      // with them where a run of them ends and the Harnack steps resume.
      std::vector<std::string> r_answer = r, s_answer = s;
      r_answer[10] = s_answer[10] = "";
      EXPECT_EQ(s_answer, r_answer) << "ray " << i;
      continue;
    }
    ++hits;
    const bool on_smooth = r[8] == "smooth" || s[8] == "smooth";
    smooth += on_smooth;
    const double cos_theta = cos_at(r);
    const double scale = std::max({std::fabs(rays[i][0]), std::fabs(rays[i][1]), std::fabs(rays[i][2])}) + 16.0;
    const double delta = std::ldexp(scale, -24);
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(cell_double(s[5 + k]), cell_double(r[5 + k]), on_smooth ? 1e-2 : 1e-3)
          << "ray " << i << " normal " << k << " (" << r[8] << ")";
    if (cos_theta < 0.02) continue;
    const double tolerance = (16 * delta + (on_smooth ? 2 * kEpsDiagonal : 0.0)) / cos_theta;
    EXPECT_NEAR(cell_double(s[1]) * glm::length(d), cell_double(r[1]) * glm::length(d), tolerance)
        << "ray " << i << ": t " << s[1] << " vs " << r[1];
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(cell_double(s[2 + k]), cell_double(r[2 + k]) + kUtm[k], tolerance)
          << "ray " << i << " axis " << k << ": " << s[2 + k] << " vs " << r[2 + k] << " + " << kUtm[k];
  }
  EXPECT_GT(hits, rays.size() / 2);
  EXPECT_GT(smooth, 20u);
  EXPECT_LE(grazing, rays.size() / 100);
}

// Exactly the library's hits on the recentred mesh (load_mesh with recentre, the rays' origins
// moved by -origin in double and rounded to float, their directions as read): the hit positions,
// read back in double with the origin subtracted, to the bit (written in double with the digits
// their floats hold), t and the normals as ever.
TEST_F(TraceCliTest, FarOffHitPositionsAreWrittenInTheInputsCoordinates) {
  const std::string near_rays = temp_path("rays.txt"), far_rays = temp_path("utm_rays.txt"),
                    far_mesh = temp_path("utm_bunny.obj");
  const std::vector<std::array<double, 6>> given = write_bunny_rays(near_rays);
  test::write_translated(near_rays, far_rays, kUtm, false);
  test::write_translated(holes_mesh_path(), far_mesh, kUtm, true);
  const auto rows = trace(far_mesh, far_rays);

  Mesh mesh;
  MeshLoadReport report;
  MeshLoadOptions options;
  options.recentre = true;
  ASSERT_TRUE(load_mesh(far_mesh, mesh, &report, options).ok());
  const dvec3 origin = report.origin;
  ASSERT_NE(origin, dvec3(0.0));
  const GwnModel model = test::build_model(std::move(mesh));
  // The rays as the program reads them: an origin in double, moved and rounded to float; a
  // direction straight to float (in double first, one that lies halfway between two floats, as
  // 2.5% of these do, could round to the other).
  std::vector<Ray> rays;
  {
    std::ifstream in(far_rays);
    std::string a[6];
    while (in >> a[0] >> a[1] >> a[2] >> a[3] >> a[4] >> a[5]) {
      Ray ray;
      for (int k = 0; k < 3; ++k) {
        ray.origin[k] = float(cell_double(a[k]) - origin[k]);
        ray.direction[k] = std::strtof(a[3 + k].c_str(), nullptr);
      }
      rays.push_back(ray);
    }
  }
  for (const std::string& f : {near_rays, far_rays, far_mesh}) std::remove(f.c_str());
  ASSERT_EQ(rays.size(), given.size());
  std::vector<RayHit> hits(rays.size());
  ASSERT_TRUE(trace_rays(model, rays, TraceOptions{}, hits).ok());

  ASSERT_EQ(rows.size(), rays.size() + 1);
  size_t hit_count = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    const std::vector<std::string>& row = rows[i + 1];
    ASSERT_EQ(row.size(), 13u);
    ASSERT_EQ(row[0], hits[i].hit ? "1" : "0") << "ray " << i;
    if (!hits[i].hit) continue;
    ++hit_count;
    EXPECT_EQ(float(cell_double(row[1])), hits[i].t) << "ray " << i;
    for (int k = 0; k < 3; ++k) {
      test::expect_position_reads_back(row[2 + k], origin[k], hits[i].position[k]);
      EXPECT_EQ(float(cell_double(row[5 + k])), hits[i].normal[k]) << "ray " << i;
    }
  }
  EXPECT_GT(hit_count, rays.size() / 2);
}

// A far-off mesh GwnModel::build refused ("translate the mesh near the origin": a unit
// tetrahedron at UTM-like coordinates, its box 4e-7 of its largest coordinate) is traced: a ray
// along x from 2 in front of the face x = 0 hits it at t = 2, where it points, in the file's
// coordinates; one that passes beside misses.
TEST_F(TraceCliTest, MeshThatWasRefusedAsFarOffIsTraced) {
  const std::string mesh = temp_path("utm_tet.obj"), rays = temp_path("utm_tet_rays.txt");
  test::write_far_tetrahedron(mesh);
  {
    std::ofstream r(rays);
    r << "512343.678 4123457.039 123.5 1 0 0\n512343.678 4123458.039 123.5 1 0 0\n";
  }
  const auto rows = trace(mesh, rays);
  std::remove(mesh.c_str());
  std::remove(rays.c_str());
  ASSERT_EQ(rows.size(), 3u);
  ASSERT_EQ(rows[1].size(), 13u);
  EXPECT_EQ(rows[1][0], "1");
  // t and the position to the rounding of the tetrahedron's coordinates about its origin (6e-8).
  EXPECT_NEAR(cell_double(rows[1][1]), 2.0, 1e-6);
  EXPECT_NEAR(cell_double(rows[1][2]), kUtm[0], 1e-6);
  EXPECT_NEAR(cell_double(rows[1][3]), kUtm[1] + 0.25, 1e-6);
  EXPECT_NEAR(cell_double(rows[1][4]), kUtm[2] + 0.25, 1e-6);
  EXPECT_EQ(rows[1][5] + "," + rows[1][6] + "," + rows[1][7], "-1,0,0");
  EXPECT_EQ(rows[2][0], "0");
}

TEST(UnreachableLevelCli, TraceSaysTheSurfaceIsEmpty) {
  // gwnrt-trace at a level of 3e9: every ray misses (no sheet hit with a flipped normal)
  // and a warning says why.
  const std::string binary = test::program_binary("gwnrt-trace");
  if (binary.empty()) GTEST_SKIP() << "gwnrt-trace not built next to the tests";
  const std::string rays = test::temp_path("rays") + ".txt";
  std::ofstream(rays) << "-1 0.1 0.05 1 0 0\n0.05 -1 0.1 0 1 0\n";
  for (const std::string level : {"3e9", "-3e9", "1e30"}) {
    const test::RunResult run = test::run_program(
        binary, test::quote(test::data_path("bunny_holes.obj")) + " --rays " + test::quote(rays) + " --level " + level);
    ASSERT_TRUE(run.exited) << level;
    EXPECT_EQ(run.exit_code, 0) << run.err;
    EXPECT_NE(run.err.find("outside every value w takes"), std::string::npos) << run.err;
    EXPECT_EQ(run.out.find(",sheet,"), std::string::npos) << run.out;
  }
}

}  // namespace
}  // namespace gwnrt
