// Which of the run settings (`oitsim run --layers --format --bits --samples
// --weight --seed`) each algorithm uses. A setting an algorithm ignores leaves
// its image, counts and state size unchanged (tests/model/test_algorithm_settings.cpp
// checks it); the sweep plans points that differ only in ignored settings once,
// and `oitsim run` shows only the used ones. A setting an algorithm refuses
// beyond one value (e.g. adaptive's fp32-only format) counts as used: another
// value is an error, not a duplicate.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace oit::model {

struct AlgorithmSettings {
  bool layers = false, format = false, bits = false, samples = false, weight = false, seed = false;
};

// Throws std::invalid_argument naming the valid algorithms on an unknown name.
AlgorithmSettings algorithmSettings(std::string_view algorithm);

// The names of the settings `algorithm` ignores, in the order layers, format,
// bits, samples, weight, seed.
std::vector<std::string> ignoredSettings(std::string_view algorithm);

}  // namespace oit::model
