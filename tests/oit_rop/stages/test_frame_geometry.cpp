// FrameGeometry (stages/FrontEnd.hpp): the screen's tiles over the partitions,
// each partition's own dense tile numbers and the lock addresses of each scope.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstdio>
#include <cstring>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <sstream>
#include <tuple>

#include "oit_rop/RopTestUtil.hpp"
#include "oit_rop/stages/FrontEnd.hpp"

using namespace oit;
using namespace oit::rop;
using namespace oit::rop::testutil;

namespace frame_geometry_test {

TEST(FrameGeometry, LocalTileNumbersAreUniqueAndDensePerPartition) {
  for (uint32_t parts : {1u, 2u, 3u, 4u})
    for (uint32_t w : {8u, 64u, 136u, 328u, 336u}) {
      PartitionConfig pc;
      pc.count = parts;
      const FrameGeometry g(w, 40, pc);
      std::vector<std::vector<uint32_t>> seen(parts);
      for (uint32_t t = 0; t < g.tiles(); ++t) seen[g.partitionOf(t)].push_back(g.localOf(t));
      const uint32_t per_row = (g.tiles_x + parts - 1) / parts;
      for (auto& v : seen) {
        std::sort(v.begin(), v.end());
        EXPECT_EQ(std::adjacent_find(v.begin(), v.end()), v.end()) << parts << " " << w;  // unique
        if (!v.empty()) {
          EXPECT_LT(v.back(), per_row * g.tiles_y) << parts << " " << w;  // dense
        }
      }
    }
}

// Lock addresses are numbered among a partition's own: two pixels share one
// exactly when they are in the same partition and the same lock scope (pixel,
// screen-aligned 2x2 quad, tile), and a partition's addresses stay below its
// tiles x addresses per tile (its PixelLock table holds its share of the frame).
TEST(FrameGeometry, LockAddressesNameOneScopeAndAreDensePerPartition) {
  struct Case {
    LockGranularity g;
    uint32_t per_tile;  // 8x8 tiles
    uint32_t (*scope)(uint32_t x, uint32_t y, uint32_t w);
  };
  const Case cases[] = {
      {LockGranularity::Pixel, 64, [](uint32_t x, uint32_t y, uint32_t w) { return y * w + x; }},
      {LockGranularity::Quad, 16, [](uint32_t x, uint32_t y, uint32_t w) { return (y / 2) * w + x / 2; }},
      {LockGranularity::Tile, 1, [](uint32_t x, uint32_t y, uint32_t w) { return (y / 8) * w + x / 8; }},
  };
  for (const Case& c : cases)
    for (uint32_t parts : {1u, 2u, 3u})
      for (uint32_t w : {8u, 44u, 136u}) {
        PartitionConfig pc;
        pc.count = parts;
        const uint32_t h = 20;
        const FrameGeometry g(w, h, pc, c.g);
        EXPECT_EQ(g.lock_per_tile, c.per_tile);
        const uint32_t limit = (g.tiles_x + parts - 1) / parts * g.tiles_y * c.per_tile;
        std::map<std::pair<uint32_t, uint32_t>, uint32_t> scope_of;  // (partition, address) -> scope
        std::map<std::pair<uint32_t, uint32_t>, uint32_t> address_of;  // (partition, scope) -> address
        for (uint32_t y = 0; y < h; ++y)
          for (uint32_t x = 0; x < w; ++x) {
            const uint32_t p = g.partitionOf(g.tileOf(x, y)), a = g.lockAddress(x, y), s = c.scope(x, y, w);
            EXPECT_LT(a, limit) << x << "," << y;
            const auto [i, fresh] = scope_of.emplace(std::pair{p, a}, s);
            EXPECT_EQ(i->second, s) << "two scopes share address " << a << " at " << x << "," << y;
            const auto [j, fresh2] = address_of.emplace(std::pair{p, s}, a);
            EXPECT_EQ(j->second, a) << "one scope has two addresses at " << x << "," << y;
          }
      }
  // Hand values, two partitions, 8x8 tiles, 24 px wide: tiles (0,0) p0 local 0,
  // (1,0) p1 local 0, (2,0) p0 local 1; (0,1) p1 local 2 (2 tiles per row).
  PartitionConfig pc;
  pc.count = 2;
  const FrameGeometry px(24, 16, pc, LockGranularity::Pixel);
  EXPECT_EQ(px.lockAddress(3, 2), 2u * 8 + 3);
  EXPECT_EQ(px.lockAddress(19, 2), 64u + 2 * 8 + 3);
  EXPECT_EQ(px.lockAddress(3, 10), 2u * 64 + 2 * 8 + 3);
  const FrameGeometry quad(24, 16, pc, LockGranularity::Quad);
  EXPECT_EQ(quad.lockAddress(3, 2), 1u * 4 + 1);
  EXPECT_EQ(quad.lockAddress(19, 3), 16u + 1 * 4 + 1);
  const FrameGeometry tile(24, 16, pc, LockGranularity::Tile);
  EXPECT_EQ(tile.lockAddress(19, 7), 1u);
  EXPECT_EQ(tile.lockAddress(7, 15), 2u);
}

}  // namespace frame_geometry_test
