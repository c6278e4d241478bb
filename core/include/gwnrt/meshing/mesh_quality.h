// The mesh quality report: what a mesh of S (geometry/surface_mesh.h) is worth as a surface. Its
// topology (is it a closed, consistently oriented 2-manifold), its self-intersections (decided by
// exact predicates, so that a correct mesh reports 0 and not round-off), and how far it lies from
// S = ∂{w > w*} of the model it was made from (distances both ways and normals). Used by the
// mesher's tests and by `gwnrt-mesh --report`.
//
// Errors: every function returns a Status and throws nothing (guard_status). A mesh with an
// index out of range fails with a message naming the triangle, a non-finite coordinate with one
// naming the vertex; an empty mesh is no error (zero counts).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "gwnrt/base/hd.h"
#include "gwnrt/base/status.h"
#include "gwnrt/geometry/surface_mesh.h"
#include "gwnrt/model/model.h"

namespace gwnrt {

// ---------------------------------------------------------------------------------------------
// Topology

struct MeshTopology {
  uint64_t vertices = 0;               // positions (after welding: distinct positions)
  uint64_t unreferenced_vertices = 0;  // of those, used by no triangle (not a defect of the surface)
  uint64_t triangles = 0;
  // Repeated vertex index, or zero area (exactly: its corners collinear). Triangles with a
  // repeated index have no proper edges and take no part in the counts below; zero-area ones
  // with three distinct indices do (they are combinatorially sound, and a sliver must not open
  // the surface it closes).
  uint64_t degenerate_triangles = 0;
  uint64_t boundary_edges = 0;      // undirected edges with exactly one incident triangle
  uint64_t non_manifold_edges = 0;  // undirected edges with more than two incident triangles
  // Vertices whose incident triangles form more than one fan (edge-connected around the vertex):
  // two surfaces touching at a point (a vertex on a non-manifold edge has one fan there).
  uint64_t non_manifold_vertices = 0;
  uint64_t inconsistent_edges = 0;  // two incident triangles that traverse the edge the same way
  uint64_t components = 0;          // edge-connected components of the triangles (non-manifold edges connect)
  // A closed, consistently oriented 2-manifold without degenerate triangles: every count but
  // vertices, unreferenced_vertices, triangles and components is zero.
  bool closed_manifold() const {
    return degenerate_triangles == 0 && watertight() && manifold() && inconsistent_edges == 0;
  }
  bool watertight() const { return boundary_edges == 0; }                                  // no open edges
  bool manifold() const { return non_manifold_edges == 0 && non_manifold_vertices == 0; }  // edges and vertices
  bool operator==(const MeshTopology&) const = default;
};

// The topology of the indexed mesh as it is; with weld_equal_positions (a triangle soup, or a
// mesh split along seams) vertices with exactly equal positions are first made one (0.0 and -0.0
// are equal). Fails on indices out of range and non-finite coordinates.
Status mesh_topology(const SurfaceMesh& mesh, MeshTopology& out, bool weld_equal_positions = false);

// ---------------------------------------------------------------------------------------------
// Self-intersections

// The number of unordered pairs of triangles that intersect other than in what they share.
// Sharing is by exactly equal positions (so an indexed mesh and its soup count the same): two
// triangles sharing one vertex intersect when their closed sets meet anywhere else, sharing an
// edge when they are coplanar with the third vertices on the same side of it (folded onto each
// other), sharing all three (a duplicate) always. Touching counts (a vertex on another triangle,
// a T-junction). Zero-area triangles are left out (mesh_topology counts them). Every decision is
// exact (the orientation predicates below), over a BVH of the triangles, in parallel. `pairs`,
// when given, receives every such pair (smaller index first, sorted).
Status count_self_intersections(const SurfaceMesh& mesh, uint64_t& count, std::vector<glm::uvec2>* pairs = nullptr);

// ---------------------------------------------------------------------------------------------
// Distances to S

struct SurfaceDistances {
  // (mean_to_surface + mean_from_surface) / 2: the symmetric mean of the two one-sided mean
  // distances (not squared).
  double chamfer = 0;
  double hausdorff_to_surface = 0;    // max over the output samples of their distance to S
  double hausdorff_from_surface = 0;  // max over the points of S of their distance to the output
  double mean_to_surface = 0, mean_from_surface = 0;
  // The angle between S's outward normal at its points and the output's normal at the nearest
  // point of the output (interpolated vertex normals, or the face normal where the mesh has
  // none), both outward: a flipped output is 180°.
  double normal_deviation_mean_deg = 0, normal_deviation_max_deg = 0;
  uint64_t surface_points = 0;                              // points of S measured: ray hits and sheet points
  uint64_t sheet_points = 0;                                // of which taken on the sheets directly
  uint64_t output_samples = 0;                              // output points measured (random points + vertices)
  double seconds_to_surface = 0, seconds_from_surface = 0;  // what each direction took
};

struct SurfaceDistanceOptions {
  // Sizes of the samples: the report's cost follows them, not the mesh (on an open scan a ray
  // costs a millisecond of Harnack steps), and a few ten thousand points resolve the means.
  uint32_t output_samples = 20000;  // random points on the output, area-weighted
  // And vertices (where Hausdorff peaks): every vertex a triangle uses when there are at most this
  // many, else this many of them at random; 0: none.
  uint32_t vertex_samples = 20000;
  // Rays whose hits on S are sample points: the only ones on S's smooth pieces (on an open scan a
  // ray costs a millisecond of Harnack steps).
  uint32_t surface_rays = 2500;
  uint32_t max_hits_per_ray = 16;  // points of S taken along one ray (at least 1)
  // Random points on S's sheets (M's triangles that are sheets for the level), area-weighted: as
  // many points of S as a ray's hits at a small fraction of their cost.
  uint32_t sheet_samples = 10000;
  // TraceOptions::epsilon: hits on the smooth pieces of S lie within this fraction of the model's
  // box diagonal of S (sheet hits are exact to float round-off), so it bounds what the distances
  // from S can resolve there.
  float trace_epsilon = 1e-5f;
  uint64_t seed = 1;
  float level = 0.5f;  // w*: the model's sheets must be classified for it
};

// The sample sizes for an output of this many triangles: `full`'s from kFullSampleTriangles up,
// in proportion below it (at least a tenth of each), so that the distances cost about as much per
// output triangle at a coarse resolution as at a fine one (on a scan with 199 holes at 128³, the
// full samples took 2.7 × the meshing).
inline constexpr size_t kFullSampleTriangles = 400000;
SurfaceDistanceOptions samples_for_output(size_t output_triangles, const SurfaceDistanceOptions& full = {});

// Output -> S: |signed distance| (evaluate_points, kFieldSignedDistance) at area-weighted random
// points of the output triangles plus its vertices. S -> output: the points of S are the hits of
// rays from random points on a sphere about the model's box (1.5 × its half-diagonal) toward
// random points in the box, every hit along a ray (up to max_hits_per_ray, so that parts of S
// hidden from outside are sampled too; not uniform in area: the maxima are what matter), and
// sheet_samples area-weighted random points of the sheet triangles, each measured to the nearest
// point of the output by a BVH over its non-zero-area triangles.
// At the nearest point the output's normal is taken from whichever triangle within 1e-6 of the
// output's box diagonal of it agrees best with S (where two triangles are equally near up to
// float round-off, on an edge, either is the nearest).
// An output with no triangles has no samples (mean and max to S are 0), and one with none of
// non-zero area is infinitely far from any point of S (no normals are compared then). Fails when the model's sheets are
// not classified for options.level (GwnModel::set_sheet_level), on bad mesh input (as above, and normals neither empty
// nor one per position) and on a non-finite level.
Status surface_distances(const GwnModel& model, const SurfaceMesh& mesh, const SurfaceDistanceOptions& options,
                         SurfaceDistances& out);

// Everything above for one output mesh: what gwnrt-mesh --report prints. `weld` as for
// mesh_topology (a soup's corners are welded by position first).
struct MeshQualityReport {
  MeshTopology topology;
  uint64_t self_intersections = 0;
  SurfaceDistances distances;
  double seconds = 0;                                           // spent on the report itself
  double seconds_topology = 0, seconds_self_intersections = 0;  // of which
};
Status mesh_quality_report(const GwnModel& model, const SurfaceMesh& mesh, const SurfaceDistanceOptions& options,
                           MeshQualityReport& out, bool weld_equal_positions = false);

}  // namespace gwnrt
