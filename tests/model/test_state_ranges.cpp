// The byte ranges of an algorithm's per-pixel state that an insert and a resolve
// touch (the timing model's cache lines come from them).
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <stdexcept>

#include "AlgoTestUtil.hpp"
#include "model/AlgorithmDetail.hpp"

using namespace oit;
using namespace oit::model;
using namespace oit::model::testutil;

// The ranges an insert reads and writes (the timing model's cache lines come
// from them): inside the state, at most two, increasing, and as many bytes as
// readBytes / writeBytes (the A-buffer's write adds the node of its pool).
TEST(StateRanges, InsideTheStateAndAddUpToTheRmwBytes) {
  for (const AlgorithmInfo& info : algorithmNames()) {
    const std::string name(info.name);
    for (StorageFormat fmt : {StorageFormat::Fp32, StorageFormat::Fp16, StorageFormat::Rgba8T8Z32}) {
      AlgorithmParams p = layers(4);
      p.format = fmt;
      std::unique_ptr<OitAlgorithm> a;
      try {
        a = makeAlgorithm(name, p);
      } catch (const std::invalid_argument&) {
        continue;  // fp32-only algorithms
      }
      for (unsigned pass = 0; pass < a->passes(); ++pass)
        for (unsigned o = 0; o < kOutcomeCount; ++o) {
          const auto out = InsertOutcome(o);
          for (const StateRanges& r : {a->readRanges(pass, out), a->writeRanges(pass, out)}) {
            ASSERT_LE(r.count, StateRanges::kMax) << name;
            for (unsigned i = 0; i < r.count; ++i) {
              EXPECT_LT(r.range[i].begin, r.range[i].end) << name;
              EXPECT_LE(r.range[i].end, a->bytesPerPixel()) << name;
              if (i) {
                EXPECT_GE(r.range[i].begin, r.range[i - 1].end) << name;
              }
            }
          }
          EXPECT_EQ(a->readRanges(pass, out).bytes(), a->readBytes(pass, out)) << name << " pass " << pass;
          if (a->bounded()) {
            EXPECT_EQ(a->writeRanges(pass, out).bytes(), a->writeBytes(pass, out)) << name << " pass " << pass;
          }
        }
    }
  }
}

TEST(StateRanges, TwoPassAlgorithmsNameTheirWords) {
  // adaptive k = 4: nodes [0, 48), accumulator [48, 60), counters at 60 and 64.
  auto ad = makeAlgorithm("adaptive", layers(4));
  const StateRanges r1 = ad->readRanges(1, InsertOutcome::Stored), w1 = ad->writeRanges(1, InsertOutcome::Stored);
  ASSERT_EQ(r1.count, 2u);
  EXPECT_EQ(r1.range[0].end, 60u);
  EXPECT_EQ(r1.range[1].begin, 64u);
  ASSERT_EQ(w1.count, 2u);
  EXPECT_EQ(w1.range[0].begin, 48u);  // pass 1 writes the accumulator and its counter only
  EXPECT_EQ(w1.range[1].end, 68u);
  // stochastic S = 8: depths [0, 32), T [32, 36), U and U1 [36, 52).
  AlgorithmParams sp;
  sp.samples = 8;
  auto st = makeAlgorithm("stochastic", sp);
  EXPECT_EQ(st->writeRanges(0, InsertOutcome::Discarded).range[0].begin, 32u);  // T only
  EXPECT_EQ(st->writeRanges(1, InsertOutcome::Stored).range[0].begin, 36u);
  EXPECT_EQ(st->writeRanges(1, InsertOutcome::Stored).bytes(), 16u);
}

TEST(StateRanges, KBufferRejectionReadsOnlyTheLastRow) {
  AlgorithmParams p = layers(4);
  p.format = StorageFormat::Rgba8T8Z32;  // 8-byte rows
  auto kb = makeAlgorithm("kbuffer", p);
  const StateRanges r = kb->readRanges(0, InsertOutcome::Discarded);
  ASSERT_EQ(r.count, 1u);
  EXPECT_EQ(r.range[0].begin, 24u);
  EXPECT_EQ(r.range[0].end, 32u);
  EXPECT_EQ(kb->readBytes(0, InsertOutcome::Stored), 32u);
  // The decision really needs that row alone: k = 2 full of depths .2 and .4,
  // a fragment at .5 is behind the last row and is rejected.
  auto k2 = makeAlgorithm("kbuffer", layers(2));
  std::vector<uint32_t> w(k2->stateWords());
  k2->clear(w.data());
  InsertContext ctx;
  k2->insert(w.data(), frag(0, 0, 0.4f, 1, 0, 0, 0.5f), 0, ctx);
  k2->insert(w.data(), frag(0, 0, 0.2f, 1, 0, 0, 0.5f), 0, ctx);
  EXPECT_EQ(k2->insert(w.data(), frag(0, 0, 0.5f, 1, 0, 0, 0.5f), 0, ctx), InsertOutcome::Discarded);
}

TEST(StateRanges, SortedRowsResolveStopsAtTheFirstEmptyRowOrFullOpacity) {
  // mlab k = 4 fp32 (20-byte rows).
  auto m = makeAlgorithm("mlab", layers(4));
  std::vector<uint32_t> w(m->stateWords());
  m->clear(w.data());
  EXPECT_EQ(m->resolveBytes(w.data()), 20u);  // row 0 is read to see it is empty
  InsertContext ctx;
  m->insert(w.data(), frag(0, 0, 0.5f, 1, 0, 0, 0.5f), 0, ctx);
  EXPECT_EQ(m->resolveBytes(w.data()), 40u);  // one row, then the empty row 1
  m->insert(w.data(), frag(0, 0, 0.2f, 0, 1, 0, 1.0f), 0, ctx);  // opaque in front: T = 0 after row 0
  EXPECT_EQ(m->resolveBytes(w.data()), 20u);
  // The other algorithms read their whole state.
  auto alpha = makeAlgorithm("alpha", layers(4));
  std::vector<uint32_t> a(alpha->stateWords());
  alpha->clear(a.data());
  EXPECT_EQ(alpha->resolveBytes(a.data()), alpha->bytesPerPixel());
}
