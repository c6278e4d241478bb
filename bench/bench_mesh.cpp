// gwnrt-bench-mesh: gwnrt's mesher of S = ∂{w > 0.5} (dual contouring and marching cubes; a
// method the library answers kUnavailable for is an n/a row) against OpenVDB's mesh ->
// narrow-band level set -> mesh on the same cell size, measured in the same run: time, triangles,
// and the quality report's topology, self-intersections and distances to S (mesh_quality.h).
// OpenVDB meshes the input triangles, not S: on a closed input the two agree, on one with holes
// its flood-filled sign is what it is.
//
// With no meshes given it runs bunny.obj and bunny_holes.obj from data/, and the 202k-triangle
// dragon when /tmp/dragon_vrip_res2.ply exists (make it with
// `gunzip -c ../shared/meshes/dragon_vrip_res2.ply.gz > /tmp/dragon_vrip_res2.ply`).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#if defined(GWNRT_HAVE_OPENVDB)
#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/VolumeToMesh.h>
#endif

#include "apps/common/cli_checks.h"
#include "apps/common/load_model.h"
#include "apps/common/program.h"
#include "gwnrt/base/memory.h"
#include "gwnrt/geometry/exact_predicates.h"
#include "gwnrt/geometry/ray.h"
#include "gwnrt/meshing/extract_surface.h"
#include "gwnrt/meshing/mesh_quality.h"

namespace {

using namespace gwnrt;
using apps::seconds_since;
using clock_type = std::chrono::steady_clock;

constexpr const char* kProgram = "gwnrt-bench-mesh";
constexpr const char* kDragon = "/tmp/dragon_vrip_res2.ply";

enum class Outcome { kOk, kUnavailable, kError };

// One (method, resolution) of one mesh: its output's measurements.
struct Row {
  std::string method;  // "gwnrt DC", "gwnrt MC", "OpenVDB"
  uint32_t resolution = 0;
  Outcome outcome = Outcome::kOk;
  std::string message;  // why n/a, or the error
  double seconds = NAN;
  std::vector<double> round_seconds;                      // each round's, when they were timed (add_rounds)
  double level_set_seconds = NAN, to_mesh_seconds = NAN;  // OpenVDB's two steps
  uint64_t quads = 0, openvdb_triangles = 0;              // OpenVDB's output before the split
  uint64_t quads_split_other_way = 0;                     // along (1, 3): see run_openvdb
  uint64_t triangles = 0;
  double cell_size = NAN;
  double volume = NAN;  // enclosed (signed): positive when oriented outward
  MeshTopology topology;
  bool self_checked = false;
  uint64_t self_intersections = 0;
  SurfaceDistances distances;
  double ratio_to_openvdb = NAN;  // seconds / OpenVDB's seconds at the same resolution
  // Seconds per output triangle over the first mesh's (gwnrt DC at the same resolution): what
  // the mess of an input costs beyond the surface it gives.
  double ratio_per_triangle = NAN;
  bool ok() const { return outcome == Outcome::kOk; }
};

struct MeshSummary {
  std::string path;
  uint64_t triangles = 0;
  uint64_t boundary_segments = 0;
  double load_seconds = 0, build_seconds = 0;
  std::vector<Row> rows;
};

struct Settings {
  uint32_t samples = 50000;
  bool self_intersections = true;
  uint32_t rounds = 1;  // timings per method, interleaved; the rows hold their medians
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n == 0 ? NAN : (n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]));
}

// Sum of the signed tetrahedra from the origin: the volume a closed mesh encloses, negative when
// its triangles are clockwise seen from outside (how OpenVDB's winding is checked below).
double signed_volume(const SurfaceMesh& mesh) {
  double v = 0;
  for (const uvec3& t : mesh.triangles) {
    const glm::dvec3 a(mesh.positions[t.x]), b(mesh.positions[t.y]), c(mesh.positions[t.z]);
    v += glm::dot(a, glm::cross(b, c));
  }
  return v / 6.0;
}

// The quality report's parts one by one, so that the self-intersection count (the slow one on a
// big output) can be left out.
Status measure(const GwnModel& model, const SurfaceMesh& mesh, const Settings& settings, Row& row) {
  row.triangles = mesh.triangles.size();
  row.volume = signed_volume(mesh);
  if (Status s = mesh_topology(mesh, row.topology); !s.ok()) return s;
  if (settings.self_intersections) {
    if (Status s = count_self_intersections(mesh, row.self_intersections); !s.ok()) return s;
    row.self_checked = true;
  }
  SurfaceDistanceOptions options;
  options.output_samples = settings.samples;
  options.surface_rays = settings.samples;
  return surface_distances(model, mesh, options, row.distances);
}

MeshingOptions gwnrt_options(MeshingMethod method, uint32_t resolution) {
  MeshingOptions options;
  options.resolution = resolution;
  options.method = method;
  // Refused with what it would need, rather than killed, beyond the memory available.
  options.memory_budget = std::min(options.memory_budget, available_memory_bytes());
  return options;
}

// The seconds of one more meshing (a round after the first), or NaN where it fails.
double gwnrt_seconds(const GwnModel& model, MeshingMethod method, uint32_t resolution) {
  SurfaceMesh out;
  const auto t0 = clock_type::now();
  const Status s = extract_surface(model, gwnrt_options(method, resolution), out, nullptr);
  return s.ok() ? seconds_since(t0) : NAN;
}

Row run_gwnrt(const GwnModel& model, MeshingMethod method, uint32_t resolution, const Settings& settings) {
  Row row;
  row.method = method == MeshingMethod::kDualContouring ? "gwnrt DC" : "gwnrt MC";
  row.resolution = resolution;
  SurfaceMesh out;
  MeshingStats stats;
  const auto t0 = clock_type::now();
  const Status s = extract_surface(model, gwnrt_options(method, resolution), out, &stats);
  row.seconds = seconds_since(t0);
  if (!s.ok()) {
    // A method the library does not have (yet): a gap in the table, not a failure.
    row.outcome = s.code() == StatusCode::kUnavailable ? Outcome::kUnavailable : Outcome::kError;
    row.message = s.message();
    row.seconds = NAN;
    return row;
  }
  row.cell_size = stats.cell_size;
  if (!stats.message.empty()) row.message = stats.message;
  if (Status q = measure(model, out, settings, row); !q.ok()) {
    row.outcome = Outcome::kError;
    row.message = "quality report: " + q.message();
  }
  return row;
}

#if defined(GWNRT_HAVE_OPENVDB)
// OpenVDB's polygons are clockwise seen from outside (measured: the closed bunny's volume comes
// out negative as they are), the opposite of SurfaceMesh's convention: each is reversed.
constexpr bool kReverseOpenVdbWinding = true;

// The input in OpenVDB's types, made outside the timing (as the gwnrt model's build is).
struct OpenVdbInput {
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
  explicit OpenVdbInput(const GwnModel& model) {
    const Mesh& input = model.mesh();
    points.resize(input.positions.size());
    triangles.resize(input.triangles.size());
    for (size_t i = 0; i < points.size(); ++i)
      points[i] = openvdb::Vec3s(input.positions[i].x, input.positions[i].y, input.positions[i].z);
    for (size_t i = 0; i < triangles.size(); ++i)
      triangles[i] = openvdb::Vec3I(input.triangles[i].x, input.triangles[i].y, input.triangles[i].z);
  }
};

// OpenVDB's mesh -> level set -> mesh, timed in its two steps; throws what OpenVDB throws.
void openvdb_mesh(const OpenVdbInput& input, double cell_size, std::vector<openvdb::Vec3s>& points,
                  std::vector<openvdb::Vec3I>& triangles, std::vector<openvdb::Vec4I>& quads, double& level_set_seconds,
                  double& to_mesh_seconds) {
  const auto transform = openvdb::math::Transform::createLinearTransform(cell_size);
  const auto t0 = clock_type::now();
  const openvdb::FloatGrid::Ptr grid =
      openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*transform, input.points, input.triangles, 3.0f);
  level_set_seconds = seconds_since(t0);
  const auto t1 = clock_type::now();
  openvdb::tools::volumeToMesh(*grid, points, triangles, quads, 0.0, 0.0);
  to_mesh_seconds = seconds_since(t1);
}

// One more round of OpenVDB (a round after the first): its two steps' seconds, NaN where it fails.
void openvdb_seconds(const GwnModel& model, double cell_size, double& level_set_seconds, double& to_mesh_seconds) {
  level_set_seconds = to_mesh_seconds = NAN;
  try {
    const OpenVdbInput input(model);
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    std::vector<openvdb::Vec4I> quads;
    openvdb_mesh(input, cell_size, points, triangles, quads, level_set_seconds, to_mesh_seconds);
  } catch (...) {
    level_set_seconds = to_mesh_seconds = NAN;
  }
}

Row run_openvdb(const GwnModel& model, uint32_t resolution, double cell_size, const Settings& settings) {
  Row row;
  row.method = "OpenVDB";
  row.resolution = resolution;
  row.cell_size = cell_size;
  if (!(cell_size > 0)) {
    row.outcome = Outcome::kError;
    row.message = "no cell size to match (gwnrt failed at this resolution)";
    return row;
  }
  SurfaceMesh out;
  try {
    const OpenVdbInput input(model);
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    std::vector<openvdb::Vec4I> quads;
    openvdb_mesh(input, cell_size, points, triangles, quads, row.level_set_seconds, row.to_mesh_seconds);
    row.seconds = row.level_set_seconds + row.to_mesh_seconds;
    row.quads = quads.size();
    row.openvdb_triangles = triangles.size();

    out.positions.resize(points.size());
    for (size_t i = 0; i < points.size(); ++i) out.positions[i] = vec3(points[i].x(), points[i].y(), points[i].z());
    out.triangles.reserve(triangles.size() + 2 * quads.size());
    auto add = [&](uint32_t a, uint32_t b, uint32_t c) {
      out.triangles.push_back(kReverseOpenVdbWinding ? uvec3(a, c, b) : uvec3(a, b, c));
    };
    for (const openvdb::Vec3I& t : triangles) add(t[0], t[1], t[2]);
    // Along the diagonal (0, 2), as OpenVDB's own consumers split its quads, unless that makes a
    // zero-area triangle (three corners on a line: the topology counts it as a defect) and the
    // other diagonal does not: a flaw of the split is not OpenVDB's.
    auto flat = [&](uint32_t a, uint32_t b, uint32_t c) {
      return exact::collinear(out.positions[a], out.positions[b], out.positions[c]);
    };
    for (const openvdb::Vec4I& q : quads) {
      if ((flat(q[0], q[1], q[2]) || flat(q[0], q[2], q[3])) && !flat(q[1], q[2], q[3]) && !flat(q[1], q[3], q[0])) {
        add(q[1], q[2], q[3]);
        add(q[1], q[3], q[0]);
        ++row.quads_split_other_way;
      } else {
        add(q[0], q[1], q[2]);
        add(q[0], q[2], q[3]);
      }
    }
  } catch (const std::exception& e) {
    row.outcome = Outcome::kError;
    row.message = std::string("OpenVDB: ") + e.what();
    return row;
  } catch (...) {
    row.outcome = Outcome::kError;
    row.message = "OpenVDB: unknown exception";
    return row;
  }
  if (Status q = measure(model, out, settings, row); !q.ok()) {
    row.outcome = Outcome::kError;
    row.message = "quality report: " + q.message();
  }
  return row;
}
#endif

const Row* find_row(const std::vector<Row>& rows, const std::string& method, uint32_t resolution) {
  for (const Row& r : rows)
    if (r.method == method && r.resolution == resolution && r.ok()) return &r;
  return nullptr;
}

// Rounds 2 to `rounds` of the rows of this resolution that succeeded, interleaved (DC, MC,
// OpenVDB, DC, ...), so that the machine's load falls on each alike; each row's seconds become
// the median of its rounds (a failed round is left out).
void add_rounds(const GwnModel& model, uint32_t resolution, uint32_t rounds, std::vector<Row>& rows) {
  struct Timed {
    Row* row;
    std::vector<double> seconds, level_set, to_mesh;
  };
  std::vector<Timed> timed;
  for (Row& r : rows)
    if (r.resolution == resolution && r.ok())
      timed.push_back({&r, {r.seconds}, {r.level_set_seconds}, {r.to_mesh_seconds}});
  for (uint32_t round = 1; round < rounds; ++round)
    for (Timed& t : timed) {
      if (t.row->method == "OpenVDB") {
#if defined(GWNRT_HAVE_OPENVDB)
        double level_set = NAN, to_mesh = NAN;
        openvdb_seconds(model, t.row->cell_size, level_set, to_mesh);
        if (std::isnan(level_set)) continue;
        t.level_set.push_back(level_set);
        t.to_mesh.push_back(to_mesh);
        t.seconds.push_back(level_set + to_mesh);
#endif
      } else {
        const MeshingMethod method =
            t.row->method == "gwnrt DC" ? MeshingMethod::kDualContouring : MeshingMethod::kMarchingCubes;
        if (const double s = gwnrt_seconds(model, method, resolution); !std::isnan(s)) t.seconds.push_back(s);
      }
    }
  for (Timed& t : timed) {
    t.row->round_seconds = t.seconds;
    t.row->seconds = median(t.seconds);
    t.row->level_set_seconds = median(t.level_set);
    t.row->to_mesh_seconds = median(t.to_mesh);
  }
}

std::string count_text(uint64_t n) { return std::to_string(n); }

void print_table(const MeshSummary& m) {
  std::printf("\n%-8s %5s %9s %7s %7s %9s %6s %6s %6s %6s %10s %10s %10s %10s %7s %7s %7s\n", "method", "res",
              "seconds", "x vdb", "x 1st/t", "tris", "closed", "bound", "nonman", "selfx", "cell", "chamfer", "H out>S",
              "H S>out", "ch/h", "Ho/h", "Hs/h");
  for (const Row& r : m.rows) {
    if (!r.ok()) {
      std::printf("%-8s %5u %9s   %s: %s\n", r.method.c_str(), r.resolution, "n/a",
                  r.outcome == Outcome::kUnavailable ? "unavailable" : "error", r.message.c_str());
      continue;
    }
    const double h = r.cell_size;
    const SurfaceDistances& d = r.distances;
    char ratio[32] = "";
    if (!std::isnan(r.ratio_to_openvdb)) std::snprintf(ratio, sizeof ratio, "%.3f", r.ratio_to_openvdb);
    char per_triangle[32] = "";
    if (!std::isnan(r.ratio_per_triangle))
      std::snprintf(per_triangle, sizeof per_triangle, "%.2f", r.ratio_per_triangle);
    std::printf("%-8s %5u %9.3f %7s %7s %9llu %6s %6llu %6llu %6s %10.4g %10.4g %10.4g %10.4g %7.3f %7.3f %7.3f\n",
                r.method.c_str(), r.resolution, r.seconds, ratio, per_triangle, (unsigned long long)r.triangles,
                r.topology.closed_manifold() ? "yes" : "no", (unsigned long long)r.topology.boundary_edges,
                (unsigned long long)r.topology.non_manifold_edges,
                r.self_checked ? count_text(r.self_intersections).c_str() : "-", h, d.chamfer, d.hausdorff_to_surface,
                d.hausdorff_from_surface, d.chamfer / h, d.hausdorff_to_surface / h, d.hausdorff_from_surface / h);
  }
  // The details that do not fit the table: OpenVDB's two steps and raw output, orientation checks.
  for (const Row& r : m.rows) {
    if (!r.ok()) continue;
    if (r.method == "OpenVDB")
      std::printf(
          "  OpenVDB %u: level set %.3f s + to mesh %.3f s; %llu quads (%llu split along 1-3), %llu triangles; "
          "volume %.6g\n",
          r.resolution, r.level_set_seconds, r.to_mesh_seconds, (unsigned long long)r.quads,
          (unsigned long long)r.quads_split_other_way, (unsigned long long)r.openvdb_triangles, r.volume);
    const MeshTopology& t = r.topology;
    if (!t.closed_manifold())
      std::printf(
          "  %s %u is not a closed manifold: %llu boundary edges, %llu non-manifold edges, %llu non-manifold "
          "vertices, %llu inconsistent edges, %llu degenerate triangles\n",
          r.method.c_str(), r.resolution, (unsigned long long)t.boundary_edges,
          (unsigned long long)t.non_manifold_edges, (unsigned long long)t.non_manifold_vertices,
          (unsigned long long)t.inconsistent_edges, (unsigned long long)t.degenerate_triangles);
    if (r.triangles > 0 && t.closed_manifold() && !(r.volume > 0))
      std::printf("  warning: %s %u encloses a volume of %.6g: oriented inward\n", r.method.c_str(), r.resolution,
                  r.volume);
    if (!r.message.empty()) std::printf("  %s %u: %s\n", r.method.c_str(), r.resolution, r.message.c_str());
  }
#if defined(GWNRT_HAVE_OPENVDB)
  // meshToLevelSet signs its band by flood fill from outside, which an open input leaks through:
  // its surface is then not S, and its time is no baseline for the quality gwnrt delivers.
  if (m.boundary_segments > 0)
    std::printf(
        "  note: the input is open (%llu boundary segments): OpenVDB's inside is its flood fill's guess, not "
        "{w > 0.5}\n",
        (unsigned long long)m.boundary_segments);
#endif
}

// gwnrt DC's time at each resolution over the one at half of it: 4 where the cost follows the area of
// S (the sparse grid's promise), 8 where it followed the volume.
struct DoublingRatio {
  uint32_t resolution, half;
  double ratio;
};
std::vector<DoublingRatio> doubling_ratios(const MeshSummary& m, const std::vector<uint32_t>& resolutions) {
  std::vector<DoublingRatio> out;
  for (uint32_t r : resolutions) {
    const Row* hi = find_row(m.rows, "gwnrt DC", r);
    const Row* lo = (r % 2 == 0) ? find_row(m.rows, "gwnrt DC", r / 2) : nullptr;
    if (hi && lo) out.push_back({r, r / 2, hi->seconds / lo->seconds});
  }
  return out;
}

nlohmann::json number_or_null(double v) { return std::isnan(v) ? nlohmann::json() : nlohmann::json(v); }

nlohmann::json row_json(const std::string& mesh, const Row& r) {
  const bool ok = r.ok();
  nlohmann::json j = {
      {"mesh", mesh},
      {"method", r.method},
      {"resolution", r.resolution},
      {"status", ok                                   ? "ok"
                 : r.outcome == Outcome::kUnavailable ? "unavailable"
                                                      : "error"},
      {"seconds", number_or_null(r.seconds)},
      {"round_seconds", r.round_seconds},
      {"triangles", ok ? nlohmann::json(r.triangles) : nlohmann::json()},
      {"closed_manifold", ok ? nlohmann::json(r.topology.closed_manifold()) : nlohmann::json()},
      {"boundary_edges", ok ? nlohmann::json(r.topology.boundary_edges) : nlohmann::json()},
      {"non_manifold_edges", ok ? nlohmann::json(r.topology.non_manifold_edges) : nlohmann::json()},
      {"non_manifold_vertices", ok ? nlohmann::json(r.topology.non_manifold_vertices) : nlohmann::json()},
      {"inconsistent_edges", ok ? nlohmann::json(r.topology.inconsistent_edges) : nlohmann::json()},
      {"degenerate_triangles", ok ? nlohmann::json(r.topology.degenerate_triangles) : nlohmann::json()},
      {"self_intersections", ok && r.self_checked ? nlohmann::json(r.self_intersections) : nlohmann::json()},
      {"chamfer", ok ? nlohmann::json(r.distances.chamfer) : nlohmann::json()},
      {"hausdorff_to_surface", ok ? nlohmann::json(r.distances.hausdorff_to_surface) : nlohmann::json()},
      {"hausdorff_from_surface", ok ? nlohmann::json(r.distances.hausdorff_from_surface) : nlohmann::json()},
      {"cell_size", number_or_null(r.cell_size)},
      {"ratio_to_openvdb", number_or_null(r.ratio_to_openvdb)},
      {"per_triangle_over_first_mesh", number_or_null(r.ratio_per_triangle)},
      {"volume", ok ? number_or_null(r.volume) : nlohmann::json()}};
  if (!r.message.empty()) j["message"] = r.message;
  if (r.method == "OpenVDB" && ok) {
    j["level_set_seconds"] = r.level_set_seconds;
    j["to_mesh_seconds"] = r.to_mesh_seconds;
    j["quads"] = r.quads;
    j["openvdb_triangles"] = r.openvdb_triangles;
    j["quads_split_other_way"] = r.quads_split_other_way;
  }
  return j;
}

}  // namespace

int main(int argc, char** argv) try {
  CLI::App app{
      "Meshing S = ∂{w > 0.5}: gwnrt's dual contouring (and marching cubes) against OpenVDB's "
      "mesh -> level set -> mesh at the same cell size: time, triangles, topology, "
      "self-intersections, distances to S",
      kProgram};
  std::vector<std::string> meshes;
  std::vector<uint32_t> resolutions = {128, 256, 512};
  int threads = 0;
  Settings settings;
  bool no_self = false;
  std::string json_path;
  app.add_option("meshes", meshes,
                 std::string("OBJ, PLY or STL meshes (default: bunny.obj and bunny_holes.obj from data/, and ") +
                     kDragon + " when it exists)");
  app.add_option("--resolutions", resolutions, "cells along the longest side of S's box, comma-separated")
      ->delimiter(',')
      ->check(CLI::Range(1u, 1u << 16))
      ->capture_default_str();
  app.add_option("--threads", threads, "worker threads (default: all cores)")->check(gwnrt::apps::thread_count());
  app.add_option("--samples", settings.samples, "output samples and rays on S of the distance measurements")
      ->check(CLI::Range(1u, 1u << 30))
      ->capture_default_str();
  app.add_flag("--no-self-intersections", no_self, "skip the self-intersection count (slow on big outputs)");
  app.add_option("--rounds", settings.rounds,
                 "time each method this many times, interleaved, and report the medians (the quality columns are "
                 "the first round's)")
      ->check(CLI::Range(1u, 100u))
      ->capture_default_str();
  bool real = false;
  app.add_flag("--real", real,
               "after the meshes, the real ones: data/realworld, and ../shared/meshes/realworld's larger ones when "
               "present");
  app.add_option("--json", json_path, "also write every row and the model build times to this JSON file");
  if (const auto status = apps::parse_command_line(app, argc, argv)) return *status;
  settings.self_intersections = !no_self;
  {
    // The distance measurements' arrays per sample (mesh_quality.h): a point on the output and its
    // distance, a ray, its list of hits and at least one hit (a position and a normal).
    const uint64_t per_sample =
        sizeof(vec3) + sizeof(float) + sizeof(Ray) + sizeof(std::vector<vec3>) + 2 * sizeof(vec3);
    if (Status s = check_memory(saturating_product(settings.samples, per_sample),
                                "--samples " + std::to_string(settings.samples));
        !s.ok())
      return apps::fail(kProgram, s.message());
  }

  if (meshes.empty()) {
    for (const char* name : {"bunny.obj", "bunny_holes.obj"})
      meshes.push_back(std::string(GWNRT_DATA_DIR) + "/" + name);
    if (std::filesystem::exists(kDragon))
      meshes.push_back(kDragon);
    else
      std::printf(
          "note: %s is missing, so the dragon is left out (make it with `gunzip -c "
          "../shared/meshes/dragon_vrip_res2.ply.gz > %s`)\n",
          kDragon, kDragon);
  }
  if (real) {
    // A scan with holes, STL soups of CAD parts, an assembly, an inside-out shell, seams, colours.
    for (const char* name : {"birdBath_ggg_photogrammetry.obj", "kuka_kr10r1100sixx_visual_base_link.stl",
                             "kuka_kr150r3100_2_visual_base_link.stl", "motoman_motomini_visual_link_1_s.stl",
                             "spot_triangulated.obj", "dolphins_colored.ply"})
      meshes.push_back(std::string(GWNRT_DATA_DIR) + "/realworld/" + name);
    const std::string shared =
        std::string(GWNRT_DATA_DIR) + "/../../shared/meshes/realworld/abb_irb6640_visual_link_3.stl";
    if (std::filesystem::exists(shared)) meshes.push_back(shared);
  }
  if (const std::string bad = apps::first_bad_input_file(meshes); !bad.empty()) return apps::fail(kProgram, bad);

  const apps::ThreadLimit limit(threads);
  const int workers = int(limit.workers());
  std::printf("%s: %d threads, %u distance samples, self-intersections %s, seconds: %s\n", kProgram, workers,
              settings.samples, settings.self_intersections ? "counted" : "not counted",
              settings.rounds > 1 ? ("medians of " + std::to_string(settings.rounds) + " interleaved rounds").c_str()
                                  : "one round");
#if defined(GWNRT_HAVE_OPENVDB)
  openvdb::initialize();
  std::printf(
      "OpenVDB %s: meshToLevelSet (half width 3) + volumeToMesh (isovalue 0, adaptivity 0) at gwnrt's cell size\n",
      openvdb::getLibraryVersionString());
#else
  std::printf("(built without OpenVDB: no OpenVDB rows; install libopenvdb-dev and libboost-dev and rebuild)\n");
#endif
  std::printf(
      "columns: x vdb = seconds / OpenVDB's; x 1st/t = seconds per triangle / the first mesh's (DC); closed = closed "
      "manifold; bound, nonman = boundary and "
      "non-manifold edges; selfx = self-intersecting pairs; H out>S, H S>out = Hausdorff distances; "
      "/h = in cells\n");

  bool failed = false;
  std::vector<MeshSummary> summaries;
  for (const std::string& path : meshes) {
    GwnModel model;
    apps::ModelLoad loaded;
    if (Status s = apps::load_model(path, model, loaded); !s.ok()) {
      std::fflush(stdout);  // the error (stderr) after the tables before it
      apps::fail(kProgram, s.message());
      failed = true;
      continue;
    }
    std::fflush(stdout);  // the warning (stderr) after the tables before it
    apps::print_load_warnings(kProgram, path, loaded.report);
    MeshSummary m;
    m.path = path;
    m.triangles = model.mesh().triangles.size();
    m.boundary_segments = model.boundary().segment_count();
    m.load_seconds = loaded.load_seconds;
    m.build_seconds = loaded.build_seconds;
    std::printf(
        "\n== %s: %llu triangles, %llu boundary segments; load %.3f s, gwnrt model build %.3f s (not in "
        "the mesher times)\n",
        path.c_str(), (unsigned long long)m.triangles, (unsigned long long)m.boundary_segments, m.load_seconds,
        m.build_seconds);
    std::fflush(stdout);
    for (uint32_t resolution : resolutions) {
      const Row dc = run_gwnrt(model, MeshingMethod::kDualContouring, resolution, settings);
      const Row mc = run_gwnrt(model, MeshingMethod::kMarchingCubes, resolution, settings);
      m.rows.push_back(dc);
      m.rows.push_back(mc);
#if defined(GWNRT_HAVE_OPENVDB)
      const double cell = dc.ok() ? dc.cell_size : mc.ok() ? mc.cell_size : NAN;
      m.rows.push_back(run_openvdb(model, resolution, cell, settings));
#endif
      add_rounds(model, resolution, settings.rounds, m.rows);
    }
    for (Row& r : m.rows) {
      if (r.outcome == Outcome::kError) failed = true;
      const Row* vdb = find_row(m.rows, "OpenVDB", r.resolution);
      if (r.ok() && vdb && vdb->seconds > 0) r.ratio_to_openvdb = r.seconds / vdb->seconds;
      const Row* first = find_row((summaries.empty() ? m : summaries.front()).rows, "gwnrt DC", r.resolution);
      if (r.ok() && r.triangles > 0 && first && first->ok() && first->triangles > 0 && first->seconds > 0)
        r.ratio_per_triangle = (r.seconds / double(r.triangles)) / (first->seconds / double(first->triangles));
    }
    print_table(m);
    for (const DoublingRatio& d : doubling_ratios(m, resolutions))
      std::printf("  gwnrt DC time %u / %u: %.2f (cost follows area: 4; volume: 8)\n", d.resolution, d.half, d.ratio);
    std::fflush(stdout);
    summaries.push_back(std::move(m));
  }

  if (!json_path.empty()) {
    nlohmann::json out;
    out["threads"] = workers;
    out["rounds"] = settings.rounds;
    out["samples"] = settings.samples;
    out["self_intersections_counted"] = settings.self_intersections;
    out["resolutions"] = resolutions;
#if defined(GWNRT_HAVE_OPENVDB)
    out["openvdb"] = openvdb::getLibraryVersionString();
#else
    out["openvdb"] = nullptr;
#endif
    nlohmann::json mesh_list = nlohmann::json::array(), rows = nlohmann::json::array();
    for (const MeshSummary& m : summaries) {
      nlohmann::json ratios = nlohmann::json::array();
      for (const DoublingRatio& d : doubling_ratios(m, resolutions))
        ratios.push_back({{"resolution", d.resolution}, {"over", d.half}, {"ratio", d.ratio}});
      mesh_list.push_back({{"mesh", m.path},
                           {"triangles", m.triangles},
                           {"boundary_segments", m.boundary_segments},
                           {"load_seconds", m.load_seconds},
                           {"model_build_seconds", m.build_seconds},
                           {"dc_time_ratios", ratios}});
      for (const Row& r : m.rows) rows.push_back(row_json(m.path, r));
    }
    out["meshes"] = mesh_list;
    out["rows"] = rows;
    std::ofstream file(json_path);
    file << out.dump(2) << "\n";
    if (!file) return apps::fail(kProgram, json_path + ": cannot write");
  }
  return failed ? 1 : 0;
} catch (const std::exception& e) {
  return apps::fail(kProgram, e.what());
} catch (...) {
  return apps::fail(kProgram, "unknown exception");
}
