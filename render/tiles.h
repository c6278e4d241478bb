// The image split into square tiles, rendered in parallel: one tile is one TBB task, small
// enough that the few expensive regions (rays that graze a hole's rim take thousands of Harnack
// steps) spread over the threads, large enough that scheduling costs nothing next to tracing.
#pragma once

#include <algorithm>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace gwnrt::render {

inline constexpr int kTileSize = 16;

struct Tile {
  int index = 0;       // row-major among the tiles
  int x0 = 0, y0 = 0;  // first pixel
  int x1 = 0, y1 = 0;  // one past the last
  int pixel_count() const { return (x1 - x0) * (y1 - y0); }
};

struct TileGrid {
  int width = 0, height = 0;
  int columns = 0, rows = 0;

  TileGrid(int image_width, int image_height)
      : width(image_width),
        height(image_height),
        columns((image_width + kTileSize - 1) / kTileSize),
        rows((image_height + kTileSize - 1) / kTileSize) {}

  int count() const { return columns * rows; }
  Tile tile(int index) const {
    Tile t;
    t.index = index;
    t.x0 = (index % columns) * kTileSize;
    t.y0 = (index / columns) * kTileSize;
    t.x1 = std::min(t.x0 + kTileSize, width);
    t.y1 = std::min(t.y0 + kTileSize, height);
    return t;
  }
};

// Calls render_tile(const Tile&) once for every tile, in parallel. Tiles are handed out in
// row-major order, so a progress count advances roughly top to bottom.
template <class RenderTile>
void parallel_for_tiles(const TileGrid& grid, RenderTile&& render_tile) {
  tbb::parallel_for(tbb::blocked_range<int>(0, grid.count(), 1), [&](const tbb::blocked_range<int>& range) {
    for (int i = range.begin(); i != range.end(); ++i) render_tile(grid.tile(i));
  });
}

}  // namespace gwnrt::render
