#include "traces/UnmodelledDraws.hpp"

namespace oit {

namespace {

std::string counted(uint64_t n, const char* what) { return std::to_string(n) + " " + what + (n == 1 ? "" : "s"); }

}  // namespace

UnmodelledDraws unmodelledDraws(const std::vector<DrawInfo>& draws) {
  UnmodelledDraws u;
  for (const DrawInfo& d : draws) {
    if (!d.state || d.state->recorded()) continue;
    const auto m = static_cast<size_t>(d.state->blend);
    if (m >= UnmodelledDraws::kModes) continue;  // the readers refuse such modes (H10)
    ++u.draws;
    u.fragments += d.state->fragments;
    ++u.draws_by_mode[m];
    u.fragments_by_mode[m] += d.state->fragments;
  }
  return u;
}

std::string UnmodelledDraws::describe() const {
  std::string s = counted(draws, "draw") + ", " + counted(fragments, "fragment");
  const char* sep = ": ";
  for (size_t m = 0; m < kModes; ++m) {
    if (!draws_by_mode[m]) continue;
    s += sep + std::string(toString(static_cast<BlendMode>(m))) + " " + counted(draws_by_mode[m], "draw") + " (" +
         counted(fragments_by_mode[m], "fragment") + ")";
    sep = ", ";
  }
  return s;
}

}  // namespace oit
