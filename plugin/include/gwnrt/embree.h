/* gwnrt's Embree plugin: the surface S = ∂{w > level} of a triangle mesh's generalized winding
 * number as an Embree user geometry. After gwnrtNewGeometry an application uses plain Embree:
 * it attaches, commits, instances and releases the geometry like any other, and rtcIntersect /
 * rtcOccluded (1/4/8/16, inside instances, with intersection filters) report hits on S.
 *
 *   GWNRTMesh mesh = gwnrtLoadMesh("scan.ply");          // the tree is built once, here
 *   if (!mesh) fprintf(stderr, "%s\n", gwnrtGetLastError());
 *   RTCGeometry geom = gwnrtNewGeometry(device, mesh, NULL);  // NULL: default options
 *   rtcAttachGeometry(scene, geom);
 *   rtcReleaseGeometry(geom);
 *   gwnrtReleaseMesh(mesh);                               // the geometry keeps it alive
 *   rtcCommitScene(scene);
 *
 * A hit reports t, Ng (unit, outward: from {w > level} toward {w < level}, in the object space of
 * the geometry), geomID and instID as for any geometry, and what was hit: on a sheet piece (on
 * the mesh) primID is the mesh's triangle index and u, v the hit's barycentric coordinates on it
 * (p = (1-u-v) p0 + u p1 + v p2, as for Embree's triangles); on a smooth piece (off the mesh, a
 * cap over a hole) primID is GWNRT_SMOOTH_PRIM_ID and u = v = 0.
 *
 * Calls from many threads at once are safe. Functions that can fail return NULL (or 0) and
 * leave the reason in gwnrtGetLastError (per thread). Embree 3.13 is what this is built and
 * tested against; what an Embree 4 port must change is confined to plugin/src/embree_api.h. */
#ifndef GWNRT_EMBREE_H
#define GWNRT_EMBREE_H

#include <stddef.h>
#include <stdint.h>

#include <embree3/rtcore.h>

#ifdef __cplusplus
extern "C" {
#endif

/* A triangle mesh with everything tracing needs (its multipole tree, boundary curve and cone),
 * reference-counted: one mesh may back any number of geometries and instances. */
typedef struct GWNRTMeshTy* GWNRTMesh;

/* The primID of a hit on a smooth piece of S (not on any triangle of the mesh). */
#define GWNRT_SMOOTH_PRIM_ID 0xFFFFFFFEu

enum GWNRTMode {
  GWNRT_MODE_GWN = 0,        /* S = ∂{w > level}: sheets on the mesh and smooth caps over holes */
  GWNRT_MODE_SOLID_ANGLE = 1 /* {Ω ≡ 4π·level mod 4π}: smooth pieces only */
};

typedef struct GWNRTOptions {
  enum GWNRTMode mode;        /* default GWNRT_MODE_GWN */
  float level;                /* w* (default 0.5); in solid-angle mode Ω over 4π (0.5 is 2π) */
  float epsilon;              /* stopping distance relative to the mesh's box diagonal, default 1e-5 */
  unsigned int max_steps;     /* Harnack steps per ray, default 4096 (a ray reaching it misses) */
  unsigned int max_crossings; /* triangle crossings per ray, default 65536 */
  float beta;                 /* multipole accuracy scale >= 1, default 2 (larger: slower, more accurate) */
} GWNRTOptions;

/* Copies xyz (3 floats per vertex) and triangles (3 indices per triangle) and builds. */
GWNRTMesh gwnrtNewMesh(const float* xyz, size_t vertexCount, const uint32_t* triangles, size_t triangleCount);
/* OBJ, PLY or STL. */
GWNRTMesh gwnrtLoadMesh(const char* path);
/* OBJ, PLY or STL, its coordinates read in double; a mesh far from the origin for its size (a
 * georeferenced scan in UTM metres, which gwnrtLoadMesh refuses: float keeps too little of it)
 * is moved by -origin, which is returned (0, 0, 0 when it was not moved). The geometry is then in
 * those moved coordinates: place it with an instance that adds origin back, composing the two
 * in double, or move the scene instead. */
GWNRTMesh gwnrtLoadMeshRecentred(const char* path, double origin[3]);
void gwnrtRetainMesh(GWNRTMesh mesh);
void gwnrtReleaseMesh(GWNRTMesh mesh);

void gwnrtInitOptions(GWNRTOptions* options);

/* A new Embree user geometry tracing S of `mesh` (retained) with `options` (copied; NULL for the
 * defaults), already committed. The application owns the returned reference, as with
 * rtcNewGeometry; after changing it (rtcSetGeometryMask, filter functions) it commits it again,
 * as any Embree geometry. NULL on failure (bad options, NULL mesh or device). */
RTCGeometry gwnrtNewGeometry(RTCDevice device, GWNRTMesh mesh, const GWNRTOptions* options);

/* Why the last failing call on this thread failed ("" when none has). */
const char* gwnrtGetLastError(void);

/* Triangles, vertices of the mesh (as given: also degenerate triangles are counted). */
size_t gwnrtGetMeshTriangleCount(GWNRTMesh mesh);
size_t gwnrtGetMeshVertexCount(GWNRTMesh mesh);

#ifdef __cplusplus
} /* extern "C" */

#include <string>
#include <utility>

namespace gwnrt::embree {

/* RAII holder of one mesh reference. */
class Mesh {
 public:
  Mesh() = default;
  explicit Mesh(GWNRTMesh adopt) : mesh_(adopt) {}
  static Mesh load(const std::string& path) { return Mesh(gwnrtLoadMesh(path.c_str())); }
  static Mesh load_recentred(const std::string& path, double origin[3]) {
    return Mesh(gwnrtLoadMeshRecentred(path.c_str(), origin));
  }
  Mesh(const Mesh& o) : mesh_(o.mesh_) {
    if (mesh_) gwnrtRetainMesh(mesh_);
  }
  Mesh(Mesh&& o) noexcept : mesh_(std::exchange(o.mesh_, nullptr)) {}
  Mesh& operator=(Mesh o) noexcept {
    std::swap(mesh_, o.mesh_);
    return *this;
  }
  ~Mesh() {
    if (mesh_) gwnrtReleaseMesh(mesh_);
  }
  explicit operator bool() const { return mesh_ != nullptr; }
  GWNRTMesh get() const { return mesh_; }

  /* A new geometry (the caller releases it with rtcReleaseGeometry). */
  RTCGeometry new_geometry(RTCDevice device, const GWNRTOptions* options = nullptr) const {
    return gwnrtNewGeometry(device, mesh_, options);
  }

 private:
  GWNRTMesh mesh_ = nullptr;
};

}  // namespace gwnrt::embree

#endif /* __cplusplus */

#endif /* GWNRT_EMBREE_H */
