#include "model/OitAlgorithm.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>

#include "model/AlgorithmDetail.hpp"

namespace oit::model {

const char* toString(InsertOutcome o) {
  switch (o) {
    case InsertOutcome::Stored: return "stored";
    case InsertOutcome::Merged: return "merged";
    case InsertOutcome::Discarded: return "discarded";
  }
  return "unknown";
}

void OitAlgorithm::clearFrame(uint32_t* words, size_t pixels) {
  if (pixels == 0) return;
  clear(words);
  // Doubling copies of the cleared prefix: log2(pixels) large memcpys.
  const size_t total = pixels * state_words_;
  for (size_t done = state_words_; done < total;) {
    const size_t n = std::min(done, total - done);
    std::memcpy(words + done, words, n * sizeof(uint32_t));
    done += n;
  }
}

std::string_view OitAlgorithm::passName(unsigned pass) const { return pass == 0 ? "insert" : "?"; }

void StateRanges::add(uint32_t begin, uint32_t end) {
  if (end <= begin) return;
  if (count == kMax || (count && begin < range[count - 1].end))
    throw std::logic_error("StateRanges::add: at most two increasing, disjoint ranges");
  range[count++] = {begin, end};
}

// Default RMW: the whole state is read; a Discarded insert leaves it unchanged
// and writes nothing, anything else writes the whole state back (upper bound).
StateRanges OitAlgorithm::readRanges(unsigned, InsertOutcome) const { return StateRanges::one(0, bytesPerPixel()); }
StateRanges OitAlgorithm::writeRanges(unsigned, InsertOutcome o) const {
  return o == InsertOutcome::Discarded ? StateRanges::none() : StateRanges::one(0, bytesPerPixel());
}

namespace {

struct Entry {
  AlgorithmInfo info;
  std::unique_ptr<OitAlgorithm> (*make)(const AlgorithmParams&);
};

const std::vector<Entry>& entries() {
  static const std::vector<Entry> e = {
      {{"abuffer", "exact reference: unbounded per-pixel lists, stable depth sort, double-precision compositing"},
       detail::makeABuffer},
      {{"alpha", "plain over-blending in submission order (a GPU without OIT)"}, detail::makeAlpha},
      {{"mlab", "multi-layer alpha blending (Salvi 2014): k sorted rows, merge the last two"},
       detail::makeMlab},
      {{"hybrid", "hybrid transparency (Maule 2013, one pass): k-1 sorted core rows + averaged tail"},
       detail::makeHybrid},
      {{"adaptive", "adaptive transparency (Salvi 2011): k-node vis(z), underestimate removal, 2 passes"},
       detail::makeAdaptive},
      {{"kbuffer", "k-buffer: keep the k nearest fragments, discard the furthest"}, detail::makeKBuffer},
      {{"wsum", "weighted sum (Meshkin 2007), output clamped to [0,1]"}, detail::makeWsum},
      {{"wavg", "weighted average (Bavoil & Myers 2008)"}, detail::makeWavg},
      {{"wboit", "weighted blended OIT (McGuire & Bavoil 2013), weight eq. 7, 8, 9 or 10"},
       detail::makeWboit},
      {{"slab", "stochastic layered alpha blending (Wyman 2016): k layers, b virtual bits, alpha-corrected colour pass"},
       detail::makeSlab},
      {{"stochastic", "stochastic transparency (Enderton 2010): S depth samples, alpha-corrected colour pass"},
       detail::makeStochastic},
      {{"mlcb", "multi-layer coverage blending (Wyman 2016): k sorted layers with b-bit pre-occluded masks, merge the last two"},
       detail::makeMlcb},
  };
  return e;
}

}  // namespace

const std::vector<AlgorithmInfo>& algorithmNames() {
  static const std::vector<AlgorithmInfo> names = [] {
    std::vector<AlgorithmInfo> v;
    for (const Entry& e : entries()) v.push_back(e.info);
    return v;
  }();
  return names;
}

std::unique_ptr<OitAlgorithm> makeAlgorithm(std::string_view name, const AlgorithmParams& params) {
  for (const Entry& e : entries())
    if (e.info.name == name) return e.make(params);
  std::string valid;
  for (const Entry& e : entries()) valid += (valid.empty() ? "" : ", ") + std::string(e.info.name);
  throw std::invalid_argument("unknown OIT algorithm '" + std::string(name) + "' (valid: " + valid + ")");
}

uint64_t fragmentHash(const Fragment& f, uint64_t seed, uint32_t stream) {
  // splitmix64 finaliser (Steele et al. 2014), applied to each 64-bit key word
  // in turn: a fixed function of the fragment's identity, no generator state.
  auto mix = [](uint64_t z) {
    z += 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  };
  uint64_t h = mix(seed);
  h = mix(h ^ (uint64_t(f.x) | uint64_t(f.y) << 16 | uint64_t(stream) << 32));
  h = mix(h ^ (uint64_t(f.draw) | uint64_t(f.prim) << 32));
  return h;
}

namespace detail {

void badParam(std::string_view algo, const std::string& what) {
  throw std::invalid_argument(std::string(algo) + ": " + what);
}

void requireLayers(std::string_view algo, const AlgorithmParams& p) {
  if (p.layers < 1 || p.layers > kMaxLayers)
    badParam(algo, "layers must be in 1.." + std::to_string(kMaxLayers) + ", got " +
                       std::to_string(p.layers));
}

void requireFormat(std::string_view algo, const AlgorithmParams& p,
                   std::initializer_list<StorageFormat> allowed) {
  std::string valid;
  for (StorageFormat f : allowed) {
    if (f == p.format) return;
    valid += (valid.empty() ? "" : ", ") + std::string(toString(f));
  }
  badParam(algo, std::string("storage format ") + toString(p.format) + " not supported (valid: " +
                     valid + ")");
}

}  // namespace detail
}  // namespace oit::model
