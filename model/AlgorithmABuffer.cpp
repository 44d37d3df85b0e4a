// The exact reference: an A-buffer. Per pixel one word, the head of a linked
// list of nodes in the algorithm's own pool (as a GPU per-pixel linked list:
// head exchange + node append). Nodes keep the fragment's exact fp32 RGBA;
// resolve stable-sorts by depth and composites in double.
#include <algorithm>
#include <stdexcept>
#include <vector>

#include "model/AlgorithmDetail.hpp"

namespace oit::model::detail {
namespace {

constexpr uint32_t kNil = 0xFFFFFFFFu;

class ABuffer final : public OitAlgorithm {
 public:
  ABuffer() { setLayout({0, StorageFormat::Fp32, 1, "head of the pixel's node list (u32, ~0 = empty)"}); }
  std::string_view name() const override { return "abuffer"; }
  bool bounded() const override { return false; }
  uint64_t poolBytes() const override { return uint64_t(pool_.size()) * sizeof(Node); }

  void beginFrame(const TraceHeader&) override { pool_.clear(); }
  void clear(uint32_t* w) override { w[0] = kNil; }

  InsertOutcome insert(uint32_t* w, const Fragment& f, unsigned, const InsertContext&) override {
    // a = 0 fragments are kept: the reference composites whatever it is given.
    if (pool_.size() >= kNil) throw std::length_error("abuffer: node pool exceeds 2^32 - 1 nodes");
    pool_.push_back({f.z, f.r, f.g, f.b, f.a, w[0]});
    w[0] = uint32_t(pool_.size() - 1);
    return InsertOutcome::Stored;
  }

  Rgb resolve(const uint32_t* w, Rgb bg) override {
    // The list runs newest first; a stable sort by depth keeps equal depths
    // newest first, i.e. a later-submitted fragment in front (the tie rule).
    scratch_.clear();
    for (uint32_t i = w[0]; i != kNil; i = pool_[i].next) scratch_.push_back(&pool_[i]);
    std::stable_sort(scratch_.begin(), scratch_.end(), [](const Node* a, const Node* b) { return a->z < b->z; });
    double r = 0, g = 0, b = 0, T = 1;
    for (const Node* n : scratch_) {
      const double a = n->a;
      r += T * a * n->r;
      g += T * a * n->g;
      b += T * a * n->b;
      T *= 1.0 - a;
    }
    return finiteRgb(float(r + T * bg.r), float(g + T * bg.g), float(b + T * bg.b));
  }

  // Insert: read + write the head (an atomic exchange), write one node (in
  // the pool, not in the per-pixel state: the ranges cover the head only).
  unsigned readBytes(unsigned, InsertOutcome) const override { return 4; }
  unsigned writeBytes(unsigned, InsertOutcome) const override { return 4 + sizeof(Node); }
  StateRanges readRanges(unsigned, InsertOutcome) const override { return StateRanges::one(0, 4); }
  StateRanges writeRanges(unsigned, InsertOutcome) const override { return StateRanges::one(0, 4); }

 private:
  struct Node {
    float z, r, g, b, a;
    uint32_t next;
  };
  std::vector<Node> pool_;
  std::vector<const Node*> scratch_;
};

}  // namespace

// The reference ignores the storage format (and every other parameter): it
// always keeps exact fp32 fragments, so one params struct can drive a whole
// comparison run.
std::unique_ptr<OitAlgorithm> makeABuffer(const AlgorithmParams&) {
  return std::make_unique<ABuffer>();
}

}  // namespace oit::model::detail
