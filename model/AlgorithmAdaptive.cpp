// Adaptive transparency (Salvi et al. 2011), fixed-memory two-pass form.
// Pass 0 builds vis(z) in k nodes (z, cumulative vis, seq), removing on
// overflow the node j >= 1 minimising (vis_{j-1} - vis_j)(z_j - z_{j-1}) with
// the underestimate rule (node j-1 takes vis_j), so the total transmittance
// stays exact. Pass 1 composites every fragment with vis just in front of it.
//
// Ties: vis(z) alone cannot say which of two equal-depth fragments is in
// front, so each node keeps the per-pixel submission index (seq) of its
// fragment; nodes are ordered by (z ascending, seq descending), i.e. a
// later-submitted fragment is in front, and pass 1 recounts seq per pixel.
#include <algorithm>
#include <bit>
#include <string>

#include "model/AlgorithmDetail.hpp"

namespace oit::model::detail {
namespace {

class Adaptive final : public OitAlgorithm {
 public:
  explicit Adaptive(const AlgorithmParams& p) : k_(p.layers) {
    // words: [z, vis, seq] x k | acc r, g, b | seq counter pass 0 | seq counter pass 1
    setLayout({0, StorageFormat::Fp32, 3 * k_ + 5,
               "k nodes (z fp32, vis fp32, seq u32); colour accumulator r,g,b fp32; "
               "per-pass fragment counters (u32 x 2)"});
  }
  std::string_view name() const override { return "adaptive"; }
  unsigned passes() const override { return 2; }
  std::string_view passName(unsigned pass) const override {
    return pass == 0 ? "build vis(z)" : pass == 1 ? "composite" : "?";
  }

  void clear(uint32_t* w) override {
    for (unsigned i = 0; i < k_; ++i) {
      w[3 * i] = asWord(kInf);
      w[3 * i + 1] = asWord(1.0f);
      w[3 * i + 2] = 0;
    }
    for (unsigned i = 3 * k_; i < 3 * k_ + 5; ++i) w[i] = 0;
  }

  InsertOutcome insert(uint32_t* w, const Fragment& f, unsigned pass, const InsertContext& ctx) override {
    // a = 0 changes nothing and is skipped in both passes before counting, so
    // the per-pixel seq numbers of the two passes agree.
    if (noContribution(f)) {
      ctx.work = {0, 0};
      return InsertOutcome::Discarded;
    }
    return pass == 0 ? build(w, f, ctx.work) : shade(w, f, ctx.work);
  }

  Rgb resolve(const uint32_t* w, Rgb bg) override {
    float T = 1.0f;
    for (unsigned i = 0; i < k_ && asFloat(w[3 * i]) != kInf; ++i) T = asFloat(w[3 * i + 1]);
    const uint32_t* acc = w + 3 * k_;
    return finiteRgb(asFloat(acc[0]) + bg.r * T, asFloat(acc[1]) + bg.g * T, asFloat(acc[2]) + bg.b * T);
  }

  // Pass 0 reads and writes the nodes and its counter; pass 1 reads the nodes,
  // the accumulator and its counter, and writes the accumulator and counter.
  // Words: nodes [0, 3k), accumulator [3k, 3k + 3), counters 3k + 3 (pass 0), 3k + 4 (pass 1).
  StateRanges readRanges(unsigned pass, InsertOutcome) const override {
    const uint32_t nodes = 12 * k_;
    return pass == 0 ? StateRanges::two(0, nodes, nodes + 12, nodes + 16)
                     : StateRanges::two(0, nodes + 12, nodes + 16, nodes + 20);
  }
  StateRanges writeRanges(unsigned pass, InsertOutcome o) const override {
    if (o == InsertOutcome::Discarded) return StateRanges::none();
    const uint32_t nodes = 12 * k_;
    return pass == 0 ? StateRanges::two(0, nodes, nodes + 12, nodes + 16)
                     : StateRanges::two(nodes, nodes + 12, nodes + 16, nodes + 20);
  }

 private:
  // Work: the position search compares nodes 0..p; the new node and every
  // node behind it (shifted, vis rescaled) are written; a compression adds
  // one removal metric per candidate node (k) and rewrites the nodes from the
  // removed one (shifted, plus the predecessor's vis).
  InsertOutcome build(uint32_t* w, const Fragment& f, InsertWork& work) {
    uint32_t& counter = w[3 * k_ + 3];
    const uint32_t seq = counter++;
    float z[kMaxLayers + 1], vis[kMaxLayers + 1];
    uint32_t sq[kMaxLayers + 1];
    unsigned n = 0;
    for (; n < k_ && asFloat(w[3 * n]) != kInf; ++n) {
      z[n] = asFloat(w[3 * n]);
      vis[n] = asFloat(w[3 * n + 1]);
      sq[n] = w[3 * n + 2];
    }
    // The new fragment is the latest: in front of every node of equal depth.
    unsigned p = 0;
    while (p < n && z[p] < f.z) ++p;
    const float t = 1.0f - f.a;
    for (unsigned i = n; i > p; --i) {
      z[i] = z[i - 1];
      vis[i] = vis[i - 1] * t;  // everything behind is attenuated by the new step
      sq[i] = sq[i - 1];
    }
    unsigned compares = std::min(p + 1, n), moves = n - p + 1;
    z[p] = f.z;
    vis[p] = (p > 0 ? vis[p - 1] : 1.0f) * t;
    sq[p] = seq;
    ++n;
    InsertOutcome o = InsertOutcome::Stored;
    if (n > k_) {
      // Node 0's predecessor is the implicit (vis 1) node, which the
      // underestimate rule cannot modify: candidates are j >= 1.
      // Key (area, step, -j), smallest first. Equal depths have zero area
      // whatever their visibility, so the area alone cannot rank them; the
      // step vis[j-1] - vis[j] is the visibility error the removal gives the
      // fragments at node j's depth, so the smallest step goes, and of equal
      // steps the last node (front nodes stay exact). Before this, "first
      // minimum wins" removed node 1 again and again in an equal-depth stack,
      // collapsing the front fragment's node to the whole stack's vis.
      unsigned best = 1;
      float bestArea = (vis[0] - vis[1]) * (z[1] - z[0]);
      float bestStep = vis[0] - vis[1];
      for (unsigned j = 2; j < n; ++j) {
        const float area = (vis[j - 1] - vis[j]) * (z[j] - z[j - 1]);
        const float step = vis[j - 1] - vis[j];
        if (area < bestArea || (area == bestArea && step <= bestStep)) {
          bestArea = area;
          bestStep = step;
          best = j;
        }
      }
      compares += n - 1;
      moves += n - best;
      vis[best - 1] = vis[best];
      for (unsigned j = best; j + 1 < n; ++j) {
        z[j] = z[j + 1];
        vis[j] = vis[j + 1];
        sq[j] = sq[j + 1];
      }
      --n;
      o = InsertOutcome::Merged;
    }
    for (unsigned i = 0; i < n; ++i) {
      w[3 * i] = asWord(z[i]);
      w[3 * i + 1] = asWord(vis[i]);
      w[3 * i + 2] = sq[i];
    }
    work = {uint8_t(std::min(255u, compares)), uint8_t(std::min(255u, moves))};
    return o;
  }

  // Work: the nodes compared until the first one behind, one accumulator written.
  InsertOutcome shade(uint32_t* w, const Fragment& f, InsertWork& work) {
    uint32_t& counter = w[3 * k_ + 4];
    const uint32_t seq = counter++;
    // vis just in front of the fragment: the last node that is nearer, or of
    // equal depth and submitted later (nodes are sorted that way).
    float v = 1.0f;
    unsigned i = 0;
    for (; i < k_; ++i) {
      const float zi = asFloat(w[3 * i]);
      if (zi < f.z || (zi == f.z && w[3 * i + 2] > seq))
        v = asFloat(w[3 * i + 1]);
      else
        break;
    }
    work = {uint8_t(std::min(255u, std::min(i + 1, k_))), 1};
    uint32_t* acc = w + 3 * k_;
    const float va = v * f.a;
    acc[0] = asWord(asFloat(acc[0]) + va * f.r);
    acc[1] = asWord(asFloat(acc[1]) + va * f.g);
    acc[2] = asWord(asFloat(acc[2]) + va * f.b);
    return InsertOutcome::Stored;
  }

  unsigned k_;
};

}  // namespace

std::unique_ptr<OitAlgorithm> makeAdaptive(const AlgorithmParams& p) {
  requireLayers("adaptive", p);
  requireFormat("adaptive", p, {StorageFormat::Fp32});
  return std::make_unique<Adaptive>(p);
}

}  // namespace oit::model::detail
