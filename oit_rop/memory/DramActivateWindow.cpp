#include "oit_rop/memory/DramActivateWindow.hpp"

#include <algorithm>

namespace oit::rop {

void DramActivateWindow::record(uint64_t t, unsigned group) {
  if (!limited()) return;
  // After the activates at or before t (usually all: they come mostly in time order).
  unsigned p = unsigned(std::upper_bound(at_.begin(), at_.begin() + n_, t) - at_.begin());
  if (n_ == kKeep) {
    if (p == 0) return;  // older than everything remembered (earliest() never places one there)
    std::copy(at_.begin() + 1, at_.begin() + p, at_.begin());  // forget the oldest
    if (grouped_) std::copy(group_.begin() + 1, group_.begin() + p, group_.begin());
    --p;
  } else {
    std::copy_backward(at_.begin() + p, at_.begin() + n_, at_.begin() + n_ + 1);
    if (grouped_) std::copy_backward(group_.begin() + p, group_.begin() + n_, group_.begin() + n_ + 1);
    ++n_;
  }
  at_[p] = t;
  group_[p] = uint8_t(group);
}

uint64_t DramActivateWindow::earliestAmong(uint64_t t, unsigned group) const {
  // Move c forward past each rule it breaks, by the least that could mend it;
  // every step passes an activate or meets a lower bound, so at most about
  // 2 x kKeep steps. Past the latest activate + max(tRRD_L, tFAW) every tick
  // is allowed.
  uint64_t c = n_ == kKeep ? std::max(t, at_[0]) : t;
  for (;;) {
    // p = the activates at or before c (c goes after those at the same tick).
    const unsigned p = unsigned(std::upper_bound(at_.begin(), at_.begin() + n_, c) - at_.begin());
    if (trrd_ && p > 0 && c < at_[p - 1] + trrd_) {
      c = at_[p - 1] + trrd_;
      continue;
    }
    if (grouped_) {
      // The same group's activates before c within tRRD_L (the others keep tRRD: above).
      uint64_t after = c;
      for (unsigned j = p; j-- > 0 && at_[j] + trrd_l_ > c;)
        if (group_[j] == group) after = std::max(after, at_[j] + trrd_l_);
      if (after > c) {
        c = after;
        continue;
      }
    }
    // The next activate too close (tRRD, tRRD_L in its group), or a window of
    // five with c inside and later activates in it (tFAW): no tick before the
    // next activate mends it, nor one within its spacing after it.
    unsigned next = p;  // the activate c must go past
    bool past_next = trrd_ && p < n_ && at_[p] < c + trrd_;
    if (grouped_)
      for (unsigned j = p; j < n_ && at_[j] < c + trrd_l_ && !past_next; ++j)
        if (group_[j] == group) {
          past_next = true;
          next = j;
        }
    uint64_t after_fourth = 0;  // c the fifth of a window: no earlier than the fourth before + tFAW
    if (tfaw_) {
      for (unsigned j = 0; j <= 4 && !past_next; ++j) {  // j of the others before c, 4 - j after it
        if (j > p || p + 4 - j > n_) continue;
        const uint64_t first = j ? at_[p - j] : c;
        const uint64_t last = j < 4 ? at_[p + 3 - j] : c;
        if (last - first >= tfaw_) continue;
        if (j < 4)
          past_next = true;
        else
          after_fourth = first + tfaw_;
      }
    }
    if (past_next) {
      c = at_[next] + spacing(next, group);
      continue;
    }
    if (after_fourth > c) {
      c = after_fourth;
      continue;
    }
    return c;
  }
}

}  // namespace oit::rop
