// The A-buffer as a GPU builds it (Yang et al. 2010): per pixel one word, the
// head of a linked list of nodes in a preallocated pool (an atomic increment
// of a global node counter, an atomic exchange of the head, a node write).
// Nodes keep the fragment's straight RGBA in the storage format (rgba8t8z32:
// the published 12-byte node; fp32: exact), its depth and the next pointer.
// Resolve: walk the list into a local array, stable-sort by depth, composite
// in double. With the default budget (unlimited pool, unlimited local array,
// fp32) it is the exact reference every run is measured against.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "model/AlgorithmDetail.hpp"

namespace oit::model::detail {
namespace {

constexpr uint32_t kNil = 0xFFFFFFFFu;
constexpr uint64_t kUnlimited = std::numeric_limits<uint64_t>::max();

class ABuffer final : public OitAlgorithm {
 public:
  explicit ABuffer(const AlgorithmParams& p) : fmt_(p.format), budget_(p.abuffer) {
    setLayout({0, StorageFormat::Fp32, 1, "head of the pixel's node list (u32, ~0 = empty)"});
    if (budget_.nodes_per_pixel < 0.0 || !std::isfinite(budget_.nodes_per_pixel))
      badParam("abuffer", "abuffer.nodes_per_pixel must be finite and >= 0");
  }
  std::string_view name() const override { return "abuffer"; }
  bool bounded() const override { return false; }
  // Allocated: the whole pool when it is preallocated (whatever the scene),
  // the nodes used when it is unlimited (the reference).
  uint64_t poolBytes() const override {
    return uint64_t(capacity_ == kUnlimited ? pool_.size() : capacity_) * poolNodeBytes();
  }
  // Colour in the storage format (rgba8 4 B, fp16 8 B, fp32 16 B) + z + next.
  unsigned poolNodeBytes() const override { return colourBytes(fmt_) + 8u; }
  uint64_t poolCapacityNodes() const override { return capacity_; }

  void beginFrame(const TraceHeader& h) override {
    pool_.clear();
    capacity_ = capacityNodes(budget_, h.width, h.height, poolNodeBytes());
  }
  // Host memory per stored node (the model keeps fp32 fields whatever the
  // storage format): oitsim run's memory estimate and the banded reference.
  uint64_t poolBytesPerFragment() const override { return sizeof(Node); }
  void reservePool(uint64_t fragments) override {
    if (fragments > kNil) throw std::length_error("abuffer: node pool exceeds 2^32 - 1 nodes");
    if (fragments > pool_.capacity()) {
      pool_ = std::vector<Node>();  // free first: the old nodes need no copy
      pool_.reserve(size_t(fragments));
    }
  }

  void clear(uint32_t* w) override { w[0] = kNil; }

  InsertOutcome insert(uint32_t* w, const Fragment& f, unsigned, const InsertContext& ctx) override {
    // a = 0 fragments are kept: the reference composites whatever it is given.
    if (pool_.size() >= capacity_) {  // the counter ran past the pool: the fragment is dropped
      ctx.work = {0, 0};
      return InsertOutcome::Discarded;
    }
    if (pool_.size() >= kNil) throw std::length_error("abuffer: node pool exceeds 2^32 - 1 nodes");
    pool_.push_back({f.z, quantized(f.r), quantized(f.g), quantized(f.b), quantized(f.a), w[0]});
    w[0] = uint32_t(pool_.size() - 1);
    ctx.work = {0, 1};
    return InsertOutcome::Stored;
  }

  Rgb resolve(const uint32_t* w, Rgb bg) override {
    // The list runs newest first; a stable sort by depth keeps equal depths
    // newest first, i.e. a later-submitted fragment in front (the tie rule).
    gather(w);
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

  ResolveWork resolveWork(const uint32_t* w) const override {
    ResolveWork rw;
    for (uint32_t i = w[0]; i != kNil; i = pool_[i].next) ++rw.nodes;
    const uint32_t limit = budget_.max_sorted == 0 ? rw.nodes : std::min<uint32_t>(rw.nodes, budget_.max_sorted);
    rw.spilled = rw.nodes - limit;
    // Insertion sort of what is sorted (Spill: every node; Truncate: the first
    // max_sorted): each node is compared with the sorted ones behind it until
    // one is not deeper (one compare more unless it reaches the front) and
    // moves past every deeper one. Strictly deeper moves: the stable order.
    const uint32_t sorted = budget_.overflow == ABufferOverflow::Truncate ? limit : rw.nodes;
    rw.sorted = sorted;
    float z[kSortProbe];
    std::vector<float> zs;
    float* a = z;
    if (sorted > kSortProbe) {
      zs.resize(sorted);
      a = zs.data();
    }
    uint32_t n = 0;
    for (uint32_t i = w[0]; i != kNil && n < sorted; i = pool_[i].next) {
      const float v = pool_[i].z;
      uint32_t j = n;
      while (j > 0 && a[j - 1] > v) {
        a[j] = a[j - 1];
        --j;
        ++rw.compares;
        ++rw.moves;
      }
      rw.compares += j > 0;  // the compare that stopped it
      a[j] = v;
      ++n;
    }
    return rw;
  }

  void listNodes(const uint32_t* w, uint32_t limit, std::vector<uint32_t>& out) const override {
    out.clear();
    for (uint32_t i = w[0]; i != kNil && out.size() < limit; i = pool_[i].next) out.push_back(i);
  }

  // Insert: read + write the head (an atomic exchange), write one node (in
  // the pool, not in the per-pixel state). A dropped fragment touches nothing.
  unsigned readBytes(unsigned, InsertOutcome o) const override { return o == InsertOutcome::Discarded ? 0 : 4; }
  unsigned writeBytes(unsigned, InsertOutcome o) const override {
    return o == InsertOutcome::Discarded ? 0 : 4 + poolNodeBytes();
  }
  // The state ranges cover the head only (the node is in the pool).
  StateRanges readRanges(unsigned, InsertOutcome o) const override {
    return o == InsertOutcome::Discarded ? StateRanges::none() : StateRanges::one(0, 4);
  }
  StateRanges writeRanges(unsigned, InsertOutcome o) const override {
    return o == InsertOutcome::Discarded ? StateRanges::none() : StateRanges::one(0, 4);
  }

 private:
  struct Node {
    float z, r, g, b, a;  // colour as stored (decoded from the storage format)
    uint32_t next;
  };
  static constexpr uint32_t kSortProbe = 64;

  static unsigned colourBytes(StorageFormat f) {
    switch (f) {
      case StorageFormat::Rgba8T8Z32: return 4;
      case StorageFormat::Fp16: return 8;
      case StorageFormat::Fp32: return 16;
    }
    return 16;
  }
  float quantized(float v) const {
    switch (fmt_) {
      case StorageFormat::Rgba8T8Z32: return decodeUnorm8(encodeUnorm8(v));
      case StorageFormat::Fp16: return decodeHalf(encodeHalf(v));
      case StorageFormat::Fp32: return v;
    }
    return v;
  }
  // The nodes resolve() composites: the whole list, or (Truncate) its first max_sorted.
  void gather(const uint32_t* w) {
    scratch_.clear();
    const bool truncate = budget_.overflow == ABufferOverflow::Truncate && budget_.max_sorted != 0;
    for (uint32_t i = w[0]; i != kNil; i = pool_[i].next) {
      if (truncate && scratch_.size() == budget_.max_sorted) break;
      scratch_.push_back(&pool_[i]);
    }
  }

  StorageFormat fmt_;
  ABufferBudget budget_;
  uint64_t capacity_ = kUnlimited;
  std::vector<Node> pool_;
  std::vector<const Node*> scratch_;
};

}  // namespace

std::unique_ptr<OitAlgorithm> makeABuffer(const AlgorithmParams& p) { return std::make_unique<ABuffer>(p); }

}  // namespace oit::model::detail

namespace oit::model {

uint64_t capacityNodes(const ABufferBudget& b, uint32_t width, uint32_t height, unsigned node_bytes) {
  const uint64_t heads = 4ull * width * height;
  if (b.pool_bytes == 0 && b.nodes_per_pixel == 0.0) return detail::kUnlimited;
  if (b.pool_bytes == 0) return uint64_t(std::floor(b.nodes_per_pixel * double(width) * double(height)));
  if (b.pool_bytes < heads + node_bytes)
    throw std::invalid_argument("abuffer.pool_bytes " + std::to_string(b.pool_bytes) +
                                " cannot hold the heads (" + std::to_string(heads) + " B for " +
                                std::to_string(width) + " x " + std::to_string(height) + " pixels) and one " +
                                std::to_string(node_bytes) + "-byte node");
  return (b.pool_bytes - heads) / node_bytes;
}

}  // namespace oit::model
