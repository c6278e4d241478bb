// Strict OBJ, PLY and STL readers. General-purpose loaders turn a malformed number into 0, accept
// out-of-range indices or stop quietly at a truncated file; a silently wrong mesh gives
// silently wrong winding numbers, so here every such defect is an error that names the file
// and the line or element.
//
// Numbering in messages follows each format's own convention for references: OBJ vertices
// are 1-based (as in its `f` statements) and come with the line number; PLY elements are
// 0-based (as in its vertex_indices lists). Meshes checked by validate_mesh are 0-based.
//
// On failure, load_mesh leaves `mesh` and `report` untouched.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "gwnrt/base/status.h"
#include "gwnrt/geometry/mesh.h"
#include "gwnrt/io/mesh_io.h"

namespace gwnrt::io {

// Parse `data` (the contents of `path`) into `mesh`; messages name `path`. Validation of the
// result (validate_mesh) is load_mesh's. When `world` is given it receives every vertex's
// coordinates in double as well (MeshLoadOptions::recentre), one per mesh.positions entry.
Status read_obj(const std::string& path, std::string_view data, Mesh& mesh, MeshLoadReport& report,
                std::vector<dvec3>* world);
Status read_ply(const std::string& path, std::string_view data, Mesh& mesh, MeshLoadReport& report,
                std::vector<dvec3>* world);

Status read_stl(const std::string& path, std::string_view data, Mesh& mesh, MeshLoadReport& report,
                std::vector<dvec3>* world);

// ReadLimits::text_end for an STL file: 0 (no lines) for a binary one, kAllText for ASCII.
size_t stl_text_end(std::string_view head);

// ReadLimits::text_end for a PLY file: where its header ends when the body is binary (kAllText for
// an ASCII body or a file that is not a PLY; kTextNotEnded before the end_header line).
size_t ply_text_end(std::string_view head);

}  // namespace gwnrt::io
