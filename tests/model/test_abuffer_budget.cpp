// The A-buffer under test's budgets (pool, local array, node format) and the
// work each algorithm's insert reports (InsertWork), with hand-derived values.
#include <gtest/gtest.h>

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "AlgoTestUtil.hpp"

namespace oit::model {
namespace {

using testutil::frag;
using testutil::render;

AlgorithmParams budget(uint64_t pool_bytes, unsigned max_sorted = 0,
                       ABufferOverflow overflow = ABufferOverflow::Spill) {
  AlgorithmParams p;
  p.abuffer.pool_bytes = pool_bytes;
  p.abuffer.max_sorted = max_sorted;
  p.abuffer.overflow = overflow;
  return p;
}

// Node bytes follow the storage format: colour (rgba8 4, fp16 8, fp32 16) + z + next.
TEST(ABufferBudget, NodeBytesFollowTheFormat) {
  AlgorithmParams p;
  p.format = StorageFormat::Rgba8T8Z32;
  EXPECT_EQ(makeAlgorithm("abuffer", p)->poolNodeBytes(), 12u);  // the MLAB paper's 12 B per fragment
  p.format = StorageFormat::Fp16;
  EXPECT_EQ(makeAlgorithm("abuffer", p)->poolNodeBytes(), 16u);
  p.format = StorageFormat::Fp32;
  EXPECT_EQ(makeAlgorithm("abuffer", p)->poolNodeBytes(), 24u);
}

// The pool holds (pool_bytes - 4 W H) / node_bytes nodes; the counter runs
// past it and every later fragment is dropped (Discarded), whatever its pixel.
// 4x4 frame: heads 64 B; 64 + 5 x 24 + 10 = 194 B holds 5 fp32 nodes.
// The image equals the exact A-buffer of the 5 kept (the first 5 submitted).
TEST(ABufferBudget, PoolOverflowDropsExactlyTheFragmentsPastThePool) {
  const std::vector<Fragment> fs = testutil::randomScene(4, 4, 3, 11, 1);
  ASSERT_GT(fs.size(), 5u);
  const RenderResult r = render("abuffer", budget(64 + 5 * 24 + 10), fs, 4, 4);
  EXPECT_EQ(r.counts.stored, 5u);
  EXPECT_EQ(r.counts.discarded, fs.size() - 5);  // fragments.dropped_pool_full
  EXPECT_EQ(r.state_bytes, 64u + 5 * 24);        // heads + the pool as allocated
  const std::vector<Fragment> kept(fs.begin(), fs.begin() + 5);
  const RenderResult exact = render("abuffer", {}, kept, 4, 4);
  EXPECT_EQ(testutil::maxDiff(r.image, exact.image), 0.0);
}

TEST(ABufferBudget, PoolSizedByNodesPerPixel) {
  AlgorithmParams p;
  p.abuffer.nodes_per_pixel = 0.5;  // 4x4: 8 nodes
  const std::vector<Fragment> fs = testutil::randomScene(4, 4, 3, 5, 2);  // >= 32 fragments
  const RenderResult r = render("abuffer", p, fs, 4, 4);
  EXPECT_EQ(r.counts.stored, 8u);
  EXPECT_EQ(r.counts.discarded, fs.size() - 8);
}

TEST(ABufferBudget, APoolThatCannotHoldTheHeadsIsRefusedNamingIt) {
  try {
    capacityNodes(budget(64 + 23).abuffer, 4, 4, 24);  // heads 64 B + less than one node
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("abuffer.pool_bytes 87 cannot hold the heads (64 B for 4 x 4 pixels)"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(capacityNodes(budget(64 + 24).abuffer, 4, 4, 24), 1u);
  EXPECT_EQ(capacityNodes(ABufferBudget{}, 4, 4, 24), UINT64_MAX);
}

// One pixel, 5 fragments submitted at depths .5 .1 .4 .2 .3 (the list runs
// newest first: .3 .2 .4 .1 .5). Truncate at 3: the resolve composites the
// 3 newest (.3 .2 .4) only = the exact A-buffer of those three.
TEST(ABufferBudget, TruncateCompositesTheFirstMaxSortedNodesOfTheList) {
  const float z[5] = {0.5f, 0.1f, 0.4f, 0.2f, 0.3f};
  std::vector<Fragment> fs;
  for (unsigned i = 0; i < 5; ++i) fs.push_back(frag(0, 0, z[i], 0.2f * i, 1 - 0.2f * i, 0.5f, 0.4f));
  const RenderResult t = render("abuffer", budget(0, 3, ABufferOverflow::Truncate), fs, 1, 1);
  const RenderResult newest3 = render("abuffer", {}, std::vector<Fragment>(fs.begin() + 2, fs.end()), 1, 1);
  EXPECT_EQ(testutil::maxDiff(t.image, newest3.image), 0.0);
  const RenderResult exact = render("abuffer", {}, fs, 1, 1);
  EXPECT_GT(testutil::maxDiff(t.image, exact.image), 0.01);  // visible in the image
  // Spill sorts everything: exact.
  const RenderResult s = render("abuffer", budget(0, 3, ABufferOverflow::Spill), fs, 1, 1);
  EXPECT_EQ(testutil::maxDiff(s.image, exact.image), 0.0);
}

// resolveWork of that pixel: list .3 .2 .4 .1 .5 (newest first). Insertion
// sort into the local array:
//  .3: -                      0 compares, 0 moves
//  .2: < .3: move .3, reach the front     1 compare, 1 move
//  .4: not < .3: stop                     1 compare
//  .1: moves past .4 .3 .2, front         3 compares, 3 moves
//  .5: not < .4: stop                     1 compare
// = 6 compares, 4 moves. Truncate at 3: .3 .2 .4 only: 2 compares, 1 move.
TEST(ABufferBudget, ResolveWorkCountsTheWalkAndTheInsertionSort) {
  const float z[5] = {0.5f, 0.1f, 0.4f, 0.2f, 0.3f};
  auto a = makeAlgorithm("abuffer", AlgorithmParams{});
  auto t = makeAlgorithm("abuffer", budget(0, 3, ABufferOverflow::Truncate));
  auto s = makeAlgorithm("abuffer", budget(0, 3, ABufferOverflow::Spill));
  for (auto* algo : {a.get(), t.get(), s.get()}) {
    algo->beginFrame(testutil::header(1, 1));
    uint32_t head;
    algo->clear(&head);
    for (float d : z) algo->insert(&head, frag(0, 0, d, 1, 1, 1, 0.5f), 0, {});
    const ResolveWork w = algo->resolveWork(&head);
    EXPECT_EQ(w.nodes, 5u);
    if (algo == t.get()) {
      EXPECT_EQ(w.sorted, 3u);
      EXPECT_EQ(w.spilled, 2u);
      EXPECT_EQ(w.compares, 2u);
      EXPECT_EQ(w.moves, 1u);
    } else {
      EXPECT_EQ(w.sorted, 5u);
      EXPECT_EQ(w.spilled, algo == s.get() ? 2u : 0u);
      EXPECT_EQ(w.compares, 6u);
      EXPECT_EQ(w.moves, 4u);
    }
  }
}

// One pixel of `name` with k rows, and the work of each insert into it.
struct OnePixel {
  std::unique_ptr<OitAlgorithm> algo;
  std::vector<uint32_t> words;
  OnePixel(const char* name, unsigned k) : algo(makeAlgorithm(name, testutil::layers(k))), words(algo->stateWords()) {
    algo->beginFrame(testutil::header(1, 1));
    algo->clear(words.data());
  }
  InsertWork insert(float z, float a = 0.5f, unsigned pass = 0, InsertOutcome* outcome = nullptr) {
    InsertContext ctx;
    const InsertOutcome o = algo->insertFn()(*algo, words.data(), frag(0, 0, z, 1, 0, 0, a), pass, ctx);
    if (outcome) *outcome = o;
    return ctx.work;
  }
};
void expectWork(InsertWork got, InsertWork want, const std::string& what) {
  EXPECT_EQ(got.compares, want.compares) << what;
  EXPECT_EQ(got.moves, want.moves) << what;
}

// The work an insert reports, mlab k = 4 (fp32), one pixel:
//  1st at .5 into the empty array: slot 0 (1 compare), writes its row: {1, 1}
//  2nd at .3: slot 0 (1 compare), shifts .5, writes its row: {1, 2}
//  3rd at .4: slot 1 (2 compares), shifts .5: {2, 2}
//  4th at .6: slot 3 (4 compares), its row only: {4, 1}
//  5th at .1: full array, slot 0: rows 0..3 rewritten (merge of the last two): {1, 4}
//  6th at .9: behind every row: 4 compares, merged into the last row: {4, 1}
TEST(InsertWork, MlabCountsTheSlotSearchAndTheRowsWritten) {
  OnePixel px("mlab", 4);
  const float z[6] = {0.5f, 0.3f, 0.4f, 0.6f, 0.1f, 0.9f};
  const InsertWork want[6] = {{1, 1}, {1, 2}, {2, 2}, {4, 1}, {1, 4}, {4, 1}};
  for (unsigned i = 0; i < 6; ++i) expectWork(px.insert(z[i]), want[i], "insert " + std::to_string(i));
}

// kbuffer k = 2: a rejection reads and compares the last row only and writes nothing.
TEST(InsertWork, KBufferRejectionComparesOneRow) {
  OnePixel px("kbuffer", 2);
  px.insert(0.2f);
  expectWork(px.insert(0.3f), {2, 1}, "slot 1");
  InsertOutcome o;
  expectWork(px.insert(0.9f, 0.5f, 0, &o), {1, 0}, "rejected");
  EXPECT_EQ(o, InsertOutcome::Discarded);
}

// adaptive k = 2, pass 0: the third node forces a compression.
//  .5: no node to compare with (min(p + 1, n) = 0), its node: {0, 1};
//  .3: slot 0 (1 compare), new node + .5 rescaled: {1, 2};
//  .4: slot 1 (2 compares), new + .5 = 2 writes; 3 nodes > k: the removal
//  metric for j = 1, 2 (2 compares) and the rewrite from the removed node:
//  node 2 removed (the smallest area) -> n - best = 1 write. Total {4, 3}.
// Pass 1 (composite): the nodes compared until the first one behind (1 or
// 2 here, by the nodes the compression kept), one accumulator.
TEST(InsertWork, AdaptiveCountsInsertAndCompress) {
  OnePixel px("adaptive", 2);
  expectWork(px.insert(0.5f), {0, 1}, ".5");
  expectWork(px.insert(0.3f), {1, 2}, ".3");
  InsertOutcome o;
  expectWork(px.insert(0.4f, 0.5f, 0, &o), {2 + 2, 2 + 1}, ".4");
  EXPECT_EQ(o, InsertOutcome::Merged);
  const InsertWork shade = px.insert(0.45f, 0.5f, 1);
  EXPECT_EQ(shade.moves, 1u);
  EXPECT_GE(shade.compares, 1u);
  EXPECT_LE(shade.compares, 2u);
}

// Accumulating algorithms write one accumulator and compare nothing; a = 0 does nothing.
TEST(InsertWork, AccumulatorsWriteOneRow) {
  for (const char* name : {"alpha", "wsum", "wavg", "wboit"}) {
    OnePixel px(name, 1);
    expectWork(px.insert(0.5f), {0, 1}, name);
    expectWork(px.insert(0.5f, 0.0f), {0, 0}, std::string(name) + " a = 0");
  }
}

}  // namespace
}  // namespace oit::model
