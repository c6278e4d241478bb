// What the path tracer renders: a camera, triangle meshes, GWN objects (a mesh's surface S with
// tracer options, in any number of transformed instances), materials and lights, read from a
// JSON scene file or made up for one mesh (default_scene).
//
// Scene file (all lengths in the meshes' units; relative paths are relative to the file):
//   {
//     "camera": {"eye": [x,y,z], "target": [x,y,z], "up": [0,1,0], "fov": 40,
//                "width": 640, "height": 480},
//     "render": {"spp": 64, "max_depth": 8, "seed": 1},
//     "materials": {"name": {"type": "diffuse", "albedo": [r,g,b]},
//                   "metal": {"type": "conductor", "albedo": [..], "roughness": 0.2},
//                   "glass": {"type": "dielectric", "ior": 1.5},
//                   "lamp": {"type": "emissive", "emission": [r,g,b]}},
//     "meshes": [{"file": "a.obj" | "plane": size, "material": "name", "transform": T}],
//     "gwn_objects": [{"file": "b.obj", "material": "name", "mode": "gwn" | "solid-angle",
//                      "level": 0.5, "epsilon": 1e-5, "max_steps": 4096, "beta": 2,
//                      "instances": [T, ...] | "transform": T}],  // default: one, the identity
//     "environment": {"radiance": [r,g,b]} | {"file": "sky.exr", "scale": 1},
//     "sun": {"direction": [x,y,z], "radiance": [r,g,b], "angular_radius": 0.00465}
//   }
// A transform T is {"translate": [..], "rotate": [axis_x, axis_y, axis_z, degrees],
// "scale": s | [sx,sy,sz]} (applied scale, then rotate, then translate) or {"matrix": 16
// numbers, row-major, affine: the last row 0 0 0 1}.
//
// Every key is one of those above (a material's keys: those of its type): an unknown or misspelt
// key is an error naming its JSON location, not ignored, because a typo that silently leaves a
// default in place (a "radiance" spelt "radiancee", a "scale" on the wrong level) renders a
// wrong image that nothing explains. For the same reason a key given twice in one object is an
// error (JSON allows it, and readers keep one or the other), and so is a scene with neither
// "meshes" nor "gwn_objects" (it would render the sky alone). A GWN object's "level" that w never
// reaches on its mesh (|level| >= half its triangle count) is accepted with a warning: it renders
// nothing. Each section has its type (an object, an array), numbers are
// finite and within float's range, and the values are refused (with their location) where the
// renderer could not carry them through float arithmetic (scene.cpp says why each limit is what
// it is): coordinates of the eye, the target and the geometry in world space beyond ±1e12 (so
// also a plane or a scale that makes them so), a scene smaller than 1e-12 across, an "up" zero or
// within 0.06 degrees of the view direction, a singular, projective or badly conditioned
// transform, an instance whose object space would put rays beyond ±1e12, and radiances (emission,
// environment, sun) above 1e20 or negative.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "gwnrt/base/status.h"
#include "gwnrt/geometry/mesh.h"
#include "gwnrt/io/mesh_io.h"
#include "gwnrt/trace/surface_trace.h"
#include "render/bsdf.h"
#include "render/camera.h"
#include "render/environment.h"

namespace gwnrt::render {

// The ranges a scene file's "render" block and the command line take: beyond them a render
// would run for days (2^20 samples per pixel of 640 x 480 is 3e11 paths) or mean nothing.
inline constexpr int kMaxSpp = 1 << 20, kMaxPathDepth = 1000, kMaxSeed = 1 << 30;

// How the path tracer renders: a scene file's "render" block, overridden by the command line.
struct RenderSettings {
  int spp = 16;
  int max_depth = 8;  // path vertices after the camera
  uint64_t seed = 1;
  bool aovs = false;  // also albedo, normal and depth of the first hit (--aovs; not in scene files)
};

struct MeshDesc {
  std::string source;  // for messages: the file, or "plane"
  Mesh mesh;           // already in world space (the transform is applied when the scene is read)
  int material = 0;
};

struct GwnObjectDesc {
  std::string source;
  Mesh mesh;  // object space
  TraceOptions options;
  std::vector<glm::mat4> instances;  // object to world, affine
  int material = 0;
};

struct EnvironmentDesc {
  std::string file;         // empty: constant
  Spectrum radiance{0.0f};  // constant radiance, or the image's scale in .x
  float scale = 1.0f;
};

// A mesh file the scene read, with what its loader reported (for the program to print the
// warnings: lines the loader skipped).
struct LoadedMesh {
  std::string path;
  MeshLoadReport report;
};

struct SceneDesc {
  render::PinholeCamera camera;  // a scene file's "camera" block through look_at
  RenderSettings render;
  std::vector<Material> materials;
  std::vector<std::string> material_names;
  std::vector<MeshDesc> meshes;
  std::vector<GwnObjectDesc> gwn_objects;
  EnvironmentDesc environment;
  Sun sun;
  std::vector<LoadedMesh> loaded_meshes;  // every mesh file read, in order
  // Where the scene's coordinate 0 lies in the file's world: nonzero for a scene far from the
  // origin for its size (recentring_origin of its geometry and eye), which is moved by -origin,
  // camera and all, before float keeps it. The image is the same; only precision changes.
  dvec3 origin{0.0};
  // What was accepted but deserves a word, for the program to print: "<file>: <JSON location>:
  // ..." (a GWN object whose level w never reaches, so that it renders nothing).
  std::vector<std::string> warnings;
};

// Reads a scene file; a bad file fails with its path and the JSON location of the problem (the
// line and column where it is not JSON). Throws nothing.
Status load_scene(const std::string& path, SceneDesc& out);

// The same for a scene file's text, already read; `path` is for messages, and relative mesh and
// image paths are relative to its directory.
Status parse_scene(const std::string& text, const std::string& path, SceneDesc& out);

// The default scene for one mesh: the mesh as a GWN object (white diffuse) standing on a grey
// ground plane, under a soft sky and a sun, seen by a camera that frames it. A mesh whose scene
// the renderer cannot carry (larger or smaller than the limits above) fails, naming the mesh.
Status default_scene(const std::string& mesh_path, SceneDesc& out);

// The bounds of everything in the scene (GWN objects by their meshes' boxes, transformed).
Aabb scene_bounds(const SceneDesc& scene);

}  // namespace gwnrt::render
