#include "oit_rop/BlendAlu.hpp"

#include <algorithm>
#include <stdexcept>

namespace oit::rop {

BlendAlu::BlendAlu(const AluConfig& cfg, double format_rate, unsigned rows_max)
    : cfg_(cfg), rate_(double(cfg.blends_per_clock) * format_rate), done_(rows_max + 1) {
  if (cfg.blends_per_clock == 0) throw std::invalid_argument("alu.blends_per_clock must be > 0");
}

unsigned BlendAlu::rowsFor(model::InsertOutcome outcome, unsigned array_rows, bool lazy_merge) {
  const unsigned merge = std::max(1u, array_rows);
  switch (outcome) {
    case model::InsertOutcome::Stored: return lazy_merge ? 1u : merge;
    case model::InsertOutcome::Merged: return merge;
    case model::InsertOutcome::Discarded: return 0u;
  }
  return 0u;
}

double BlendAlu::formatRate(const AluConfig& cfg, const model::StateLayout& layout) {
  switch (layout.format) {
    case model::StorageFormat::Rgba8T8Z32: return 1.0;
    case model::StorageFormat::Fp16: return cfg.fp16_rate;
    case model::StorageFormat::Fp32: return cfg.fp32_rate;
  }
  return 1.0;
}

void BlendAlu::issue(Cycle now, uint32_t token, unsigned rows, bool drop) {
  rate_.take();
  rows = std::min<unsigned>(rows, unsigned(done_.size() - 1));
  const Cycle done = now + latency(rows);
  done_[rows].push({done, token});
  next_done_ = std::min(next_done_, done);
  ++in_flight_;
  if (drop) {
    ++stats_.dropped;
  } else {
    ++stats_.blends;
    stats_.rows += rows;
  }
}

}  // namespace oit::rop
