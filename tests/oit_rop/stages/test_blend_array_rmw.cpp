// BlendArrayRmw: the inserts of lock.mode unordered (in place, at entry) and
// none (read at entry into a private copy, written at the blend's end), with
// the lost updates of overlapping read-modify-writes counted by hand.
#include <gtest/gtest.h>

#include <limits>
#include <vector>

#include "model/AlgoTestUtil.hpp"
#include "oit_rop/stages/BlendArrayRmw.hpp"

using namespace oit;
using namespace oit::rop;
using model::testutil::frag;

namespace {

// A 2x1 frame's per-pixel state for `algo`, cleared, no opaque surface.
struct Frame {
  explicit Frame(const std::string& algo)
      : a(model::makeAlgorithm(algo, {})),
        words(size_t(2) * a->stateWords()),
        opaque(2, std::numeric_limits<float>::infinity()),
        nodes(1, 0),
        updates(2, 0) {
    a->beginFrame(model::testutil::header(2, 1));
    a->clearFrame(words.data(), 2);
  }
  FrontEnd::PixelState state(LockMode mode) {
    return {a.get(),       words.data(), a->stateWords(), 2, opaque.data(), a->bounded() ? nullptr : nodes.data(),
            mode == LockMode::None ? updates.data() : nullptr};
  }
  // Pixel (0, 0) after inserting `fs` in this order into a cleared array.
  std::vector<uint32_t> inserted(const std::vector<Fragment>& fs) {
    auto b = model::makeAlgorithm("alpha", {});
    std::vector<uint32_t> w(b->stateWords());
    b->clear(w.data());
    for (const Fragment& f : fs) b->insert(w.data(), f, 0, {});
    return w;
  }
  std::vector<uint32_t> pixel0() const { return {words.begin(), words.begin() + a->stateWords()}; }
  std::unique_ptr<model::OitAlgorithm> a;
  std::vector<uint32_t> words;
  std::vector<float> opaque;
  std::vector<uint32_t> nodes, updates;
};

// Alpha blending is order-dependent: red then green differs from green then red.
const Fragment kRed = frag(0, 0, 0.3f, 1, 0, 0, 0.5f);
const Fragment kGreen = frag(0, 0, 0.6f, 0, 1, 0, 0.5f);
const Fragment kBlue = frag(0, 0, 0.4f, 0, 0, 1, 0.5f);

TEST(BlendArrayRmw, UnorderedInsertsInPlaceInEntryOrder) {
  Frame fr("alpha");
  BlendArrayRmw rmw(LockMode::Unordered, fr.state(LockMode::Unordered), 4, 1);
  rmw.hold(0, kRed);    // submitted first
  rmw.hold(1, kGreen);  // entered first
  EXPECT_EQ(rmw.enter(1, 0, 0), model::InsertOutcome::Stored);
  EXPECT_EQ(fr.pixel0(), fr.inserted({kGreen}));  // in place at entry, before its blend ends
  EXPECT_EQ(rmw.enter(0, 0, 0), model::InsertOutcome::Stored);
  rmw.complete(1);
  rmw.complete(0);
  EXPECT_EQ(fr.pixel0(), fr.inserted({kGreen, kRed}));
  ASSERT_NE(fr.inserted({kGreen, kRed}), fr.inserted({kRed, kGreen}));  // the order shows
  EXPECT_EQ(rmw.passOutcomes()[0][size_t(model::InsertOutcome::Stored)], 2u);
  EXPECT_EQ(rmw.lostUpdates(), 0u);
}

// Two read-modify-writes that overlap (both read the cleared array): the
// later write overwrites the earlier one's update, one update lost, and the
// pixel holds the later writer's insert alone.
TEST(BlendArrayRmw, NoneOverlappingWritesLoseOneUpdate) {
  Frame fr("alpha");
  BlendArrayRmw rmw(LockMode::None, fr.state(LockMode::None), 4, 1);
  rmw.hold(0, kRed);
  rmw.hold(1, kGreen);
  rmw.enter(0, 0, 0);
  rmw.enter(1, 0, 0);
  EXPECT_EQ(fr.pixel0(), fr.inserted({}));  // nothing written before a blend ends
  rmw.complete(0);
  EXPECT_EQ(fr.pixel0(), fr.inserted({kRed}));
  rmw.complete(1);
  EXPECT_EQ(fr.pixel0(), fr.inserted({kGreen}));
  EXPECT_EQ(rmw.lostUpdates(), 1u);
  EXPECT_EQ(rmw.passOutcomes()[0][size_t(model::InsertOutcome::Stored)], 2u);  // each fragment's own outcome
}

TEST(BlendArrayRmw, NoneSequentialWritesLoseNothing) {
  Frame fr("alpha");
  BlendArrayRmw rmw(LockMode::None, fr.state(LockMode::None), 4, 1);
  rmw.hold(2, kRed);
  rmw.hold(3, kGreen);
  rmw.enter(2, 0, 0);
  rmw.complete(2);
  rmw.enter(3, 0, 0);
  rmw.complete(3);
  EXPECT_EQ(fr.pixel0(), fr.inserted({kRed, kGreen}));
  EXPECT_EQ(rmw.lostUpdates(), 0u);
}

// Nested races: X and A read the cleared array; A writes {A}; B reads {A};
// X writes {X} (A's update overwritten: 1 lost); B writes {A, B} (X's update
// overwritten, A's back: still 1 lost). Three writes, two updates held at the
// end: 3 - 2 = 1, not the 2 overwrites.
TEST(BlendArrayRmw, NoneCountsUpdatesMissingFromTheFinalArray) {
  Frame fr("alpha");
  BlendArrayRmw rmw(LockMode::None, fr.state(LockMode::None), 4, 1);
  rmw.hold(0, kBlue);   // X
  rmw.hold(1, kRed);    // A
  rmw.hold(2, kGreen);  // B
  rmw.enter(0, 0, 0);
  rmw.enter(1, 0, 0);
  rmw.complete(1);
  rmw.enter(2, 0, 0);
  rmw.complete(0);
  EXPECT_EQ(rmw.lostUpdates(), 1u);
  EXPECT_EQ(fr.pixel0(), fr.inserted({kBlue}));
  rmw.complete(2);
  EXPECT_EQ(rmw.lostUpdates(), 1u);
  EXPECT_EQ(fr.pixel0(), fr.inserted({kRed, kGreen}));
  EXPECT_EQ(fr.updates[0], 2u);
}

// A fragment whose insert writes nothing (a = 0: Discarded, writeBytes 0)
// cannot overwrite anything.
TEST(BlendArrayRmw, NoneDiscardedFragmentWritesNothing) {
  Frame fr("alpha");
  BlendArrayRmw rmw(LockMode::None, fr.state(LockMode::None), 4, 1);
  rmw.hold(0, kRed);
  rmw.hold(1, frag(0, 0, 0.5f, 0, 1, 0, 0.0f));
  rmw.enter(0, 0, 0);
  EXPECT_EQ(rmw.enter(1, 0, 0), model::InsertOutcome::Discarded);
  rmw.complete(0);
  rmw.complete(1);
  EXPECT_EQ(fr.pixel0(), fr.inserted({kRed}));
  EXPECT_EQ(rmw.lostUpdates(), 0u);
}

// The A-buffer's nodes per tile (the resolve reads them) are counted at entry.
TEST(BlendArrayRmw, AbufferNodesCountedPerTileAtEntry) {
  Frame fr("abuffer");
  BlendArrayRmw rmw(LockMode::Unordered, fr.state(LockMode::Unordered), 4, 1);
  rmw.hold(0, kRed);
  rmw.hold(1, frag(1, 0, 0.6f, 0, 1, 0, 0.5f));
  rmw.enter(0, 0, 0);
  rmw.enter(1, 0, 0);
  EXPECT_EQ(fr.nodes[0], 2u);
}

TEST(BlendArrayRmw, OrderedIsTheFrontEndsJob) {
  Frame fr("alpha");
  EXPECT_THROW(BlendArrayRmw(LockMode::Ordered, fr.state(LockMode::Ordered), 4, 1), std::logic_error);
  EXPECT_THROW(BlendArrayRmw(LockMode::None, fr.state(LockMode::Unordered), 4, 1), std::logic_error);  // no counts
}

}  // namespace
