// Loading meshes from OBJ and PLY files (core/src/io/), and what loading found.
#pragma once

#include <cstddef>
#include <string>

#include "gwnrt/base/status.h"
#include "gwnrt/geometry/mesh.h"
#include "gwnrt/geometry/weld.h"

namespace gwnrt {

// What loading found, for the user to read; none of it is an error.
struct MeshLoadReport {
  std::size_t vertex_count = 0;
  std::size_t file_vertices = 0;         // as the file lists them: an STL lists 3 a facet, merged when identical
  std::size_t triangle_count = 0;        // after fanning polygons
  std::size_t polygons_fanned = 0;       // input faces with more than three corners
  std::size_t degenerate_triangles = 0;  // zero area (repeated or collinear corners): contribute nothing
  std::string format;        // "obj", "ply-ascii", "ply-binary-le", "ply-binary-be", "stl-ascii", "stl-binary"
  std::size_t uv_count = 0;  // texture coordinates kept (Mesh::uvs)
  bool has_colors = false;   // vertex colours kept (Mesh::colors)
  // Empty, or why UVs or colours in the file were not kept (e.g. only some faces have them).
  std::string attributes_dropped;
  // Empty, or what was skipped that the user may not expect (OBJ lines with unknown statements).
  std::string warnings;
  // Topology by position (what ∂M, the cone and the sheets use) against topology by index; with
  // MeshLoadOptions::summarize_weld only.
  WeldSummary weld;
  // Vertices moved onto a neighbour by MeshLoadOptions::weld_tolerance (0 without it).
  std::size_t tolerance_welded = 0;
  // Where the mesh's coordinate 0 lies in the file's coordinates: Mesh::positions are the file's
  // minus this. Zero unless MeshLoadOptions::recentre moved the mesh.
  dvec3 origin{0.0};
};

// A mesh is recentred (MeshLoadOptions::recentre) when its largest coordinate exceeds this many
// times its box's diagonal (float then keeps at least 4 bits fewer of its shape than it would
// about the origin), or exceeds kMaxMeshCoordinate. Meshes about the origin, the usual case, are
// read exactly as without recentring.
inline constexpr double kRecentreCoordinatePerDiagonal = 16;

struct MeshLoadOptions {
  // gwnrt computes in float, whose step at a coordinate c is about 6e-8 c: a georeferenced scan
  // (UTM coordinates of 1e5 to 1e7 m, for a site metres to kilometres across) keeps few bits of
  // its shape in float, or is refused by GwnModel::build. With `recentre`, coordinates are also
  // read in double and a mesh far from the origin for its size (kRecentreCoordinatePerDiagonal)
  // is moved by -MeshLoadReport::origin before it is rounded to float. origin is the centre of
  // the box of the vertices the triangles use, rounded to a multiple of the largest power of 2
  // not above the box's diagonal (so it prints short and adds back exactly). The caller then
  // subtracts origin from the points and rays it asks about, in double, and adds it back to the
  // positions it writes out (MeshWriteOptions::origin). Needs a report to return origin in.
  bool recentre = false;
  // Files written with rounding leave cracks between vertices that were one: with a tolerance t > 0
  // every vertex within t times the box's diagonal of another is moved onto it (weld_within), which
  // moves triangles by up to that much. 0: vertices are one only where their positions are
  // bit-identical (always so, whatever this says). At most kMaxWeldTolerance.
  double weld_tolerance = 0;
  // Fill MeshLoadReport::weld: sorts of the vertices and half-edges, which on a large mesh cost
  // more than parsing it (the 871k dragon: 0.5 s against 0.3 s), so only when it will be read.
  bool summarize_weld = false;
};
inline constexpr double kMaxWeldTolerance = 0.01;

// The origin that recentring moves geometry whose box is [lo, hi] (in double) by: zero when the
// box lies within kRecentreCoordinatePerDiagonal diagonals of the origin and within
// ±max_coordinate; otherwise its centre rounded to a multiple of the largest power of 2 not
// above its diagonal. MeshLoadOptions::recentre uses it on the triangles' corners; gwnrt-render
// on a whole scene.
dvec3 recentring_origin(const dvec3& lo, const dvec3& hi, double max_coordinate);

// What to add to a message that names coordinates of a mesh loaded with `origin` subtracted (a
// build's refusal): " (coordinates relative to (x, y, z), the mesh being recentred)", or "" for
// a zero origin.
std::string recentred_note(const dvec3& origin);

// Loads an OBJ, PLY or STL file (chosen by the extension, case-insensitive; an STL is binary when
// its size is 84 + 50 bytes a facet, else ASCII). Polygons are fanned
// into triangles. Texture coordinates (OBJ vt; PLY u v, s t, texture_u texture_v, texture_s
// texture_t per vertex, or a face texcoord list) and vertex colours (OBJ v x y z r g b; PLY red
// green blue [alpha], integers scaled to [0, 1]) are kept when every face or vertex has them. Fails, naming the file
// and the line or element, on malformed content, non-finite coordinates, out-of-range indices and meshes without
// triangles; and, as it reads, on a text line longer than kMaxMeshLineBytes (the header of a binary PLY included) or
// more bytes than the memory available (gwnrt/io/read_file.h): /dev/zero stops there.
Status load_mesh(const std::string& path, Mesh& mesh, MeshLoadReport* report = nullptr,
                 const MeshLoadOptions& options = {});

}  // namespace gwnrt
