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
//                      "instances": [T, ...]}],          // default: one, the identity
//     "environment": {"radiance": [r,g,b]} | {"file": "sky.exr", "scale": 1},
//     "sun": {"direction": [x,y,z], "radiance": [r,g,b], "angular_radius": 0.00465}
//   }
// A transform T is {"translate": [..], "rotate": [axis_x, axis_y, axis_z, degrees],
// "scale": s | [sx,sy,sz]} (applied scale, then rotate, then translate) or {"matrix": 16
// numbers, row-major}.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "bsdf.h"
#include "camera.h"
#include "environment.h"
#include "gwnrt/geometry/mesh.h"
#include "gwnrt/status.h"
#include "gwnrt/trace/surface_trace.h"

namespace gwnrt::render {

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

struct SceneDesc {
  examples::PinholeCamera camera;  // a scene file's "camera" block through look_at
  RenderSettings render;
  std::vector<Material> materials;
  std::vector<std::string> material_names;
  std::vector<MeshDesc> meshes;
  std::vector<GwnObjectDesc> gwn_objects;
  EnvironmentDesc environment;
  Sun sun;
};

// Reads a scene file; a bad file fails with its path and the JSON location of the problem.
Status load_scene(const std::string& path, SceneDesc& out);

// The default scene for one mesh: the mesh as a GWN object (white diffuse) standing on a grey
// ground plane, under a soft sky and a sun, seen by a camera that frames it.
Status default_scene(const std::string& mesh_path, SceneDesc& out);

// The bounds of everything in the scene (GWN objects by their meshes' boxes, transformed).
Aabb scene_bounds(const SceneDesc& scene);

}  // namespace gwnrt::render
