// FrontEnd (stages/FrontEnd.hpp) on its own: how it routes a trace's records to
// the partitions (tile owner, tiled pixel number, lock address, submission
// index), what it decides on the way (culled at or behind the opaque surface,
// whether early depth must read the depth tile, the insert's outcome), the
// pass-end markers and the source's rewinds between passes, primitive runs for
// grouped locks, and the deferred inserts of lock.mode = unordered. Expected
// values derived by hand from the geometry in each test's comment.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "model/AlgoTestUtil.hpp"
#include "model/FunctionalRenderer.hpp"
#include "model/MemorySource.hpp"
#include "oit_rop/stages/FrontEnd.hpp"

namespace oit::rop {
namespace {

using model::InsertOutcome;
using model::testutil::frag;
using model::testutil::kOpaqueDraw;
using model::testutil::kTranspDraw;

// A 16x8 frame of two 8x8 tiles over two partitions: tile 0 (x 0-7) belongs
// to partition 0, tile 1 (x 8-15) to partition 1 ((tx + ty) % 2). Each
// partition owns one tile of the row, so both tiles are local tile 0 of
// their partition. A pixel's tiled number is tile x 64 + (y % 8) x 8 + x % 8;
// its per-pixel lock address local tile x 64 + (y % 8) x 8 + x % 8.
struct FrontEndBench {
  FrontEndBench(std::vector<Fragment> fs, const std::string& algo, unsigned layers, RopConfig c = config())
      : cfg(c),
        src(model::testutil::header(16, 8), std::move(fs), 3),  // batches of 3: routes straddle them
        classes(src.header()),
        opaque(model::buildOpaqueLayer(src, classes)),
        geo(16, 8, cfg.partitions, cfg.lock.granularity),
        algorithm(model::makeAlgorithm(algo, model::testutil::layers(layers))),
        fe(src, *algorithm, classes, opaque, std::vector<uint64_t>(2, 0), geo, cfg) {}
  static RopConfig config() {
    RopConfig c;
    c.partitions.count = 2;
    c.partitions.tile_width = c.partitions.tile_height = 8;
    return c;
  }
  // Refills until the front end is exhausted; the queues then hold every record.
  void routeAll() {
    for (int guard = 0; !fe.exhausted() && guard < 1000; ++guard) fe.refill();
    ASSERT_TRUE(fe.exhausted());
  }
  std::vector<InRec> records(unsigned partition) {
    std::vector<InRec> v;
    auto& q = fe.queue(partition);
    for (size_t i = 0; i < q.size(); ++i) v.push_back(q.at(i));
    return v;
  }
  RopConfig cfg;
  model::MemorySource src;
  model::DrawClassifier classes;
  model::OpaqueLayer opaque;
  FrameGeometry geo;
  std::unique_ptr<model::OitAlgorithm> algorithm;
  FrontEnd fe;
};

bool isPassEnd(const InRec& r) { return (r.flags & InRec::kPassEnd) != 0; }

TEST(FrontEnd, RoutesEachRecordToItsTilesOwnerWithItsPixelLockAndIndex) {
  // mlab k = 2, no opaque surface. Records 0-4:
  //   0 (3,3)  tile 0 -> partition 0, pixel 0 + 24 + 3 = 27, lock 27, first at its pixel: stored
  //   1 (12,5) tile 1 -> partition 1, pixel 64 + 40 + 4 = 108, lock 0 x 64 + 40 + 4 = 44: stored
  //   2 (3,3)  partition 0, pixel 27: second row of the pixel: stored
  //   3 (9,0)  partition 1, pixel 64 + 0 + 1 = 65, lock 1: stored
  //   4 (3,3)  partition 0, a third fragment on two rows: merged
  FrontEndBench b({frag(3, 3, 0.5f, 1, 0, 0, 0.5f), frag(12, 5, 0.5f, 0, 1, 0, 0.5f), frag(3, 3, 0.4f, 0, 0, 1, 0.5f),
           frag(9, 0, 0.3f, 1, 1, 0, 0.5f), frag(3, 3, 0.45f, 0, 1, 1, 0.5f)},
          "mlab", 2);
  b.routeAll();
  const std::vector<InRec> p0 = b.records(0), p1 = b.records(1);
  ASSERT_EQ(p0.size(), 4u);  // three records and the pass end
  ASSERT_EQ(p1.size(), 3u);
  EXPECT_EQ(p0[0].seq, 0u);
  EXPECT_EQ(p0[0].pixel, 27u);
  EXPECT_EQ(p0[0].lock, 27u);
  EXPECT_EQ(p0[0].outcome, uint8_t(InsertOutcome::Stored));
  EXPECT_EQ(p0[1].seq, 2u);
  EXPECT_EQ(p0[1].pixel, 27u);
  EXPECT_EQ(p0[1].outcome, uint8_t(InsertOutcome::Stored));
  EXPECT_EQ(p0[2].seq, 4u);
  EXPECT_EQ(p0[2].outcome, uint8_t(InsertOutcome::Merged));
  EXPECT_TRUE(isPassEnd(p0[3]));
  EXPECT_EQ(p1[0].seq, 1u);
  EXPECT_EQ(p1[0].pixel, 108u);
  EXPECT_EQ(p1[0].lock, 44u);
  EXPECT_EQ(p1[1].seq, 3u);
  EXPECT_EQ(p1[1].pixel, 65u);
  EXPECT_EQ(p1[1].lock, 1u);
  EXPECT_TRUE(isPassEnd(p1[2]));
  for (const InRec& r : p0)
    if (!isPassEnd(r)) {
      EXPECT_EQ(r.flags & InRec::kCulled, 0);
      EXPECT_EQ(r.prim_offset, 0u);  // per-pixel locks do not group primitives
    }
  const model::RenderCounts& c = b.fe.counts();
  EXPECT_EQ(c.fragments_in, 5u);
  EXPECT_EQ(c.stored, 4u);
  EXPECT_EQ(c.merged, 1u);
  EXPECT_EQ(c.culled, 0u);
  EXPECT_EQ(b.fe.sourceReads(), 1u);
}

TEST(FrontEnd, CullsAtOrBehindTheOpaqueSurfaceAndAsksForDepthOnlyWithinTheTilesRange) {
  // Opaque fragments at (3,3) z 0.5 and (4,4) z 0.6 (records 0, 1): tile 0's
  // opaque depth ranges over [0.5, +inf) (its other pixels have none), tile
  // 1's is +inf everywhere. Hierarchical Z: a record needs the depth tile read
  // unless z < the tile's min or z >= its max.
  //   2 (3,3) z 0.7: behind the opaque 0.5: culled, kind 4; 0.5 <= 0.7 < inf: reads depth
  //   3 (3,3) z 0.5: at the opaque depth (a tie is behind): culled, reads depth
  //   4 (5,5) z 0.2: in front of tile 0's nearest opaque: no depth read; inserted
  //   5 (12,1) z 0.9: tile 1, no opaque: min = max = inf, z < min: no depth read; inserted
  FrontEndBench b({frag(3, 3, 0.5f, 1, 1, 1, 1, kOpaqueDraw), frag(4, 4, 0.6f, 1, 1, 1, 1, kOpaqueDraw),
           frag(3, 3, 0.7f, 1, 0, 0, 0.5f), frag(3, 3, 0.5f, 1, 0, 0, 0.5f), frag(5, 5, 0.2f, 1, 0, 0, 0.5f),
           frag(12, 1, 0.9f, 1, 0, 0, 0.5f)},
          "mlab", 2);
  EXPECT_FLOAT_EQ(b.fe.hizMin()[0], 0.5f);
  EXPECT_TRUE(std::isinf(b.fe.hizMax()[0]));
  EXPECT_EQ(b.fe.opaqueLanded()[0], 2u);
  EXPECT_EQ(b.fe.opaqueLanded()[1], 0u);
  b.routeAll();
  const std::vector<InRec> p0 = b.records(0), p1 = b.records(1);
  ASSERT_EQ(p0.size(), 4u);
  ASSERT_EQ(p1.size(), 2u);
  EXPECT_EQ(p0[0].seq, 2u);  // the opaque records take indices too
  EXPECT_EQ(p0[0].flags, InRec::kCulled | InRec::kNeedsDepthRead);
  EXPECT_EQ(p0[0].outcome, InRec::kCulledKind);
  EXPECT_EQ(p0[1].seq, 3u);
  EXPECT_EQ(p0[1].flags, InRec::kCulled | InRec::kNeedsDepthRead);
  EXPECT_EQ(p0[2].seq, 4u);
  EXPECT_EQ(p0[2].flags, 0);
  EXPECT_EQ(p0[2].outcome, uint8_t(InsertOutcome::Stored));
  EXPECT_EQ(p1[0].seq, 5u);
  EXPECT_EQ(p1[0].flags, 0);
  const model::RenderCounts& c = b.fe.counts();
  EXPECT_EQ(c.opaque, 2u);
  EXPECT_EQ(c.culled, 2u);
  EXPECT_EQ(c.stored, 2u);
  ASSERT_EQ(b.fe.perDraw().count(kTranspDraw), 1u);
  EXPECT_EQ(b.fe.perDraw().at(kTranspDraw).fragments, 4u);
  EXPECT_EQ(b.fe.perDraw().at(kTranspDraw).culled, 2u);
  EXPECT_EQ(b.fe.perDraw().at(kTranspDraw).inserted, 2u);
}

TEST(FrontEnd, WithoutHierarchicalZEveryRecordReadsTheDepthTile) {
  RopConfig c = FrontEndBench::config();
  c.early_depth.hierarchical = false;
  FrontEndBench b({frag(5, 5, 0.2f, 1, 0, 0, 0.5f), frag(12, 1, 0.9f, 1, 0, 0, 0.5f)}, "mlab", 2, c);
  b.routeAll();
  EXPECT_EQ(b.records(0)[0].flags, InRec::kNeedsDepthRead);
  EXPECT_EQ(b.records(1)[0].flags, InRec::kNeedsDepthRead);
}

TEST(FrontEnd, ATwoPassAlgorithmReadsTheTraceTwiceWithAPassEndAfterEach) {
  // adaptive: two passes over the trace. Each partition's queue holds pass
  // 0's records, a pass end, pass 1's records (indices from 0 again), a pass end.
  FrontEndBench b({frag(3, 3, 0.5f, 1, 0, 0, 0.5f), frag(12, 5, 0.5f, 0, 1, 0, 0.5f), frag(2, 2, 0.4f, 0, 0, 1, 0.5f)},
          "adaptive", 2);
  ASSERT_EQ(b.fe.passes(), 2u);
  b.routeAll();
  const std::vector<InRec> p0 = b.records(0), p1 = b.records(1);
  ASSERT_EQ(p0.size(), 6u);
  EXPECT_EQ(p0[0].seq, 0u);
  EXPECT_EQ(p0[1].seq, 2u);
  EXPECT_TRUE(isPassEnd(p0[2]));
  EXPECT_EQ(p0[3].seq, 0u);
  EXPECT_EQ(p0[4].seq, 2u);
  EXPECT_TRUE(isPassEnd(p0[5]));
  ASSERT_EQ(p1.size(), 4u);
  EXPECT_EQ(p1[0].seq, 1u);
  EXPECT_TRUE(isPassEnd(p1[1]));
  EXPECT_EQ(p1[2].seq, 1u);
  EXPECT_TRUE(isPassEnd(p1[3]));
  EXPECT_EQ(b.fe.sourceReads(), 2u);
  EXPECT_EQ(b.fe.counts().fragments_in, 3u);  // counted once, not per pass
  ASSERT_EQ(b.fe.counts().pass_outcomes.size(), 2u);
  EXPECT_EQ(b.fe.counts().pass_outcomes[1][size_t(InsertOutcome::Stored)] +
                b.fe.counts().pass_outcomes[1][size_t(InsertOutcome::Merged)] +
                b.fe.counts().pass_outcomes[1][size_t(InsertOutcome::Discarded)],
            3u);
}

TEST(FrontEnd, QuadLocksGroupAPrimitivesRunAndNumberItsRecords) {
  // lock.granularity quad with per_primitive: an 8x8 tile has 16 quads; a
  // pixel's lock is local tile x 16 + (y % 8) / 2 x 4 + (x % 8) / 2, and
  // prim_offset counts the records since its primitive's run began (a run =
  // consecutive records of one draw and primitive).
  //   0 (0,0) prim 7: run starts, offset 0, lock 0
  //   1 (1,1) prim 7: offset 1, lock 0 (same quad)
  //   2 (2,0) prim 7: offset 2, lock 1
  //   3 (3,3) prim 8: a new run, offset 0, lock 4 + 1 = 5
  //   4 (0,0) prim 7: a new run again (7 is not the previous primitive), offset 0
  RopConfig c = FrontEndBench::config();
  c.lock.granularity = LockGranularity::Quad;
  c.lock.per_primitive = true;
  FrontEndBench b({frag(0, 0, 0.5f, 1, 0, 0, 0.5f, kTranspDraw, 7), frag(1, 1, 0.5f, 1, 0, 0, 0.5f, kTranspDraw, 7),
           frag(2, 0, 0.5f, 1, 0, 0, 0.5f, kTranspDraw, 7), frag(3, 3, 0.5f, 1, 0, 0, 0.5f, kTranspDraw, 8),
           frag(0, 0, 0.4f, 1, 0, 0, 0.5f, kTranspDraw, 7)},
          "mlab", 2, c);
  b.routeAll();
  const std::vector<InRec> p0 = b.records(0);
  ASSERT_EQ(p0.size(), 6u);
  const uint32_t locks[] = {0, 0, 1, 5, 0};
  const uint16_t offsets[] = {0, 1, 2, 0, 0};
  for (size_t i = 0; i < 5; ++i) {
    EXPECT_EQ(p0[i].lock, locks[i]) << "record " << i;
    EXPECT_EQ(p0[i].prim_offset, offsets[i]) << "record " << i;
  }
}

TEST(FrontEnd, UnorderedLocksDeferTheInsertToThePartition) {
  // lock.mode unordered: the front end routes the fragment beside its record
  // and does not insert it (the partition does at lock entry): no outcome, the
  // per-pixel state as cleared, no stored count; a culled record is still decided here.
  RopConfig c = FrontEndBench::config();
  c.lock.mode = LockMode::Unordered;
  FrontEndBench b({frag(3, 3, 0.5f, 1, 1, 1, 1, kOpaqueDraw), frag(3, 3, 0.4f, 1, 0, 0, 0.5f), frag(3, 3, 0.7f, 0, 1, 0, 0.5f),
           frag(12, 5, 0.2f, 0, 0, 1, 0.5f)},
          "mlab", 2, c);
  ASSERT_TRUE(b.fe.defersInserts());
  const std::vector<uint32_t> cleared(b.fe.state().begin(), b.fe.state().end());
  b.routeAll();
  const std::vector<InRec> p0 = b.records(0), p1 = b.records(1);
  ASSERT_EQ(p0.size(), 3u);
  EXPECT_EQ(p0[0].flags & InRec::kDeferredInsert, InRec::kDeferredInsert);
  EXPECT_EQ(p0[0].outcome, 0u);
  EXPECT_EQ(p0[0].work.compares + p0[0].work.moves, 0u);
  EXPECT_EQ(p0[1].flags & (InRec::kCulled | InRec::kDeferredInsert), InRec::kCulled);  // behind the opaque 0.5
  ASSERT_EQ(b.fe.deferred(0).size(), 1u);
  EXPECT_FLOAT_EQ(b.fe.deferred(0).front().z, 0.4f);
  ASSERT_EQ(b.fe.deferred(1).size(), 1u);
  EXPECT_FLOAT_EQ(b.fe.deferred(1).front().z, 0.2f);
  EXPECT_EQ(p1[0].flags & InRec::kDeferredInsert, InRec::kDeferredInsert);
  const std::vector<uint32_t> after(b.fe.state().begin(), b.fe.state().end());
  EXPECT_EQ(after, cleared);
  EXPECT_EQ(b.fe.counts().stored, 0u);
  EXPECT_EQ(b.fe.counts().culled, 1u);
}

}  // namespace
}  // namespace oit::rop
