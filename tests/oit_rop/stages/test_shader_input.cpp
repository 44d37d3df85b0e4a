// ShaderInput: issue rate, deterministic latency model, out-of-order arrival.
#include <gtest/gtest.h>

#include <set>
#include <utility>
#include <vector>

#include "oit_rop/stages/ShaderInput.hpp"

using namespace oit::rop;

TEST(ShaderInput, UniformLatencyIsDeterministicAndCoversTheRange) {
  InputConfig c;
  c.latency_min = 40;
  c.latency_max = 50;
  ShaderInput a(c), b(c);
  std::set<unsigned> seen;
  for (uint64_t s = 0; s < 2000; ++s) {
    const unsigned l = a.latencyOf(s, 0);
    ASSERT_GE(l, 40u);
    ASSERT_LE(l, 50u);
    EXPECT_EQ(l, b.latencyOf(s, 0));
    seen.insert(l);
  }
  EXPECT_EQ(seen.size(), 11u);
  c.seed = 2;
  ShaderInput d(c);
  unsigned differ = 0;
  for (uint64_t s = 0; s < 100; ++s) differ += d.latencyOf(s, 0) != a.latencyOf(s, 0);
  EXPECT_GT(differ, 50u);
}

TEST(ShaderInput, FixedLatencyAndIssueRate) {
  InputConfig c;
  c.latency_model = LatencyModel::Fixed;
  c.latency_min = 7;
  c.fragments_per_clock = 0.5;
  ShaderInput s(c);
  unsigned issued = 0;
  std::vector<std::pair<Cycle, uint32_t>> out;
  for (Cycle now = 0; now < 40; ++now) {
    s.finished(now, [&](uint32_t t) { out.push_back({now, t}); });
    if (s.slots(now) > 0 && issued < 10) {
      const uint32_t t = issued++;
      s.issue(now, t, t, 0);  // fixed latency: the sequence number does not matter
    }
  }
  ASSERT_EQ(out.size(), 10u);
  for (size_t i = 1; i < out.size(); ++i) EXPECT_EQ(out[i].first - out[i - 1].first, 2u);  // one every 2 cycles
  EXPECT_EQ(out[0].first, 7u);                                                               // + fixed latency
}

TEST(ShaderInput, UniformLatencyReordersFragments) {
  InputConfig c;  // igpu: Uniform[40, 120], 2 per clock
  ShaderInput s(c);
  std::vector<uint32_t> order;
  uint32_t next = 0;
  for (Cycle now = 0; order.size() < 200; ++now) {
    s.finished(now, [&](uint32_t t) { order.push_back(t); });
    for (unsigned k = s.slots(now); k > 0 && next < 200; --k) s.issue(now, next, next, 0), ++next;
    if (s.inShader()) {
      const Cycle nf = s.nextFinish(now);
      ASSERT_GT(nf, now);
    }
    ASSERT_LT(now, 10000u);
  }
  unsigned inversions = 0;
  for (size_t i = 1; i < order.size(); ++i) inversions += order[i] < order[i - 1];
  EXPECT_GT(inversions, 20u);
  EXPECT_EQ(s.issued(), 200u);
}

// issue() reduces the latency hash with a multiply instead of a 64-bit
// division; every fragment must still leave after exactly latencyOf() cycles,
// for spans that are and are not powers of two, one-cycle spans, the largest
// hashes, and warps of one, four and 1024 fragments.
TEST(ShaderInput, IssuedFragmentsLeaveAfterLatencyOf) {
  for (auto [lo, hi] : {std::pair{40u, 120u}, {1u, 1u}, {0u, 0u}, {3u, 4u}, {5u, 68u}, {1u, 1000u}, {0u, 6999u}}) {
    InputConfig c;
    c.latency_min = lo;
    c.latency_max = hi;
    c.seed = 0xC0FFEEull * (hi + 1);
    for (auto [pass, warp] : {std::pair{0u, 1u}, {3u, 1u}, {0u, 4u}, {3u, 1024u}}) {
      c.warp_size = warp;
      ShaderInput s(c);
      const uint64_t base = pass == 3 ? ~uint64_t(0) - 3000 : 0;  // sequence numbers up to 2^64 - 1
      constexpr uint32_t kCount = 3000;
      std::vector<Cycle> left(kCount, kNever);
      unsigned done = 0;
      for (Cycle now = 0; done < kCount; ++now) {
        s.finished(now, [&](uint32_t t) { left[t] = now, ++done; });
        if (now < kCount) {
          ASSERT_GT(s.slots(now), 0u);  // one issue per cycle, below the rate
          s.issue(now, uint32_t(now), base + now, pass);
        }
        ASSERT_LT(now, Cycle(kCount) + hi + 2);
      }
      for (uint32_t i = 0; i < kCount; ++i)
        ASSERT_EQ(left[i], i + s.latencyOf(base + i, pass))
            << "latency " << lo << ".." << hi << " warp " << warp << " seq " << base + i;
    }
  }
}

// Values recorded from the model before input.warp_size existed (and equal to
// 40 + splitmix64(splitmix64(seed ^ pass << 56) ^ seq) mod 81): with one
// fragment per warp, the default, every latency stays what it was.
TEST(ShaderInput, UniformLatencyPinnedValues) {
  InputConfig c;  // igpu: Uniform[40, 120], seed 1
  ShaderInput s(c);
  struct Pin {
    uint64_t seq;
    unsigned pass, latency;
  };
  for (const Pin& p : {Pin{0, 0, 53}, Pin{1, 0, 49}, Pin{2, 0, 41}, Pin{31, 0, 56}, Pin{32, 0, 49},
                       Pin{1000003, 0, 89}, Pin{0, 1, 64}, Pin{7, 1, 64}, Pin{0xFFFFFFFFull, 2, 58}})
    EXPECT_EQ(s.latencyOf(p.seq, p.pass), p.latency) << "seq " << p.seq << " pass " << p.pass;
}

// The approximate engine draws through draw(pass): the same latencies as
// latencyOf() for every pass, for the uniform model, warps and the fixed model.
TEST(ShaderInput, DrawOfAPassGivesLatencyOf) {
  InputConfig uniform;  // Uniform[40, 120]
  InputConfig warps = uniform;
  warps.warp_size = 8;
  warps.latency_min = 3;
  warps.latency_max = 10;
  InputConfig fixed = uniform;
  fixed.latency_model = LatencyModel::Fixed;
  for (const InputConfig& c : {uniform, warps, fixed}) {
    ShaderInput s(c);
    for (unsigned pass : {0u, 1u, 0u, 5u}) {  // a pass drawn again after another
      const ShaderInput::Draw d = s.draw(pass);
      for (uint64_t seq : {uint64_t(0), uint64_t(1), uint64_t(7), uint64_t(8), uint64_t(1000003), uint64_t(0xFFFFFFFFull)})
        EXPECT_EQ(d(seq), s.latencyOf(seq, pass)) << "pass " << pass << " seq " << seq;
    }
  }
  EXPECT_EQ(ShaderInput(fixed).draw(3)(12345), 40u);
}

// The draw reduces its hash with one multiply and ONE conditional subtract
// (the quotient estimate is exact or one below): over 200,000 draws per span,
// including spans of one and powers of two (span_inv rounded down from
// 2^64 - 1), every draw equals latencyOf()'s true remainder, and for span 81
// the correction is needed for a large share of the draws (so a missing
// correction would show).
TEST(ShaderInput, DrawReductionIsExactWithOneCorrection) {
  for (auto [lo, hi] : {std::pair{40u, 120u}, {0u, 0u}, {7u, 7u}, {0u, 1u}, {0u, 63u}, {1u, 1024u}, {0u, 6999u}, {100u, 65635u}}) {
    InputConfig c;
    c.latency_min = lo;
    c.latency_max = hi;
    c.seed = 0x5EEDull + hi;
    ShaderInput s(c);
    const ShaderInput::Draw d = s.draw(2);
    const uint64_t span = uint64_t(hi - lo) + 1;
    uint64_t corrected = 0;
    for (uint64_t seq = 0; seq < 200000; ++seq) {
      const uint64_t h = ShaderInput::mix64(d.pass_mix ^ seq);
      const uint64_t q = uint64_t(ShaderInput::U128(h) * d.span_inv >> 64);
      ASSERT_LT(h - q * span, 2 * span) << "span " << span << " seq " << seq;  // q is h / span or one below
      corrected += h - q * span >= span;
      ASSERT_EQ(d(seq), s.latencyOf(seq, 2)) << "span " << span << " seq " << seq;
    }
    if (span == 81) {
      EXPECT_GT(corrected, 40000u);  // 2^64 mod 81 = 52: about a third of the draws
    }
  }
}

// input.warp_size: the fragments of a warp (warp_size consecutive sequence
// numbers) share one draw, the draw of the warp's number seq >> log2(warp_size).
TEST(ShaderInput, WarpSharesOneLatency) {
  InputConfig one;  // igpu: Uniform[40, 120], warps of one fragment
  InputConfig w32 = one;
  w32.warp_size = 32;
  const ShaderInput a(one), b(w32);
  for (unsigned pass : {0u, 1u}) {
    for (uint64_t seq = 0; seq < 64; ++seq)
      ASSERT_EQ(b.latencyOf(seq, pass), a.latencyOf(seq >> 5, pass)) << "seq " << seq << " pass " << pass;
    // Sequence numbers near 2^64: the last warp is whole.
    const uint64_t top = ~uint64_t(0);
    EXPECT_EQ(b.latencyOf(top, pass), a.latencyOf(top >> 5, pass));
    EXPECT_EQ(b.latencyOf(top - 31, pass), b.latencyOf(top, pass));
  }
  // Recorded values (UniformLatencyPinnedValues): warp 0 draws as fragment 0,
  // warp 1 (fragments 32..63) as fragment 1.
  EXPECT_EQ(b.latencyOf(0, 0), 53u);
  EXPECT_EQ(b.latencyOf(31, 0), 53u);
  EXPECT_EQ(b.latencyOf(32, 0), 49u);
  EXPECT_EQ(b.latencyOf(63, 0), 49u);
  // The fixed model ignores the warp.
  w32.latency_model = LatencyModel::Fixed;
  EXPECT_EQ(ShaderInput(w32).latencyOf(5, 0), 40u);
}

TEST(ShaderInput, WarpLatenciesStillCoverTheRange) {
  InputConfig c;  // Uniform[40, 120]: a span of 81
  c.warp_size = 32;
  const ShaderInput s(c);
  std::set<unsigned> seen;
  for (uint64_t w = 0; w < 20000; ++w) {
    const unsigned l = s.latencyOf(w * 32 + w % 32, 0);  // any fragment of the warp
    ASSERT_EQ(l, s.latencyOf(w * 32, 0)) << "warp " << w;
    seen.insert(l);
  }
  EXPECT_EQ(*seen.begin(), 40u);
  EXPECT_EQ(*seen.rbegin(), 120u);
  EXPECT_EQ(seen.size(), 81u);
}
