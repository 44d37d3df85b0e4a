// The draws of a version 2 trace whose blend mode the model does not blend
// (additive, multiplicative, other; FORMAT.md 3.1): their fragments are counted in
// the draw state table and are in no record, so a run counts them as this outcome,
// apart from the records it replays, and they are missing from its image.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "traces/Fragment.hpp"

namespace oit {

struct UnmodelledDraws {
  static constexpr size_t kModes = 6;  // BlendMode values
  uint64_t draws = 0, fragments = 0;
  uint64_t draws_by_mode[kModes] = {}, fragments_by_mode[kModes] = {};
  // "2 draws, 19 fragments: additive 1 draw (7 fragments), multiplicative 1 draw (12 fragments)"
  std::string describe() const;
};

UnmodelledDraws unmodelledDraws(const std::vector<DrawInfo>& draws);

}  // namespace oit
