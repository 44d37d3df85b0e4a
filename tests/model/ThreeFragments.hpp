// Three fragments at one pixel, submitted at depths .2, .8, .5 (red, green, blue;
// alpha .5, .25, .75): the hand-computed cases of test_algorithms_by_hand.cpp and
// the outcome counts of test_algorithms.cpp.
#pragma once

#include <vector>

#include "AlgoTestUtil.hpp"

namespace oit::model::testutil {

inline std::vector<Fragment> threeFragments() {
  return {frag(0, 0, 0.2f, 1, 0, 0, 0.5f), frag(0, 0, 0.8f, 0, 1, 0, 0.25f), frag(0, 0, 0.5f, 0, 0, 1, 0.75f)};
}

}  // namespace oit::model::testutil
