#include "oit_rop/stages/BlendArrayRmw.hpp"

#include <stdexcept>

namespace oit::rop {

BlendArrayRmw::BlendArrayRmw(LockMode mode, const FrontEnd::PixelState& pixels, unsigned capacity, unsigned passes)
    : unlocked_(mode == LockMode::None),
      px_(pixels),
      insert_(pixels.algo->insertFn()),
      frag_(capacity),
      updates_(pixels.updates),
      outcomes_(passes) {
  if (mode == LockMode::Ordered) throw std::logic_error("BlendArrayRmw: lock.mode=ordered inserts in the FrontEnd");
  if (unlocked_) {
    if (!updates_) throw std::logic_error("BlendArrayRmw: lock.mode=none needs the per-pixel update counts");
    copy_.resize(size_t(capacity) * px_.words_per_pixel);
    pixel_.resize(capacity);
    read_updates_.resize(capacity);
    writes_.resize(capacity);
  }
}

model::InsertOutcome BlendArrayRmw::enter(uint32_t token, unsigned pass, uint32_t tile) {
  const Fragment& f = frag_[token];
  const uint32_t pixel = uint32_t(f.y) * px_.width + f.x;
  const unsigned words = px_.words_per_pixel;
  uint32_t* array = px_.words + size_t(pixel) * words;
  model::InsertContext ctx;
  ctx.opaque_z = px_.opaque_z[pixel];
  model::InsertOutcome o;
  if (unlocked_) {
    // The read: the array as it is now, into the fragment's own copy.
    uint32_t* copy = copy_.data() + size_t(token) * words;
    std::memcpy(copy, array, words * sizeof(uint32_t));
    o = insert_(*px_.algo, copy, f, pass, ctx);
    pixel_[token] = pixel;
    read_updates_[token] = updates_[pixel];
    writes_[token] = px_.algo->writeBytes(pass, o) != 0;
  } else {
    o = insert_(*px_.algo, array, f, pass, ctx);
  }
  last_work_ = ctx.work;
  ++outcomes_.at(pass)[size_t(o)];
  if (px_.tile_nodes && o == model::InsertOutcome::Stored) ++px_.tile_nodes[tile];
  return o;
}

void BlendArrayRmw::land(uint32_t token) {
  if (!writes_[token]) return;
  const uint32_t pixel = pixel_[token];
  const unsigned words = px_.words_per_pixel;
  std::memcpy(px_.words + size_t(pixel) * words, copy_.data() + size_t(token) * words, words * sizeof(uint32_t));
  // The array now holds the updates of the array this fragment read, and its own.
  lost_ += int64_t(updates_[pixel]) - int64_t(read_updates_[token]);
  updates_[pixel] = read_updates_[token] + 1;
}

}  // namespace oit::rop
