// DRAM model against a reference that books burst by burst by the formulas
// of oit_rop/memory/MEMORY.md, on seeded random request streams over several
// geometries, row policies and sample intervals.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "oit_rop/TestLcg.hpp"
#include "oit_rop/memory/DramTestConfig.hpp"
#include "oit_rop/memory/MemorySystem.hpp"

namespace oit::rop {
namespace memory_system_reference_test {

using namespace testutil;  // the round configuration's timings (DramTestConfig.hpp)
DramConfig roundConfig(unsigned channels) { return roundDramConfig(channels); }

// Reference: the per-burst booking of MEMORY.md written out directly (address
// mapping by its formulas, one burst at a time), on the ticks the model uses,
// for a write queue that drains every write at once (dram.write_high = 1,
// write_low = 0, a queue too large to push back): a write is booked when it
// arrives and returns its acceptance (posted); turnarounds tWTR and tRTW apply
// burst by burst.
class ReferenceDram {
 public:
  ReferenceDram(const DramConfig& c, const MemorySystem& m)
      : c_(c),
        ctrl_(ticks(m.controllerCycles())),
        cl_(ticks(m.clCycles())),
        trcd_(ticks(m.trcdCycles())),
        trp_(ticks(m.trpCycles())),
        tras_(ticks(m.trasCycles())),
        burst_(ticks(m.burstCycles())),
        twtr_(ticks(m.twtrCycles())),
        trtw_(ticks(m.trtwCycles())),
        bus_(c.channels, 0),
        last_read_end_(c.channels, 0),
        last_write_end_(c.channels, 0),
        busy_(c.channels, 0),
        banks_(size_t(c.channels) * c.banks) {
    stats_.channel_busy.assign(c.channels, 0);
  }
  void setSampleInterval(Cycle i) { interval_ = i; }
  const MemoryStats& stats() const { return stats_; }

  Cycle access(Cycle now, uint64_t addr, uint32_t bytes, bool write, Surface s) {
    if (bytes == 0) return now;
    (write ? stats_.write_bytes : stats_.read_bytes)[unsigned(s)] += bytes;
    ++stats_.requests;
    ++requests_;
    const uint64_t arrive = (now << 16) + ctrl_;
    uint64_t done = arrive;
    const uint64_t B = c_.burst_bytes, I = c_.interleave_bytes, C = c_.channels, R = c_.row_bytes, K = c_.banks;
    for (uint64_t a = addr / B * B; a < addr + bytes; a += B) {
      const uint64_t ch = (a / I) % C;
      const uint64_t local = a / (I * C) * I + a % I;
      uint64_t bank_index = (local / R) % K;
      const uint64_t row = local / (R * K);
      if (c_.bank_hash) {
        // MEMORY.md: XOR of the row's bank-sized bit groups (K a power of two),
        // else the sum of its base-K digits, mod K.
        const bool pow2 = (K & (K - 1)) == 0;
        for (uint64_t r = row; r != 0; r /= K) bank_index = pow2 ? (bank_index ^ (r % K)) : bank_index + r % K;
        bank_index %= K;
      }
      Bank& k = banks_[ch * K + bank_index];
      uint64_t col;
      if (c_.open_row) {
        if (k.open && k.row == row) {
          ++stats_.row_hits;
          col = std::max(arrive, k.row_ready);
        } else {
          ++stats_.row_misses;
          uint64_t pre = std::max({arrive, k.row_ready, k.last_end});
          if (k.open) pre = std::max(pre, k.act + tras_) + trp_;  // tRAS, then precharge
          k.act = pre;
          k.row_ready = pre + trcd_;
          k.open = true;
          k.row = row;
          col = k.row_ready;
        }
      } else if (k.run_request == requests_ && k.row == row) {
        ++stats_.row_hits;  // closed page: a later burst of the run this request opened
        col = k.row_ready;
      } else {
        ++stats_.row_misses;  // closed page: the bank was precharged after its last run
        k.act = std::max(arrive, k.act_ready);
        k.row_ready = k.act + trcd_;
        k.run_request = requests_;
        k.row = row;
        col = k.row_ready;
      }
      if (!write) col = std::max(col, last_write_end_[ch] + twtr_);  // tWTR
      const uint64_t bus_floor = write ? std::max(bus_[ch], last_read_end_[ch] + trtw_) : bus_[ch];  // tRTW
      const uint64_t start = std::max(col + cl_, bus_floor);
      const uint64_t end = start + burst_;
      bus_[ch] = end;
      (write ? last_write_end_ : last_read_end_)[ch] = end;
      k.last_end = std::max(k.last_end, end);
      if (!c_.open_row) k.act_ready = std::max(k.last_end, k.act + tras_) + trp_;
      if (interval_) {
        const uint64_t bucket = (start >> 16) / interval_;
        if (bucket >= stats_.bus_bytes_per_interval.size()) stats_.bus_bytes_per_interval.resize(bucket + 1, 0);
        stats_.bus_bytes_per_interval[bucket] += B;
      }
      busy_[ch] += burst_;
      stats_.channel_busy[ch] = (busy_[ch] + 0xffff) >> 16;
      if (!write) done = std::max(done, end);  // a write completes when accepted
    }
    const Cycle completion = (done + 0xffff) >> 16;
    stats_.last_completion = std::max(stats_.last_completion, completion);
    return completion;
  }

 private:
  static uint64_t ticks(double cycles) { return uint64_t(std::llround(std::ldexp(cycles, 16))); }
  struct Bank {
    bool open = false;
    uint64_t row = 0, row_ready = 0, last_end = 0, act_ready = 0, act = 0;
    uint64_t run_request = 0;  // closed page: the request whose run has the row open
  };
  uint64_t requests_ = 0;
  DramConfig c_;
  uint64_t ctrl_, cl_, trcd_, trp_, tras_, burst_, twtr_, trtw_;
  std::vector<uint64_t> bus_, last_read_end_, last_write_end_, busy_;
  std::vector<Bank> banks_;
  MemoryStats stats_;
  Cycle interval_ = 0;
};

void expectSameStats(const MemoryStats& got, const MemoryStats& want, const std::string& what) {
  EXPECT_EQ(got.read_bytes, want.read_bytes) << what;
  EXPECT_EQ(got.write_bytes, want.write_bytes) << what;
  EXPECT_EQ(got.requests, want.requests) << what;
  EXPECT_EQ(got.row_hits, want.row_hits) << what;
  EXPECT_EQ(got.row_misses, want.row_misses) << what;
  EXPECT_EQ(got.channel_busy, want.channel_busy) << what;
  EXPECT_EQ(got.last_completion, want.last_completion) << what;
  EXPECT_EQ(got.bus_bytes_per_interval, want.bus_bytes_per_interval) << what;
}

struct Geometry {
  unsigned channels, banks, row_bytes, burst_bytes, interleave_bytes;
};

// Seeded random request streams (unaligned starts, 1 B .. 8 KiB, reads and
// writes, writers slightly out of time order) on regular and odd geometries,
// both row policies and several sample intervals: every completion and every
// stats field equals the burst-by-burst reference.
TEST(MemorySystem, MatchesBurstByBurstReferenceOnRandomStreams) {
  const Geometry geometries[] = {
      {1, 8, 8192, 64, 256},   // igpu-like, 1 channel
      {2, 8, 8192, 64, 256},   // igpu
      {4, 16, 4096, 64, 256},  // dgpu
      {3, 6, 8192, 64, 256},   // non-power-of-two channels and banks
      {2, 5, 320, 64, 192},    // rows of 5 bursts, chunks of 3: chunks cross rows
      {3, 3, 128, 64, 256},    // rows shorter than a chunk
      {4, 7, 96, 32, 96},      // row = chunk, odd everything
      {1, 3, 192, 64, 128},    // one channel, rows not a multiple of the chunk
      {2, 2, 64, 64, 64},      // one burst per row and per chunk
  };
  struct Timing {
    double mhz, gbps, tck, ctrl;
  };
  const Timing timings[] = {{1000.0, 16.0, 1.0, 40.0}, {1150.0, 12.8, 1.25, 40.0}, {1600.0, 56.0, 0.667, 100.0}};
  testutil::TestLcg rnd{0x9e3779b97f4a7c15ull, 17};
  int cases = 0;
  for (const Geometry& g : geometries) {
    for (bool open : {true, false}) {
      for (bool hash : {false, true}) {
        for (Cycle interval : {Cycle(0), Cycle(1), Cycle(7), Cycle(10000)}) {
          const Timing& t = timings[cases % 3];
          DramConfig c;
          c.channels = g.channels;
          c.banks = g.banks;
          c.row_bytes = g.row_bytes;
          c.burst_bytes = g.burst_bytes;
          c.interleave_bytes = g.interleave_bytes;
          c.open_row = open;
          c.bank_hash = hash;
          c.channel_gbps = t.gbps;
          c.tck_ns = t.tck;
          c.controller_ns = t.ctrl;
          c.cl = 11 + unsigned(cases % 5);
          c.trcd = 11;
          c.trp = 9 + unsigned(cases % 7);
          c.twtr = unsigned(cases % 9);  // 0 .. 8 tCK
          c.trtw = unsigned(cases % 4);
          c.write_high = 1;  // every write drains when it arrives
          c.write_low = 0;
          c.write_queue = 1u << 30;  // and never waits for room
          c.scheduler = DramScheduler::Fcfs;  // reads in booking order
          c.trefi_ns = 0;                     // the reference has no refresh
          MemorySystem m(c, t.mhz);
          ReferenceDram ref(c, m);
          m.setSampleInterval(interval);
          ref.setSampleInterval(interval);
          const std::string what = std::to_string(g.channels) + " ch " + std::to_string(g.banks) + " banks row " +
                                   std::to_string(g.row_bytes) + " il " + std::to_string(g.interleave_bytes) +
                                   (open ? " open" : " closed") + (hash ? " hashed" : "") + " interval " +
                                   std::to_string(interval);
          // A small address range (many row hits and conflicts) or a large one.
          const uint64_t range = (cases % 2) ? (uint64_t(1) << 20) : (uint64_t(1) << 34);
          Cycle now = 0;
          uint64_t addr = 0;
          uint32_t bytes = 1;
          for (int i = 0; i < 3000; ++i) {
            const uint64_t kind = rnd(12);
            // 10: streaming on from the previous request, 11: the same address again.
            if (kind == 10)
              addr += bytes;
            else if (kind == 9)
              addr = rnd(range) / 2048 * 2048;
            else if (kind != 11)
              addr = rnd(range);
            if (kind < 3)
              bytes = uint32_t(1 + rnd(64));
            else if (kind < 6)
              bytes = uint32_t(1 + rnd(8192));
            else
              bytes = uint32_t(64) << rnd(6);  // 64 B .. 2 KiB
            // Mostly forward in time, bursty, sometimes a writer up to a quantum
            // behind. (Reads stay in time order: with FCFS a read that arrived
            // before an earlier booking may take the bus time it left idle,
            // which the reference does not model; test_dram_scheduler.cpp has
            // that.)
            const bool write = rnd(2) == 1;
            const Cycle at = write && rnd(4) == 0 ? now - std::min<Cycle>(now, rnd(1000)) : now;
            now += rnd(4) == 0 ? rnd(400) : 0;
            const Surface s = Surface(rnd(kSurfaceCount));
            const Cycle want = ref.access(at, addr, bytes, write, s);
            ASSERT_EQ(m.access(at, addr, bytes, write, s), want) << what << ", request " << i;
          }
          expectSameStats(m.stats(), ref.stats(), what);
          // A change of interval on the way keeps the series consistent too.
          if (interval) {
            m.setSampleInterval(interval * 3);
            ref.setSampleInterval(interval * 3);
            for (int i = 0; i < 200; ++i) {
              addr = rnd(range);
              bytes = uint32_t(1 + rnd(4096));
              EXPECT_EQ(m.access(now + Cycle(i), addr, bytes, false, Surface::Colour),
                        ref.access(now + Cycle(i), addr, bytes, false, Surface::Colour))
                  << what;
            }
            expectSameStats(m.stats(), ref.stats(), what + " (interval changed)");
          }
          EXPECT_GT(m.stats().row_misses, 0u) << what;
          if (open) {
            EXPECT_GT(m.stats().row_hits, 0u) << what;
          }
          ++cases;
        }
      }
    }
  }
  EXPECT_EQ(cases, 9 * 2 * 2 * 4);
}

}  // namespace memory_system_reference_test
}  // namespace oit::rop
