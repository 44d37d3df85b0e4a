// The ROP cache in whole timing runs: a cache that holds the frame's arrays
// exactly misses each line once, fills in flight never exceed its lines, and a
// partition's cache sets are indexed by its own tile numbers (values by hand).
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

namespace cache_in_run_test {

// A 128 KiB, 8-way cache of 64-byte lines (2048 lines, 256 sets) holds a
// 64x64 frame's arrays exactly with mlab k=4 rgba8t8z32 (64 tiles x 64 px x
// 32 B = 2048 lines; set = (tile x 32 + line) mod 256: 8 lines per set). One
// fragment per pixel in raster order: two pixels share a line, so each line
// misses once (its first pixel) and hits once: 4096 accesses, 2048 misses;
// the resolve reads the 2048 written lines and hits them all. With fp32 rows
// (80 B per pixel) a tile is 80 lines (5120 lines in all) and a pixel's array
// spans two lines: per row of 8 pixels of a tile, 16 line accesses to 10 lines
// (10 misses, 6 hits): 8192 accesses, 5120 misses; the resolve then walks the
// tiles in order through 2048 lines and misses all 5120 again (LRU: the first
// tiles' lines left first).
TEST(TimingRun, ExactlyFittingCacheMissesEachTileOnce) {
  std::vector<Fragment> fs;
  for (uint16_t y = 0; y < 64; ++y)
    for (uint16_t x = 0; x < 64; ++x) fs.push_back(model::testutil::frag(x, y, 0.5f, 1, 0, 0, 0.5f));
  RopConfig cfg = smallConfig();
  cfg.partitions.count = 1;
  cfg.cache.size_bytes = 128 * 1024;
  cfg.cache.ways = 8;
  for (const auto format : {model::StorageFormat::Rgba8T8Z32, model::StorageFormat::Fp32}) {
    model::AlgorithmParams p;
    p.layers = 4;
    p.format = format;
    const auto r = runInChild([&] { return timed("mlab", p, fs, 64, 64, cfg); });
    ASSERT_TRUE(r.ok) << r.error;
    const bool rgba8 = format == model::StorageFormat::Rgba8T8Z32;
    EXPECT_EQ(r.stats["cache"]["line_bytes"].get<uint64_t>(), 64u);
    EXPECT_EQ(r.stats["cache"]["tile_stride_bytes"].get<uint64_t>(), rgba8 ? 2048u : 5120u);
    EXPECT_EQ(r.stats["skips"]["tiles_resolved"].get<uint64_t>(), 64u);
    EXPECT_EQ(r.stats["cache"]["accesses"].get<uint64_t>(), rgba8 ? 4096u + 2048 : 8192u + 5120);  // fragments + resolve
    EXPECT_EQ(r.stats["cache"]["misses"].get<uint64_t>(), rgba8 ? 2048u : 5120u + 5120);
  }
}

// Audit: 30 fragments visiting tiles 0, 1, 2 in turn through a 2-line cache
// (one set, 2 ways). Every access misses (LRU over 3 tiles in 2 lines), but
// the lines whose fills were in flight used to be the victims, so 16 fills
// were in flight in a 2-line cache. A line in use (fill in flight or blend not
// done) is never a victim now: at most 2 fills in flight, and the third tile
// waits for a line ("set_in_use").
TEST(TimingRun, CacheNeverHasMoreFillsInFlightThanLines) {
  std::vector<Fragment> fs;
  for (int i = 0; i < 30; ++i)
    fs.push_back(model::testutil::frag(uint16_t(8 * (i % 3) + (i / 3) % 8), 0, 0.5f - 0.001f * float(i), 0.5f, 0.2f,
                                       0.1f, 0.4f, model::testutil::kTranspDraw, uint32_t(i)));
  RopConfig cfg = smallConfig();
  cfg.partitions.count = 1;
  cfg.cache.size_bytes = 1024;  // 2 lines of 512 B (8x8 px x 8 B, k = 1: a tile per line)
  cfg.cache.ways = 2;
  cfg.cache.line_bytes = 512;
  cfg.input.latency_model = LatencyModel::Fixed;
  model::AlgorithmParams p;
  p.layers = 1;
  p.format = model::StorageFormat::Rgba8T8Z32;
  const auto r = runInChild([&] { return timed("mlab", p, fs, 24, 8, cfg); });
  ASSERT_TRUE(r.ok) << r.error;
  const auto& c = r.stats["cache"];
  EXPECT_EQ(c["line_bytes"].get<uint64_t>(), 512u);
  EXPECT_EQ(c["accesses"].get<uint64_t>(), 33u);  // 30 fragments + 3 resolve reads, all misses
  EXPECT_EQ(c["misses"].get<uint64_t>(), 33u);
  EXPECT_LE(c["peak_misses_in_flight"].get<uint64_t>(), 2u);
  EXPECT_GT(c["set_in_use"].get<uint64_t>(), 0u);
}

// A partition's cache is indexed by its own tile numbers. A frame 17 tiles wide
// and 1 high on 2 partitions: partition 0 owns the 9 even tiles. Indexed by the
// global tile number they all fell in set 0 of 2 (8 ways: 9 tiles thrash, every
// access missed; audit: at widths with tiles_x = 1 mod N a bigger cache could be
// slower). By the local number (tx / 2) they spread over both sets and fit: only
// the 17 compulsory misses, the 3 sweeps and the resolve hit.
TEST(TimingRun, CacheSetsAreIndexedByThePartitionsOwnTileNumbers) {
  std::vector<Fragment> fs;
  uint32_t prim = 0;
  for (int sweep = 0; sweep < 4; ++sweep)
    for (uint16_t tx = 0; tx < 17; ++tx)
      fs.push_back(model::testutil::frag(uint16_t(8 * tx + sweep), 0, 0.5f - 0.01f * float(sweep), 1, 0, 0, 0.5f,
                                         model::testutil::kTranspDraw, prim++));
  RopConfig cfg = smallConfig();
  cfg.partitions.count = 2;
  cfg.cache.size_bytes = 16 * 1024;  // 16 lines of 1 KiB, a tile each (8x8 px x 2 rows x 8 B): 2 sets of 8 ways
  cfg.cache.ways = 8;
  cfg.cache.line_bytes = 1024;
  model::AlgorithmParams p;
  p.layers = 2;
  p.format = model::StorageFormat::Rgba8T8Z32;
  const auto r = runInChild([&] { return timed("mlab", p, fs, 17 * 8, 8, cfg); });
  ASSERT_TRUE(r.ok) << r.error;
  const auto& c = r.stats["cache"];
  EXPECT_EQ(c["accesses"].get<uint64_t>(), 4u * 17 + 17);  // fragments + resolve reads
  EXPECT_EQ(c["misses"].get<uint64_t>(), 17u);
  EXPECT_EQ(c["evictions"].get<uint64_t>(), 0u);
}

}  // namespace cache_in_run_test
