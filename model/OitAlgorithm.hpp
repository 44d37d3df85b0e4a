// One per-pixel interface for every OIT algorithm of the functional model.
//
// An algorithm owns no per-pixel state: the caller owns an array of 32-bit
// words, stateWords() per pixel, and hands the pixel's words to clear /
// insert / resolve. insert() is exactly the read-modify-write an ordered
// pixel lock protects in the ROP, so the SystemC timing model can call it per
// fragment and charge readBytes / writeBytes of memory traffic.
// Semantics and layouts of each algorithm: model/ALGORITHMS.md.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "model/Image.hpp"
#include "model/StorageFormat.hpp"
#include "traces/Fragment.hpp"

namespace oit::model {

// What one insert did to the pixel state (the timing model counts these).
enum class InsertOutcome : uint8_t {
  Stored = 0,     // kept without loss (new row/node/sample, or accumulated)
  Merged = 1,     // kept, but older data was compressed or evicted to make room
                  // (rows merged, tail update, node removed, furthest layer dropped)
  Discarded = 2,  // the fragment did not enter the state (a = 0, behind a full
                  // list, rejected by a random test); the state is unchanged
                  // except for bookkeeping words (counters, total transmittance)
};
inline constexpr unsigned kOutcomeCount = 3;
const char* toString(InsertOutcome o);

// Layout of the fixed-size per-pixel state: `rows` rows of `format`
// (rowWords(format) words each, row 0 first) followed by `extra_words` words.
struct StateLayout {
  unsigned rows = 0;
  StorageFormat format = StorageFormat::Fp32;
  unsigned extra_words = 0;
  std::string extra;  // what the extra words hold (human-readable)

  unsigned words() const { return rows * rowWords(format) + extra_words; }
};

// The work one insert did inside its read-modify-write, in rows (nodes,
// layers, samples): what the timing model's BlendAlu charges cycles for
// (ALGORITHMS.md, "Work per insert"). Counts saturate at 255.
struct InsertWork {
  uint8_t compares = 0;  // rows whose depth (or removal metric) was compared with the fragment's
  uint8_t moves = 1;     // rows written: the new row, rows shifted or rescaled behind it, a merged row,
                         // an accumulator; 0 when nothing was written
};

// Byte ranges of a pixel's state, in the state's own order (row i of the
// layout at i x rowBytes(format), the extra words after the rows): at most
// two, increasing and disjoint. What one insert reads or writes
// (OitAlgorithm::readRanges / writeRanges); the timing model turns them into
// the cache lines and sectors the insert touches.
struct StateRanges {
  struct Range {
    uint32_t begin = 0, end = 0;  // [begin, end), bytes
  };
  static constexpr unsigned kMax = 2;
  Range range[kMax]{};
  unsigned count = 0;

  static StateRanges none() { return {}; }
  static StateRanges one(uint32_t begin, uint32_t end) {
    StateRanges r;
    r.add(begin, end);
    return r;
  }
  static StateRanges two(uint32_t b0, uint32_t e0, uint32_t b1, uint32_t e1) {
    StateRanges r;
    r.add(b0, e0);
    r.add(b1, e1);
    return r;
  }
  // Appends [begin, end) (an empty range is dropped); ranges must come in increasing order.
  void add(uint32_t begin, uint32_t end);
  unsigned bytes() const {
    unsigned n = 0;
    for (unsigned i = 0; i < count; ++i) n += range[i].end - range[i].begin;
    return n;
  }
};

// Per-fragment information the ROP has besides the fragment itself.
struct InsertContext {
  // Final opaque depth at the pixel, +inf where no opaque fragment landed.
  // The caller has already culled fragments at or behind it.
  float opaque_z = std::numeric_limits<float>::infinity();
  // Written by insert() (an output beside the outcome: one store, no change to
  // the insert's signature). Algorithms that write one accumulator leave the
  // caller's {0, 1}; the sorted ones say how far they searched and shifted.
  mutable InsertWork work;
};

// The A-buffer under test's budgets (abuffer.* of the ROP configuration,
// CONFIG.md). All zero: unlimited, the exact reference.
enum class ABufferOverflow : uint8_t { Spill, Truncate };
struct ABufferBudget {
  // Heads (4 B per pixel) + node pool, bytes; 0: sized by nodes_per_pixel.
  uint64_t pool_bytes = 0;
  // Pool nodes per pixel of the frame when pool_bytes is 0; 0 with pool_bytes 0: unlimited.
  double nodes_per_pixel = 0.0;
  // The resolve's local array (nodes sorted per pixel); 0: unlimited.
  unsigned max_sorted = 0;
  // A list longer than max_sorted: Spill sorts it all (exact, at a cost per
  // spilled node), Truncate composites only the first max_sorted nodes of the
  // list (the newest: it runs newest first) and ignores the rest.
  ABufferOverflow overflow = ABufferOverflow::Spill;
  bool unlimited() const { return pool_bytes == 0 && nodes_per_pixel == 0.0 && max_sorted == 0; }
};

// What the resolve of one pixel's list did (A-buffer): the timing model's list
// walk and sort (ALGORITHMS.md, abuffer).
struct ResolveWork {
  uint32_t nodes = 0;     // nodes in the list (dependent reads of the walk)
  uint32_t sorted = 0;    // nodes loaded into the local array and sorted
  uint32_t spilled = 0;   // nodes beyond the local array (Spill: sorted too, at a cost; Truncate: ignored)
  uint64_t compares = 0;  // insertion sort's compares over the sorted nodes
  uint64_t moves = 0;     // insertion sort's element moves
};

struct AlgorithmParams {
  unsigned layers = 4;                       // k: rows / nodes / layers
  StorageFormat format = StorageFormat::Fp32;
  unsigned bits = 8;                         // slab: virtual coverage bits b; mlcb: mask bits b (1..64)
  unsigned samples = 8;                      // stochastic: samples S
  bool coverage_mask = false;                // slab: b-bit coverage masks instead of continuous alpha
  int weight = 10;                           // wboit: weight equation 7, 8, 9 or 10
  uint64_t seed = 1;                         // random streams (slab, stochastic, mlcb)
  ABufferBudget abuffer;                     // abuffer: pool and local-array budgets (default: unlimited)
  // Overrides the trace header's camera planes (wboit eq. 7-9 need them).
  std::optional<CameraPlanes> camera;
};

class OitAlgorithm {
 public:
  virtual ~OitAlgorithm() = default;

  virtual std::string_view name() const = 0;
  const StateLayout& layout() const { return layout_; }
  // Words of caller-owned state per pixel; bytesPerPixel() = 4 * stateWords().
  unsigned stateWords() const { return state_words_; }
  unsigned bytesPerPixel() const { return 4u * state_words_; }

  // Passes over the transparent fragments (1 for single-pass algorithms).
  virtual unsigned passes() const { return 1; }
  virtual std::string_view passName(unsigned pass) const;

  // Once per frame before any clear(): checks the trace suits the algorithm
  // (e.g. wboit eq. 7-9 need camera planes; throws std::invalid_argument) and
  // resets shared storage (the A-buffer's node pool).
  virtual void beginFrame(const TraceHeader& header) {}

  // Writes every one of the stateWords() words (callers need not zero them;
  // FunctionalRenderer hands in uninitialised memory). Contract: the words
  // written do not depend on the pixel (same pattern for every pixel), so
  // clearFrame may replicate one cleared pixel.
  virtual void clear(uint32_t* words) = 0;
  // clear() of `pixels` consecutive pixels: one clear(), then copies (a
  // virtual call per pixel was most of a full-screen clear).
  void clearFrame(uint32_t* words, size_t pixels);
  // One fragment (already known transparent and in front of the opaque depth)
  // in pass `pass` < passes(); the fragments of every pass arrive in
  // submission order.
  virtual InsertOutcome insert(uint32_t* words, const Fragment& f, unsigned pass,
                               const InsertContext& ctx) = 0;
  // insert() as a plain function, for the frame loops (one insert per
  // fragment): insertFn()(*this, words, f, pass, ctx) == insert(words, f, pass,
  // ctx). An algorithm whose insert dispatches again inside (on its storage
  // format) returns its per-format insert, one indirect call instead of two;
  // the default calls insert().
  using InsertFn = InsertOutcome (*)(OitAlgorithm&, uint32_t*, const Fragment&, unsigned, const InsertContext&);
  virtual InsertFn insertFn() const { return &OitAlgorithm::callInsert; }
  static InsertOutcome callInsert(OitAlgorithm& a, uint32_t* words, const Fragment& f, unsigned pass,
                                  const InsertContext& ctx) {
    return a.insert(words, f, pass, ctx);
  }
  // After the last pass. Always finite.
  virtual Rgb resolve(const uint32_t* words, Rgb background) = 0;

  // Bytes of per-pixel memory one insert reads / writes (the ROP's RMW).
  // Default: the bytes of readRanges / writeRanges (the A-buffer adds the
  // node it appends to its pool).
  virtual unsigned readBytes(unsigned pass, InsertOutcome o) const { return readRanges(pass, o).bytes(); }
  virtual unsigned writeBytes(unsigned pass, InsertOutcome o) const { return writeRanges(pass, o).bytes(); }
  // Which bytes of the pixel's state one insert with outcome `o` reads and
  // writes, as ranges (an upper bound where the bytes depend on the state,
  // e.g. the rows a sorted insert shifts). Default: the whole state read; the
  // whole state written, nothing when Discarded.
  virtual StateRanges readRanges(unsigned pass, InsertOutcome o) const;
  virtual StateRanges writeRanges(unsigned pass, InsertOutcome o) const;
  // Bytes from the start of the state the resolve reads for this pixel's
  // final state (default: all of them). Sorted rows stop after the first
  // empty row or the row that made the transmittance exactly 0: the rows
  // behind it add nothing (the image is the same whether or not they are read).
  virtual unsigned resolveBytes(const uint32_t* words) const { return bytesPerPixel(); }

  // False for the A-buffer (unbounded lists in its own pool).
  virtual bool bounded() const { return true; }
  // Bytes held outside the per-pixel words (A-buffer pool), 0 otherwise.
  virtual uint64_t poolBytes() const { return 0; }
  // A-buffer: bytes of one pool node (colour in the storage format, depth,
  // next pointer), 0 otherwise; the pool's capacity in nodes for the frame of
  // the last beginFrame() (UINT64_MAX: unlimited).
  virtual unsigned poolNodeBytes() const { return 0; }
  virtual uint64_t poolCapacityNodes() const { return 0; }
  // A-buffer: what resolve() of this pixel walks and sorts; zero otherwise.
  virtual ResolveWork resolveWork(const uint32_t* words) const { return {}; }
  // A-buffer: the pool indices of the pixel's list in walk order (newest
  // first), at most `limit`, into `out` (cleared first). Index i is the node
  // counter's i-th value (in submission order): the timing model's walk reads
  // it at the pool's base + i x poolNodeBytes(). Nothing for other algorithms.
  virtual void listNodes(const uint32_t* words, uint32_t limit, std::vector<uint32_t>& out) const { out.clear(); }
  // Bytes of the pool per stored fragment (the A-buffer's node), 0 for the
  // bounded algorithms: the memory estimate and the banded reference use it.
  virtual uint64_t poolBytesPerFragment() const { return 0; }
  // Makes room in the pool for this many stored fragments at once, so it does
  // not grow by doubling (which can take up to three times the nodes' bytes
  // while it copies). Call it before beginFrame(), which keeps the room (a
  // larger reservation drops the nodes held). No effect on bounded algorithms.
  virtual void reservePool(uint64_t fragments) {}

 protected:
  void setLayout(StateLayout l) {
    layout_ = std::move(l);
    state_words_ = layout_.words();
  }

 private:
  StateLayout layout_;
  unsigned state_words_ = 0;
};

struct AlgorithmInfo {
  std::string_view name;
  std::string_view description;  // one line
};

// In registry order: abuffer, alpha, mlab, hybrid, adaptive, kbuffer, wsum, wavg, wboit,
// slab, stochastic, mlcb.
const std::vector<AlgorithmInfo>& algorithmNames();

// Throws std::invalid_argument naming the valid values on an unknown name or
// an out-of-range parameter.
std::unique_ptr<OitAlgorithm> makeAlgorithm(std::string_view name, const AlgorithmParams& params);

// The A-buffer pool's capacity in nodes for a width x height frame: (pool_bytes
// - 4 W H) / node_bytes, or nodes_per_pixel x W x H when pool_bytes is 0;
// UINT64_MAX when both are 0 (unlimited). Throws std::invalid_argument naming
// abuffer.pool_bytes when it cannot hold the heads and one node.
uint64_t capacityNodes(const ABufferBudget& b, uint32_t width, uint32_t height, unsigned node_bytes);

// Deterministic random bits of one fragment: a hash of (x, y, draw, prim,
// seed, stream); no generator state, so any pass or any order gives the same
// bits (splitmix64 finaliser over the packed key, see ALGORITHMS.md).
uint64_t fragmentHash(const Fragment& f, uint64_t seed, uint32_t stream);

}  // namespace oit::model
