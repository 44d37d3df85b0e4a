// The float specials the model tests feed to the code under test, defined once
// so that the test files also compile together (a unity build).
#pragma once

#include <limits>

namespace oit::model::testutil {

inline constexpr float kInf = std::numeric_limits<float>::infinity();
inline constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

}  // namespace oit::model::testutil
