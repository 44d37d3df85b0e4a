// Root-cause attribution of a partition's cycles (DESIGN.md "Root causes"):
// every cycle a partition runs is charged to exactly one cause, the resource
// that held the pipeline back in that cycle. A stage blocked by back-pressure
// takes the cause of whatever blocks it, recursively, down to a resource: the
// input rate, the blend ALU, the ordered lock, the memory a waited-for line or
// tile comes from (split into DRAM's unloaded access, its queueing by what the
// controller waited for, and the cache's own latency), the scoreboard, the front end. The per-stage accounts
// (TimingStats.hpp) stay beside it: they say where fragments wait, this says why.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <vector>

#include "oit_rop/Types.hpp"

namespace oit::rop {

enum class RootCause : uint8_t {
  Input,            // the input rate: the pipeline keeps up with the fragments the shader hands it
  InputStarvation,  // the front end has no fragment for this partition (another partition's backlog holds it)
  ScoreboardFull,   // every scoreboard entry held by fragments in fixed latencies (shader, depth, hit, blend)
  LockWait,         // fragments wait for older ones of their lock address (the ordered interlock)
  Alu,              // the blend ALU at its rate (transparent passes and the resolve)
  RopCacheMiss,     // the ROP cache's own latency on a miss (what is left of the wait beyond DRAM)
  L2,               // the shared L2 / L3 levels
  DramLatency,      // DRAM's unloaded access (controller, activate, CL, the bursts on an idle channel)
  DramBandwidth,    // the DRAM data bus busy moving other data (and a request's own further bursts)
  PipelineLatency,  // a pass's tail: fragments in fixed latencies with nothing behind them to overlap
  Atomics,          // "atomic_wait": the A-buffer's global node counter (issue 22, items 1-3; the stall cause's name)
  ListWalk,         // the A-buffer resolve's dependent node reads
  Sort,             // the A-buffer resolve's sort
  // DRAM queueing that is not the bus moving data (issue 22 s3; appended so the
  // causes before keep their order, which breaks DelayShares' ties):
  DramBankConflict,  // the bank busy closing or opening rows (tRP, tRAS, tRCD of other rows) with the bus idle
  DramTurnaround,    // read/write turnarounds (tWTR, tRTW): bus idle while the direction switches
  DramRefresh,       // the bank closed for refresh (tRFC)
};
inline constexpr unsigned kRootCauseCount = 16;
const char* rootCauseKey(RootCause c);  // "input", "input_starvation", ... (report keys)

// A memory wait as the cycles it passes through, in order: up to latency_end
// DRAM's unloaded access to the request's first data (its activate and CL go
// on while the bus still moves older data), then the queueing by what the
// controller waited for: up to refresh_end a refresh, up to bank_end the
// bank (rows closing and opening), up to turn_end turnarounds, up to
// queue_end the bus moving other data (next to the transfer: a stage that
// waits for a tail of the wait is charged bandwidth before the idle-bus
// causes); up to dram_end the rest of its data at the bus's rate
// (bandwidth), after that `rest` (the cache's own latency). A stage that
// waits only for the tail of a wait (an older fragment waited for the front)
// is charged for that tail. Inner ends left below latency_end: all of the
// queueing is the bus's.
struct WaitSplit {
  Cycle latency_end = 0, queue_end = 0, dram_end = 0;
  RootCause rest = RootCause::RopCacheMiss;
  Cycle refresh_end = 0, bank_end = 0, turn_end = 0;
  bool operator==(const WaitSplit&) const = default;
};

// What a DRAM request's queueing waited for, as the controller booked it:
// the delay of its data beyond an idle controller's, by cause (DRAM ticks;
// only their proportions are used). All zero: the bus (the default cause).
struct DramQueueParts {
  uint64_t bus = 0, bank = 0, turnaround = 0, refresh = 0;
  uint64_t sum() const { return bus + bank + turnaround + refresh; }
};

// The DRAM side of the requests made since MemorySystem::resetProbe(): the
// one that completed last, done at `done`; an idle controller takes
// `unloaded` cycles to its first data and `transfer` more for the rest of it;
// `queue` says what its queueing waited for. `done` = 0: no DRAM request.
struct DramProbe {
  Cycle done = 0, unloaded = 0, transfer = 0;
  DramQueueParts queue{};
};

// The split of a wait from `now` to `ready` whose DRAM part is `d` (the
// request that completed last): the unloaded access first, then the
// queueing (shared out over refresh, bank, turnaround and bus in the
// proportions of d.queue; all zero: the bus's), the transfer of the rest of
// its data, the rest `rest`.
WaitSplit splitWait(Cycle now, Cycle ready, const DramProbe& d, RootCause rest = RootCause::RopCacheMiss);

// The waits of a partition's latest misses, by the cycle each is ready. An
// access refused for a full miss queue waits for the first entry to free: for
// the oldest miss in flight, whose wait is then in its tail (queueing), not
// for the latest miss, just issued, whose wait is then in its front (its
// unloaded access). Taking the latest's charged a resolve bound by the
// channel's activate limits (test_bounds.cpp, DramActivateLimitFrame) 16-20 %
// dram_latency.
struct MissWait {
  Cycle from = 0, ready = 0;  // the miss's wait: asked at `from`, its line there at `ready`
  WaitSplit wait;
};
class MissWaits {
 public:
  // Keeps the latest `n` (the miss queue's entries: the oldest in flight is among them).
  explicit MissWaits(unsigned n = 1) : ring_(std::max(1u, n)) {}
  void add(Cycle from, Cycle ready, const WaitSplit& w) {
    ring_[next_] = {from, ready, w};
    next_ = next_ + 1 == ring_.size() ? 0 : next_ + 1;
    size_ = std::min<size_t>(size_ + 1, ring_.size());
  }
  // The miss a miss queue that frees at `frees` waits for: the one kept
  // whose ready cycle is the first at or after it; none: nullptr.
  const MissWait* freeingMiss(Cycle frees) const;
  // Its wait; none: `fallback`.
  WaitSplit freeing(Cycle frees, const WaitSplit& fallback) const {
    const MissWait* m = freeingMiss(frees);
    return m ? m->wait : fallback;
  }

 private:
  std::vector<MissWait> ring_;
  size_t next_ = 0, size_ = 0;
};

// The share of the DRAM buses busy over [from, to) (MemorySystem::busShare):
// the part of a wait's unloaded access during which the buses moved other
// data is charged to bandwidth (a shorter latency would not have shortened
// the frame then; a faster bus would). Empty: all latency.
// An object's busShare(from, to) (MemorySystem's), called through a plain
// function pointer: the approximate engine asks it per span, and a
// std::function there cost its own indirections (session 20). The object
// must outlive the accounts that hold it. Empty: all latency.
class BusShareFn {
 public:
  BusShareFn() = default;
  template <class T>
  static BusShareFn of(const T& obj) {
    BusShareFn f;
    f.obj_ = &obj;
    f.call_ = [](const void* o, Cycle from, Cycle to) { return static_cast<const T*>(o)->busShare(from, to); };
    return f;
  }
  explicit operator bool() const { return call_ != nullptr; }
  double operator()(Cycle from, Cycle to) const { return call_(obj_, from, to); }

 private:
  const void* obj_ = nullptr;
  double (*call_)(const void*, Cycle, Cycle) = nullptr;
};

// Splits `n` cycles of unloaded access over [from, to) into latency and bandwidth.
void splitLatency(uint64_t n, Cycle from, Cycle to, const BusShareFn& bus, uint64_t& latency, uint64_t& bandwidth);

// One partition's cycles by root cause, accounted lazily: a cause holds from
// set() until the next set() with another one (as the stage accounts).
class RootCauseAccount {
 public:
  using Cycles = std::array<uint64_t, kRootCauseCount>;
  void setBusShare(BusShareFn f) { bus_ = f; }
  void set(Cycle now, RootCause c) {
    if (!wait_ && c == cause_) return;
    account(now);
    cause_ = c;
    wait_ = false;
  }
  void setWait(Cycle now, const WaitSplit& w) {
    if (wait_ && w == w_) return;
    account(now);
    w_ = w;
    wait_ = true;
  }
  // Accounts the current cause up to `now` (it keeps holding).
  void account(Cycle now);
  // Adds `n` cycles to cause c directly (the approximate engine's spans).
  void add(RootCause c, uint64_t n) { cycles_[std::size_t(c)] += n; }
  // Moves the accounting cursor to `now` without charging (cycles another
  // mechanism charged with add()).
  void skipTo(Cycle now) { since_ = now; }
  const Cycles& cycles() const { return cycles_; }
  uint64_t total() const;

 private:
  Cycles cycles_{};
  BusShareFn bus_;
  RootCause cause_ = RootCause::Input;
  bool wait_ = false;
  WaitSplit w_;
  Cycle since_ = 0;
};

// The approximate engine's coarse attribution of a wait it cannot place in
// time (a full scoreboard, a pass's drain): the delays the fragments in
// flight met since the last such wait, by cause, share it out in proportion
// (largest remainders; all zero: `fallback`).
//
// A wait's unloaded access splits into latency and bandwidth by the bus time
// booked over it (splitLatency), and the approximate engine books requests
// in issue order: when a wait is charged, later fragments' bookings (a write
// batch drained after it) may still fill its span (evaluated then, the spans
// of a DRAM-bound frame looked 73 % busy; with every booking made, 98 %).
// So the cycles the unloaded accesses take are kept with their spans and
// split once the bookings over them are final (settle(), finish()).
class DelayShares {
 public:
  void setBusShare(BusShareFn f) { bus_ = f; }
  void add(RootCause c, uint64_t cycles) { delay_[std::size_t(c)] += cycles; }
  void addWait(Cycle from, Cycle to, const WaitSplit& w);  // [from, to) split as the WaitSplit says
  // `n` cycles in the proportions of w's parts over [from, to) (a hit that
  // waits for another fragment's fill: that fill's proportions).
  void addLike(uint64_t n, Cycle from, Cycle to, const WaitSplit& w);
  // Charges `n` cycles to `acc` in proportion to the delays gathered, then
  // forgets them (the unloaded accesses' share: when settled).
  void chargeTo(RootCauseAccount& acc, uint64_t n, RootCause fallback);
  // Splits the charged unloaded accesses whose spans end by `before` (no
  // booking still to come lands before it) into latency and bandwidth.
  void settle(RootCauseAccount& acc, Cycle before);
  void finish(RootCauseAccount& acc) { settle(acc, ~Cycle(0)); }  // all of them (the phase's end)

 private:
  // The unloaded accesses' cycles not yet split: `unloaded_` in total over
  // the spans added since the last charge; each charge's share of them waits
  // in a Charge over its spans [begin, end) (absolute indices into spans_).
  struct Span {
    Cycle from, to;
    uint64_t n;
  };
  struct Charge {
    uint64_t cycles, begin, end;
    Cycle last_to;
  };
  void addUnloaded(Cycle from, Cycle to, uint64_t n);
  RootCauseAccount::Cycles delay_{};
  uint64_t unloaded_ = 0;
  BusShareFn bus_;
  std::deque<Span> spans_;
  uint64_t spans_base_ = 0, open_begin_ = 0;  // spans_.front()'s index; the first not yet charged
  Cycle open_last_to_ = 0;
  std::deque<Charge> charges_;
};

}  // namespace oit::rop
