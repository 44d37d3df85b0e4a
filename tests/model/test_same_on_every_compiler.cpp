// The generated inputs of the stress suite and of the model tests are the same
// from every compiler. C++ leaves the order of a call's arguments (and of the
// operands of +) to the compiler: g++ evaluates them right to left, clang
// left to right, so two random draws in one call made other stress cases and
// other test scenes under clang (the stress table, and a count in
// test_approximate_lock_conflicts.cpp, differed between the g++ Release build
// and the clang sanitizer build). CI runs this file in both builds; the
// fingerprints are g++'s, the ones the committed stress table was made with.
#include <gtest/gtest.h>


#include "Fnv1a.hpp"
#include "model/AlgoTestUtil.hpp"
#include "model/StressSuite.hpp"

using namespace oit;
using namespace oit::model;
using namespace oit::model::stress;

namespace {

// FNV-1a over the fragments' bytes (Fragment has no padding: 32 bytes).
uint64_t fingerprint(const std::vector<Fragment>& fs, uint64_t h = test::kFnv1aOffset) {
  return test::fnv1a64(fs.data(), fs.size() * sizeof(Fragment), h);
}

TEST(SameOnEveryCompiler, StressCases) {
  uint64_t h = test::kFnv1aOffset;
  size_t n = 0;
  for (const std::string& name : caseNames()) {
    const StressCase c = makeCase(name);
    h = fingerprint(c.fragments, h);
    n += c.fragments.size();
  }
  EXPECT_EQ(n, 139816u);
  EXPECT_EQ(h, 0x1b99c9977c918049ull) << std::hex << "0x" << h;
}

TEST(SameOnEveryCompiler, RandomTestScene) {
  const auto fs = testutil::randomScene(24, 16, 12, 5);
  EXPECT_EQ(fs.size(), 2522u);
  EXPECT_EQ(fingerprint(fs), 0xe73c98331efa3e3dull) << std::hex << "0x" << fingerprint(fs);
}

}  // namespace
