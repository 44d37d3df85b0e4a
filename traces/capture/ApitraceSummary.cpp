// frameSummary: what `oitsim capture --apitrace` prints per frame.
#include <array>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "traces/capture/ApitraceCapture.hpp"
#include "traces/capture/interposer/BlendClass.hpp"

namespace oit::capture {

namespace {

// "0, 3-7, 12"
std::string ranges(const std::vector<uint32_t>& ids) {
  std::string s;
  for (size_t i = 0; i < ids.size();) {
    size_t j = i;
    while (j + 1 < ids.size() && ids[j + 1] == ids[j] + 1) ++j;
    if (!s.empty()) s += ", ";
    s += j > i ? fmt::format("{}-{}", ids[i], ids[j]) : fmt::format("{}", ids[i]);
    i = j + 1;
  }
  return s;
}

}  // namespace

std::string frameSummary(const FrameCapture& f, const std::string& output) {
  using namespace stream;
  std::string s = fmt::format("frame {} -> {}: {} fragments, {} x {}, {} draw calls", f.frame, output,
                              f.fragments.size(), f.header.width, f.header.height, f.draw_calls);
  // The captured draws by blend mode, from the draw table's states.
  constexpr size_t kModes = static_cast<size_t>(oit::BlendMode::Other) + 1;
  std::array<uint64_t, kModes> draws_by_mode{}, fragments_by_mode{};
  for (const DrawInfo& d : f.header.draws) {
    // A captured frame is format v2: readStream's addDraw gives every draw its
    // state (FrameCapture::header); a draw without one is a caller's error.
    if (!d.state)
      throw std::logic_error(fmt::format("frameSummary: frame {}: draw {} has no draw state", f.frame, d.id));
    const auto m = static_cast<size_t>(d.state->blend);
    ++draws_by_mode[m];
    fragments_by_mode[m] += d.state->fragments;
  }
  std::vector<std::string> modelled, unmodelled;
  for (uint32_t m = 0; m < kModes; ++m) {
    if (!draws_by_mode[m]) continue;
    const std::string part =
        fmt::format("{} {} ({} fragments)", draws_by_mode[m], blendModeName(m), fragments_by_mode[m]);
    (m <= kBlendPremulOver ? modelled : unmodelled).push_back(part);
  }
  s += fmt::format("\n  captured: {}", modelled.empty() ? std::string("none") : fmt::format("{}", fmt::join(modelled, ", ")));
  if (!unmodelled.empty())
    s += fmt::format("\n  not modelled (in the draw table, fragments not recorded): {}", fmt::join(unmodelled, ", "));
  std::map<uint32_t, std::vector<uint32_t>> by_reason;
  for (const UncapturedDraw& u : f.uncaptured) by_reason[u.reason].push_back(u.index);
  if (!by_reason.empty()) {
    s += fmt::format("\n  not captured: {} draw{}", f.uncaptured.size(), f.uncaptured.size() == 1 ? "" : "s");
    for (const auto& [reason, ids] : by_reason) s += fmt::format("\n    {}: draw{} {}", reasonName(reason), ids.size() == 1 ? "" : "s", ranges(ids));
  }
  std::vector<std::string> notes;
  if (f.late_depth_draws)
    notes.push_back(fmt::format("{} draw{} recorded before the depth test (the program discards or writes depth)",
                                f.late_depth_draws, f.late_depth_draws == 1 ? "" : "s"));
  if (f.multi_draws)
    notes.push_back(fmt::format("{} instanced or multi-draw call{} (primitive ids restart per instance)", f.multi_draws,
                                f.multi_draws == 1 ? "" : "s"));
  if (f.colour_clamped) notes.push_back(fmt::format("{} fragments with colour clamped into [0, 1]", f.colour_clamped));
  if (f.depth_clamped) notes.push_back(fmt::format("{} fragments with depth clamped into [0, 1]", f.depth_clamped));
  if (f.premultiplied_clamped)
    notes.push_back(fmt::format("{} premultiplied colour components above their alpha (straight colour clamped to 1)",
                                f.premultiplied_clamped));
  if (f.premultiplied_zero_alpha)
    notes.push_back(fmt::format("{} premultiplied fragments with colour over alpha 0 (recorded black)",
                                f.premultiplied_zero_alpha));
  if (!notes.empty()) s += fmt::format("\n  notes: {}", fmt::join(notes, "; "));
  return s;
}

}  // namespace oit::capture
