// The corner pass of dual contouring (meshing/dual_contouring.h): the winding numbers of a line
// of cell corners, from one shared ray, and their screened values.
#include <gtest/gtest.h>

#include <cmath>

#include "gwnrt/field/crossing_winding.h"
#include "gwnrt/field/ribbon_winding.h"
#include "gwnrt/meshing/dual_contouring.h"
#include "gwnrt/meshing/edge_hermite.h"
#include "reference/brute_force_winding.h"
#include "test_util.h"

namespace gwnrt {
namespace {

// The corner pass's shared ray: every point of a line gets the w that winding_number_crossing
// gives it alone (which tests/field/test_crossing_winding.cpp checks against the brute force).
TEST(MeshingCorners, WindingAlongAnAxisIsEachPointsOwn) {
  for (const char* name : {"bunny_holes.obj", "bunny.obj", "teapot.obj"}) {
    const GwnModel model = test::build_model(test::load_test_mesh(name));
    const ModelView view = model.view();
    test::Random random(11);
    const Aabb box = model.bounds();
    for (int line = 0; line < 300; ++line) {
      const int axis = random.index(3);
      const float sign = random.index(2) ? 1.0f : -1.0f;
      const float step = 0.02f * glm::length(box.hi - box.lo);
      vec3 points[8];
      points[0] = random.in_box(box);
      for (int k = 1; k < 8; ++k) {
        points[k] = points[0];
        points[k][axis] += sign * step * float(k);
      }
      float w[8];
      winding_numbers_along_axis(view, points, axis, sign, w);
      for (int k = 0; k < 8; ++k) {
        const float alone = winding_number_crossing<false, false>(view, points[k]).w;
        EXPECT_NEAR(w[k], alone, 2e-6f) << name << " line " << line;
      }
    }
  }
}

// A block's columns walked as one lattice: each line's jumps are exactly those of its own walk,
// also where lines run through the cube's edges and vertices and in its faces' planes (the
// lattice on the cube's own coordinates, where only the tie-break decides).
TEST(MeshingCorners, LatticeJumpsAreEachLinesOwn) {
  int crossed = 0;
  for (const char* name : {"bunny_holes.obj", "bunny.obj", "teapot.obj", "cube"}) {
    const bool cube = std::string(name) == "cube";
    const GwnModel model = test::build_model(cube ? test::make_cube() : test::load_test_mesh(name));
    const ModelView view = model.view();
    test::Random random(17);
    const Aabb box = model.bounds();
    for (int lattice = 0; lattice < 200; ++lattice) {
      const int axis = random.index(3);
      const float sign = random.index(2) ? 1.0f : -1.0f;
      // The cube: steps of 1/2 from -2, so that lines meet its vertices, edges and faces.
      const float step = cube ? 0.5f : random.uniform(0.002f, 0.03f) * glm::length(box.hi - box.lo);
      const vec3 origin =
          cube ? vec3(-2.0f) + 0.5f * vec3(float(random.index(3)), float(random.index(3)), float(random.index(3)))
               : random.in_box(box);
      float u[8], v[8], along[8];
      for (int k = 0; k < 8; ++k) {
        u[k] = origin[(axis + 1) % 3] + step * float(k);
        v[k] = origin[(axis + 2) % 3] + step * float(k);
        along[k] = origin[axis] + sign * step * float(k);
      }
      int lattice_jumps[64][8];
      jumps_along_axis_lattice(view.triangles, u, v, along, axis, sign, lattice_jumps);
      for (int line = 0; line < 64; ++line) {
        vec3 points[8];
        for (int k = 0; k < 8; ++k) {
          points[k][axis] = along[k];
          points[k][(axis + 1) % 3] = u[line % 8];
          points[k][(axis + 2) % 3] = v[line / 8];
        }
        int jumps[8];
        mesh_jumps_along_axis(view, points, axis, sign, jumps);
        for (int k = 0; k < 8; ++k) {
          ASSERT_EQ(lattice_jumps[line][k], jumps[k]) << name << " lattice " << lattice << " line " << line;
          crossed += jumps[k] != 0;
        }
      }
    }
  }
  EXPECT_GT(crossed, 10000) << "the lines hardly met the meshes";
}

// The jumps CornerJumpsPass keeps for the edges' bounds: each corner's own walk along its slot's
// bound's ray where they fit a byte, kUnknownJumps where they do not or the slot has no bound. Nested
// cubes, each open on one face in turn, so that every ray out of the middle crosses over 127.
TEST(MeshingCorners, KeptJumpsAreEachCornersOwnOrUnknown) {
  constexpr int kShells = 200;
  Mesh nested;
  const Mesh cube = test::make_cube();
  for (int k = 0; k < kShells; ++k) {
    const uint32_t first = uint32_t(nested.positions.size());
    for (const vec3& p : cube.positions) nested.positions.push_back(p * (1.0f + 0.1f * float(k)));
    for (size_t t = 0; t < cube.triangles.size(); ++t)
      if (t / 2 != size_t(k % 6)) nested.triangles.push_back(cube.triangles[t] + first);
  }
  const GwnModel model = test::build_model(nested);
  const ModelView view = model.view();
  // Four blocks a side over the middle, from the innermost cubes out to about the 50th.
  MeshGrid grid;
  grid.origin = vec3(-6.0f);
  grid.cell = 12.0f / float(4 * kBlockCells);
  for (int a = 0; a < 3; ++a) {
    grid.cells[a] = 4 * kBlockCells;
    grid.blocks[a] = 4;
  }
  const uint32_t slots = uint32_t(grid.block_count());
  std::vector<uint32_t> block_of_slot(slots);
  std::vector<BlockWinding> bound(slots);
  for (uint32_t s = 0; s < slots; ++s) {
    block_of_slot[s] = s;
    bound[s].block = s % 7 != 0;  // every seventh slot without a bound: its rays are block_ray's
    bound[s].axis = int32_t(s % 3);
    bound[s].sign = s % 2 ? 1.0f : -1.0f;
  }
  SparseGridView grid_view;
  grid_view.grid = grid;
  grid_view.block_of_slot = block_of_slot.data();
  std::vector<float> values(size_t(slots) * kBlockItems);
  std::vector<int8_t> kept(values.size(), 0);
  WindingOptions winding;
  winding.method = WindingMethod::kCrossing;
  const CornerJumpsPass pass{grid_view, view, winding, bound.data(), values.data(), kept.data()};
  int fitting = 0, beyond = 0;
  for (uint32_t s = 0; s < slots; ++s) {
    pass(s);
    const GridCoord b = grid.block_of_index(s);
    for (uint32_t local = 0; local < kBlockItems; ++local) {
      const int8_t j = kept[size_t(s) * kBlockItems + local];
      if (!bound[s].any()) {
        EXPECT_EQ(j, kUnknownJumps) << "slot " << s;
        continue;
      }
      const GridCoord l = local_coord(local);
      const vec3 points[1] = {
          grid.corner_position({b.x * kBlockCells + l.x, b.y * kBlockCells + l.y, b.z * kBlockCells + l.z})};
      int own[1];
      mesh_jumps_along_axis(view, points, bound[s].axis, bound[s].sign, own);
      if (own[0] > INT8_MIN && own[0] <= INT8_MAX) {
        ASSERT_EQ(j, own[0]) << "slot " << s << " corner " << local;
        ++fitting;
      } else {
        ASSERT_EQ(j, kUnknownJumps) << "slot " << s << " corner " << local << ": " << own[0] << " jumps";
        ++beyond;
      }
    }
  }
  EXPECT_GT(fitting, 1000);
  EXPECT_GT(beyond, 1000);
}

// The corner pass's screened values: the same side of the level as the exact w, whatever the
// level, also levels within a hair of w itself.
TEST(MeshingCorners, ScreenedValuesHaveTheExactSigns) {
  for (const char* name : {"bunny_holes.obj", "teapot.obj"}) {
    const GwnModel model = test::build_model(test::load_test_mesh(name));
    const ModelView view = model.view();
    test::Random random(5);
    const Aabb box = model.bounds();
    int screened = 0;
    for (int line = 0; line < 300; ++line) {
      const int axis = random.index(3);
      const float sign = random.index(2) ? 1.0f : -1.0f;
      vec3 points[8];
      points[0] = random.in_box(box);
      for (int k = 1; k < 8; ++k) {
        points[k] = points[0];
        points[k][axis] += sign * 0.01f * glm::length(box.hi - box.lo) * float(k);
      }
      float exact[8];
      for (int k = 0; k < 8; ++k) exact[k] = winding_number_crossing<false, false>(view, points[k]).w;
      for (const float level : {0.5f, exact[3] + 1e-4f, exact[5] - 1e-3f, exact[0] + 0.015f}) {
        float w[8];
        int jumps[8];
        mesh_jumps_along_axis(view, points, axis, sign, jumps);
        for (int k = 0; k < 8; ++k) w[k] = corner_winding_value(view, points[k], axis, sign, jumps[k], level);
        for (int k = 0; k < 8; ++k) {
          EXPECT_EQ(w[k] > level, exact[k] > level) << name << " line " << line << " level " << level;
          screened += w[k] != exact[k];
        }
      }
    }
    EXPECT_GT(screened, 1000) << name << ": the screen was never used";
  }
}

#if GWNRT_HOST_LANES && defined(__AVX__)
// The batched ribbon sums the corners, roots and centres take (RibbonWindingBatch, M's jumps from
// their own walk): w within each use's allowance of the exact w wherever the batch is sure, by
// blocks of corners beside the rims (their rays pass by ∂M); ∇w by the rims as the normals take
// it; the eighths' and the blocks' centres (ŵ and ∇w times their reach) against a far higher beta.
TEST(MeshingCorners, BatchedRibbonSumsAreWithinTheScreensError) {
  for (const char* name : {"bunny_holes.obj", "teapot.obj", "realworld/birdBath_ggg_photogrammetry.obj"}) {
    const GwnModel model = test::build_model(test::load_test_mesh(name));
    const ModelView view = model.view();
    const BoundaryCurve& rim = model.boundary();
    const float diagonal = glm::length(model.bounds().hi - model.bounds().lo);
    const float h = diagonal / 256.0f;
    test::Random random(31);
    const auto by_the_rim = [&] {
      const size_t s = size_t(random.index(int(rim.segment_count())));
      return glm::mix(rim.endpoints[2 * s], rim.endpoints[2 * s + 1], random.uniform(0, 1));
    };
    int sure = 0, unsure = 0;
    // The screen's, the refinement's and the centres' betas (the last with ∇w, as the centres
    // take it), each tenfold under what its use allows: the margins of 0.02 and 2e-3 on the
    // corners (dual_contouring.h) and of 1e-3 on ŵ (kBoxWindingMargin); and the exact method's
    // own beta for the corners nearest the level, within twice its 1e-5 of the one-by-one sum.
    const float betas[4] = {kCornerScreenBeta, kCornerRefineBeta, kTaylorPointBeta, kConeBeta};
    const float tolerances[4] = {2e-3f, 2e-4f, 1e-4f, 2e-5f};
    float worst[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    for (int block = 0; block < 12; ++block) {  // 8³ corners a cell of 1/256 of the box apart
      const vec3 origin = by_the_rim() - random.uniform(0.0f, 8.0f * h) * vec3(1.0f);
      std::vector<vec3> points;
      for (int k = 0; k < 512; ++k) points.push_back(origin + h * vec3(float(k % 8), float(k / 8 % 8), float(k / 64)));
      const int axis = random.index(3);
      const float sign = random.index(2) ? 1.0f : -1.0f;
      for (int pass = 0; pass < 4; ++pass) {
        RibbonWindingBatch<512> batch;
        RibbonWindingBatch<512, true> with_gradient;
        const bool gradient = pass == 2;
        for (const vec3& x : points) (gradient ? with_gradient.add(x) : batch.add(x));
        if (gradient)
          with_gradient.evaluate(view.ribbons, betas[pass], axis, sign);
        else
          batch.evaluate(view.ribbons, betas[pass], axis, sign);
        for (int j = 0; j < int(points.size()); ++j) {
          const int jumps = jumps_ahead(view.triangles, points[j], axis, sign);
          const float w = gradient ? with_gradient.crossing_winding(j, jumps) : batch.crossing_winding(j, jumps);
          if (!(w == w)) {
            ++unsure;
            continue;
          }
          ++sure;
          const float exact = winding_number_crossing<false, false>(view, points[j]).w;
          worst[pass] = std::max(worst[pass], std::fabs(w - exact));
          ASSERT_NEAR(w, exact, tolerances[pass]) << name << " point " << j << " beta " << betas[pass];
        }
      }
    }
    // ∇w (the smooth roots' normals): within a relative 1e-2 of ∇w at the derivatives' beta,
    // as the one-by-one gradient at the same beta is.
    float worst_gradient[2] = {0.0f, 0.0f};
    for (int block = 0; block < 12; ++block) {
      const vec3 origin = by_the_rim();
      RibbonWindingBatch<512, true> batch;
      std::vector<vec3> points;
      for (int k = 0; k < 300; ++k) {
        points.push_back(origin + random.uniform(0.5f * h, 8.0f * h) * random.unit());
        batch.add(points.back());
      }
      batch.evaluate(view.ribbons, kHermiteNormalBeta, -1, 1.0f);
      for (int j = 0; j < int(points.size()); ++j) {
        const vec3 reference = winding_number_crossing<true, false>(view, points[j], kConeDerivativeBeta).gradient;
        const vec3 alone = smooth_root_gradient(view, WindingOptions{}, points[j]);
        const vec3 g = batch.winding_gradient(j);
        if (!(g.x == g.x)) continue;
        const float scale = glm::length(reference);
        worst_gradient[0] = std::max(worst_gradient[0], glm::length(g - reference) / scale);
        worst_gradient[1] = std::max(worst_gradient[1], glm::length(alone - reference) / scale);
      }
    }
    std::printf("%s: gradient's largest relative error %.2e batched, %.2e one by one\n", name, worst_gradient[0],
                worst_gradient[1]);
    EXPECT_LT(worst_gradient[0], 1e-2f) << name;
    // The centres, eight by the rims as a block's eighths are (kEighthPointBeta) and as a group's
    // blocks are (kTaylorPointBeta, twice as far apart): the errors of ŵ and of ∇w times the
    // reach of the estimate at 256³ against beta 24, tenfold under its margin (kBoxWindingMargin).
    for (const int scale : {1, 2}) {
      const float beta = scale == 1 ? kEighthPointBeta : kTaylorPointBeta;
      float worst_centre = 0.0f;
      for (int block = 0; block < 40; ++block) {
        const vec3 origin = by_the_rim();
        const int axis = random.index(3);
        const float sign = random.index(2) ? 1.0f : -1.0f;
        RibbonWindingBatch<8, true> centres, reference;
        for (int k = 0; k < 8; ++k) {
          const vec3 x =
              origin + float(scale) * h * (vec3(float(k & 1), float((k >> 1) & 1), float(k >> 2)) * 4.0f - vec3(2.0f)) +
              random.uniform(0.0f, h) * random.unit();
          centres.add(x);
          reference.add(x);
        }
        centres.evaluate(view.ribbons, beta, axis, sign);
        reference.evaluate(view.ribbons, 24.0f, axis, sign);
        const float reach = float(scale) * 2.0f * std::sqrt(3.0f) * h;
        for (int j = 0; j < 8; ++j) {
          const float e = glm::length(centres.winding_gradient(j) - reference.winding_gradient(j)) * reach +
                          std::fabs(centres.winding(j) - reference.winding(j));
          if (e == e) worst_centre = std::max(worst_centre, e);
        }
      }
      std::printf("%s: centres %d blocks apart at beta %g: largest error times reach %.2e\n", name, scale, beta,
                  worst_centre);
      EXPECT_LT(worst_centre, 0.1f * kBoxWindingMargin) << name;
      EXPECT_GT(worst_centre, 0.0f) << name;
    }
    EXPECT_GT(sure, 10 * unsure) << name;
    EXPECT_GT(worst[0], 0.0f) << name;
    std::printf(
        "%s: %d sure, %d unsure; largest error %.2e, %.2e, %.2e (with gradient), %.2e at betas %g, %g, %g, %g\n", name,
        sure, unsure, worst[0], worst[1], worst[2], worst[3], betas[0], betas[1], betas[2], betas[3]);
  }
}
#endif

// The scout's first-order test: a block it settles (no sheet within it, ŵ's range over it clear
// of every w* + n, by the block's centre alone or eighth by eighth) holds no point of S: w − w*
// keeps one sign at every corner of a fine lattice over it (exact w by crossings, every other
// corner). Blocks of 8 cells at 256³ by the rims and across the box.
TEST(MeshingScout, BlocksSettledByBoundsHoldNoSurface) {
  for (const char* name : {"bunny_holes.obj", "teapot.obj", "realworld/birdBath_ggg_photogrammetry.obj"}) {
    GwnModel model = test::build_model(test::load_test_mesh(name));
    ASSERT_TRUE(model.set_sheet_level(0.5f).ok());
    const ModelView view = model.view();
    const BoundaryCurve& rim = model.boundary();
    const float h = glm::length(model.bounds().hi - model.bounds().lo) / 256.0f;
    const ScoutQuery scout{view, 0.5f, 2.0f, true, true};
    test::Random random(41);
    int settled = 0, tried = 0, settled_by_eighths = 0;
    for (int block = 0; block < 3000; ++block) {
      const size_t s = size_t(random.index(int(rim.segment_count())));
      const vec3 lo = block % 2 ? random.in_box(model.bounds())
                                : glm::mix(rim.endpoints[2 * s], rim.endpoints[2 * s + 1], random.uniform(0, 1)) +
                                      random.uniform(2.0f * h, 24.0f * h) * random.unit();
      const Aabb box{lo, lo + vec3(8.0f * h)};
      const vec3 centre = box.centre();
      // The scout asks this only of blocks no sheet is within.
      if (unsigned_distance(view.sheets, centre).distance <= kScoutSlack * 0.5f * glm::length(box.hi - box.lo))
        continue;
      ++tried;
      const bool whole = scout.settled_by_bounds(box), by_eighths = scout.settled_by_bounds(box, true);
      ASSERT_TRUE(by_eighths || !whole) << name << " block " << block;  // the eighths come after the block
      if (!by_eighths) continue;
      ++settled;
      settled_by_eighths += !whole;
      const bool inside = winding_number_crossing<false, false>(view, lo).w > 0.5f;
      for (int k = 0; k < 5 * 5 * 5; ++k) {
        const vec3 x = lo + 2.0f * h * vec3(float(k % 5), float(k / 5 % 5), float(k / 25));
        const bool x_inside = winding_number_crossing<false, false>(view, x).w > 0.5f;
        ASSERT_EQ(x_inside, inside) << name << " block " << block << " corner " << k;
      }
    }
    std::printf("%s: %d of %d blocks settled by bounds, %d of them by eighths\n", name, settled, tried,
                settled_by_eighths);
    EXPECT_GE(settled, 100) << name;
    EXPECT_GE(settled_by_eighths, 10) << name;
    EXPECT_LT(settled, tried) << name;
#if GWNRT_HOST_LANES && defined(__AVX__)
    // The same eight at a time, as the scout takes a block's children (their centres batched):
    // a block it drops holds no point of S either. The finest level's order (bounds first, then
    // the eighths) with the distance to M rather than to the sheets: the teapot's sheets are
    // classified at centroids, wrong on a side of the cuts of its intersecting parts (which
    // run_dual_contouring's second scouting covers), and the bounds are what is tested here.
    const ScoutQuery by_mesh{view, 0.5f, 2.0f, false, true};
    int dropped = 0, dropped_finest = 0;
    for (int parent = 0; parent < 600; ++parent) {
      const bool finest = parent % 2 == 1;  // as the finest level asks: bounds first, eighths too
      const size_t s = size_t(random.index(int(rim.segment_count())));
      const vec3 lo = glm::mix(rim.endpoints[2 * s], rim.endpoints[2 * s + 1], random.uniform(0, 1)) +
                      random.uniform(4.0f * h, 24.0f * h) * random.unit();
      Aabb children[8];
      for (int k = 0; k < 8; ++k) {
        const vec3 c = lo + 8.0f * h * vec3(float(k & 1), float((k >> 1) & 1), float(k >> 2));
        children[k] = {c, c + vec3(8.0f * h)};
      }
      bool meets[8];
      (finest ? by_mesh : scout).may_meet_batch(children, 8, meets, finest);
      for (int k = 0; k < 8; ++k) {
        if (meets[k]) continue;
        ++dropped;
        dropped_finest += finest;
        const bool inside = winding_number_crossing<false, false>(view, children[k].lo).w > 0.5f;
        for (int q = 0; q < 5 * 5 * 5; ++q) {
          const vec3 x = children[k].lo + 2.0f * h * vec3(float(q % 5), float(q / 5 % 5), float(q / 25));
          const bool x_inside = winding_number_crossing<false, false>(view, x).w > 0.5f;
          ASSERT_EQ(x_inside, inside) << name << " parent " << parent << " child " << k << " corner " << q;
        }
      }
    }
    EXPECT_GE(dropped, 100) << name;
    EXPECT_GE(dropped_finest, 50) << name;
#endif
  }
}

// The edges' smooth roots, searched with w at kRootSearchConeBeta (within 1e-4 of the exact): by
// the double brute force each lies on S up to the bracket's width (kRootTolerance of the edge) or
// that error, on edges across S by the rims of open meshes.
TEST(MeshingEdges, SmoothRootsLieOnSWithinTheSearchsError) {
  for (const char* name : {"bunny_holes.obj", "teapot.obj"}) {
    const GwnModel model = test::build_model(test::load_test_mesh(name));
    const ModelView view = model.view();
    const reference::ReferenceMesh ref = reference::reference_mesh(model.mesh());
    const BoundaryCurve& rim = model.boundary();
    const float h = 0.01f * glm::length(model.bounds().hi - model.bounds().lo);
    WindingOptions winding;
    winding.method = WindingMethod::kCrossing;
    test::Random random(23);
    int smooth = 0;
    for (int edge = 0; edge < 20000 && smooth < 150; ++edge) {
      const size_t s = size_t(random.index(int(rim.segment_count())));
      const vec3 on_rim = glm::mix(rim.endpoints[2 * s], rim.endpoints[2 * s + 1], random.uniform(0, 1));
      const vec3 p0 = on_rim + random.uniform(0.1f * h, 4.0f * h) * random.unit();
      const int axis = random.index(3);
      vec3 p1 = p0;
      p1[axis] += h;
      const float f0 = winding_number_crossing<false, false>(view, p0).w - 0.5f;
      const float f1 = winding_number_crossing<false, false>(view, p1).w - 0.5f;
      if ((f0 > 0.0f) == (f1 > 0.0f)) continue;
      const HermitePoint hit = edge_hermite(view, winding, 0.5f, p0, axis, h, f0, f1);
      ASSERT_NE(hit.kind, HermiteKind::kFallback) << name << " edge " << edge;
      if (hit.kind != HermiteKind::kSmooth) continue;
      ++smooth;
      // S crosses within the bracket's width of the point, or w there is within the error of the
      // search's w (where the slope is small).
      const dvec3 x(hit.point);
      dvec3 e(0.0);
      e[axis] = kRootTolerance * h;
      const double before = reference::reference_w(ref, x - e) - 0.5, after = reference::reference_w(ref, x + e) - 0.5;
      EXPECT_TRUE((before > 0.0) != (after > 0.0) || std::abs(reference::reference_w(ref, x) - 0.5) <= 2e-4)
          << name << " edge " << edge << ": w − 1/2 " << before << " and " << after << " either side";
    }
    EXPECT_GE(smooth, 50) << name;
  }
}

// The first point of a whole edge's root search, from the corner values along its line: on a
// cubic through four corners (a quadratic through three where the fourth is missing or a jump
// away) the root itself and the slope there, against bisection in double; NaN where no three
// values fit.
TEST(MeshingEdges, InterpolatedGuessIsTheRootOfTheInterpolant) {
  test::Random rng(41);
  int cubics = 0;
  for (int k = 0; k < 2000 && cubics < 300; ++k) {
    // p(t) = a (t − r) + b (t − r)² + c (t − r)³, monotone on [−1, 2] when its slope keeps a sign.
    const double r = rng.uniform(0.02f, 0.98f), a = rng.uniform(0.05f, 0.2f) * (rng.index(2) ? 1 : -1);
    const double b = rng.uniform(-0.1f, 0.1f) * a, c = rng.uniform(-0.05f, 0.05f) * a;
    const auto p = [&](double t) { return a * (t - r) + b * (t - r) * (t - r) + c * (t - r) * (t - r) * (t - r); };
    const auto dp = [&](double t) { return a + 2 * b * (t - r) + 3 * c * (t - r) * (t - r); };
    if (dp(-1) * a <= 0 || dp(2) * a <= 0 || std::abs(p(-1)) >= 0.5 || std::abs(p(2)) >= 0.5) continue;
    ++cubics;
    float slope = NAN;
    const float t = interpolated_root_guess(float(p(-1)), float(p(0)), float(p(1)), float(p(2)), slope);
    EXPECT_NEAR(t, r, 2e-5) << "cubic " << k;
    EXPECT_NEAR(slope, dp(r), 1e-4 * std::abs(a)) << "cubic " << k;
    // A missing fourth value, or one a jump away: the quadratic through the other three, exact
    // when the data are quadratic.
    const auto q = [&](double u) { return a * (u - r) + b * (u - r) * (u - r); };
    if ((a + 2 * b * (-1 - r)) * a <= 0 || (a + 2 * b * (2 - r)) * a <= 0) continue;
    EXPECT_NEAR(interpolated_root_guess(NAN, float(q(0)), float(q(1)), float(q(2)), slope), r, 2e-5);
    EXPECT_NEAR(interpolated_root_guess(float(q(-1)), float(q(0)), float(q(1)), float(q(2)) + 1.0f, slope), r, 2e-5);
  }
  EXPECT_GE(cubics, 300);
  float slope = 0;
  EXPECT_TRUE(std::isnan(interpolated_root_guess(NAN, -0.2f, 0.3f, NAN, slope)));
  EXPECT_TRUE(std::isnan(interpolated_root_guess(5.0f, -0.2f, 0.3f, -7.0f, slope)));
}

// The root search ends within its tolerance of the root of smooth functions, and in fewer
// steps from an interpolated guess than from the secant of the edge's ends.
TEST(MeshingEdges, BracketFindsTheRootFasterFromAGuess) {
  test::Random rng(43);
  int with_guess = 0, without = 0;
  for (int k = 0; k < 300; ++k) {
    const double r = rng.uniform(0.02f, 0.98f), a = rng.uniform(0.05f, 1.0f) * (rng.index(2) ? 1 : -1);
    const double b = rng.uniform(-0.4f, 0.4f) * a, c = rng.uniform(-0.3f, 0.3f) * a;
    const auto f = [&](double t) { return a * (t - r) + b * (t - r) * (t - r) + c * std::sin(3 * (t - r)) * (t - r); };
    const float h = 1.0f;
    for (const bool guess : {false, true}) {
      IllinoisBracket bracket(0.0f, float(f(0)), h, float(f(1)), h);
      if (guess) {
        float slope = NAN;
        bracket.first_guess = interpolated_root_guess(float(f(-1)), float(f(0)), float(f(1)), float(f(2)), slope);
        bracket.slope = slope;
      }
      int values = 0;
      while (bracket.active()) {
        bracket.take(float(f(bracket.next())));
        ++values;
      }
      ASSERT_FALSE(bracket.capped()) << "function " << k;
      // Within the bracket's tolerance, or where |f| is within the value tolerance (and float's).
      const double t = bracket.root();
      EXPECT_TRUE(std::abs(t - r) <= kRootTolerance * h || std::abs(f(t)) <= kRootValueTolerance + 1e-6)
          << "function " << k << (guess ? " with" : " without") << " a guess: " << t << " against " << r;
      (guess ? with_guess : without) += values;
    }
  }
  EXPECT_LT(with_guess, without);
}

// A walk that stops for each value before a crossing of M (value_deferred), given them one at a
// time as a batch would (by winding_number_crossing here, as the walk sums them itself), ends
// on the very Hermite point of the walk that sums them itself, also past kDeferredEdgeValues.
TEST(MeshingEdges, DeferredValuesGiveTheWalksOwnPoint) {
  for (const char* name : {"bunny_holes.obj", "teapot.obj"}) {
    const GwnModel model = test::build_model(test::load_test_mesh(name));
    const ModelView view = model.view();
    const BoundaryCurve& rim = model.boundary();
    const float diagonal = glm::length(model.bounds().hi - model.bounds().lo);
    WindingOptions winding;
    winding.method = WindingMethod::kCrossing;
    test::Random random(29);
    int deferred = 0, many = 0;
    for (int edge = 0; edge < 4000; ++edge) {
      // Short edges by the rims, and long ones across the model (many crossings).
      const bool long_edge = edge % 4 == 0;
      const float h = (long_edge ? 0.5f : 0.01f) * diagonal;
      const size_t s = size_t(random.index(int(rim.segment_count())));
      const vec3 p0 = long_edge ? random.in_box(model.bounds())
                                : glm::mix(rim.endpoints[2 * s], rim.endpoints[2 * s + 1], random.uniform(0, 1)) +
                                      random.uniform(0.1f * h, 2.0f * h) * random.unit();
      const int axis = random.index(3);
      vec3 p1 = p0;
      p1[axis] += h;
      const float f0 = root_search_value(view, p0, 0.5f), f1 = root_search_value(view, p1, 0.5f);
      if ((f0 > 0.0f) == (f1 > 0.0f)) continue;
      const HermitePoint direct = edge_hermite(view, winding, 0.5f, p0, axis, h, f0, f1);
      EdgeValues values{};
      HermitePoint walked = edge_hermite(view, winding, 0.5f, p0, axis, h, f0, f1, nullptr, false, false, &values);
      for (int round = 0; walked.value_deferred; ++round) {
        ASSERT_LT(round, kDeferredEdgeValues) << name << " edge " << edge << ": the walk stops past its cap";
        values.value[values.count++] = root_search_value(view, walked.point, 0.5f);
        walked = edge_hermite(view, winding, 0.5f, p0, axis, h, f0, f1, nullptr, false, false, &values);
      }
      deferred += values.count > 0;
      many += values.count == kDeferredEdgeValues;
      EXPECT_EQ(walked.kind, direct.kind) << name << " edge " << edge;
      EXPECT_EQ(walked.point, direct.point) << name << " edge " << edge;
      EXPECT_EQ(walked.normal, direct.normal) << name << " edge " << edge;
    }
    EXPECT_GE(deferred, 50) << name << ": few walks stopped for a value";
    std::printf("%s: %d walks stopped for values, %d up to the cap\n", name, deferred, many);
  }
  // Past the cap: an edge through a stack of twelve open squares, the level near w above the top
  // one, so that the walk takes more values than the cap before its sign changes.
  Mesh stack;
  for (int k = 0; k < 12; ++k) {
    const float z = 0.1f * float(k);
    const uint32_t b = uint32_t(stack.positions.size());
    stack.positions.insert(stack.positions.end(), {{-1, -1, z}, {1, -1, z}, {1, 1, z}, {-1, 1, z}});
    stack.triangles.insert(stack.triangles.end(), {{b, b + 1, b + 2}, {b, b + 2, b + 3}});
  }
  const GwnModel model = test::build_model(stack);
  const ModelView view = model.view();
  const vec3 p0(0.1f, 0.13f, -0.05f);
  const float h = 1.2f;
  const float level = 0.5f * (root_search_value(view, p0 + vec3(0, 0, 1.05f), 0.0f) +
                              root_search_value(view, p0 + vec3(0, 0, 1.15f), 0.0f));
  const float f0 = root_search_value(view, p0, level), f1 = root_search_value(view, p0 + vec3(0, 0, h), level);
  ASSERT_NE(f0 > 0.0f, f1 > 0.0f);
  WindingOptions winding;
  winding.method = WindingMethod::kCrossing;
  const HermitePoint direct = edge_hermite(view, winding, level, p0, 2, h, f0, f1);
  EdgeValues values{};
  HermitePoint walked = edge_hermite(view, winding, level, p0, 2, h, f0, f1, nullptr, false, false, &values);
  while (walked.value_deferred) {
    ASSERT_LT(values.count, kDeferredEdgeValues);
    values.value[values.count++] = root_search_value(view, walked.point, level);
    walked = edge_hermite(view, winding, level, p0, 2, h, f0, f1, nullptr, false, false, &values);
  }
  EXPECT_EQ(values.count, kDeferredEdgeValues);
  EXPECT_EQ(walked.kind, direct.kind);
  EXPECT_EQ(walked.point, direct.point);
  EXPECT_EQ(walked.kind, HermiteKind::kSheet);  // on a square beyond the eighth
  EXPECT_NEAR(walked.point.z, 0.1f * std::round(10.0f * walked.point.z), 1e-5f);
  EXPECT_GT(walked.point.z, 0.75f);
}

}  // namespace
}  // namespace gwnrt
