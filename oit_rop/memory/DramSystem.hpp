// DramSystem: the sc_module of the memory side the partitions share: the
// DRAM (MemorySystem) and, in front of it, the shared cache levels (l2, l3:
// CacheLevel, owned by OitRop) when the configuration has them. Partitions
// reach the first of them (setEntry; DRAM when there is none) through a
// TLM-2 socket (b_transport) for the depth, colour, resolve and node-pool
// traffic; the request's cycle and surface travel in a DramExtension, the
// completion comes back both as an annotated delay and as the exact cycle.
// The BlendArrayCache's fills and write-backs call the same entry directly
// (a MemoryPort: the thin-interface option, see DESIGN.md).
#pragma once

#include <systemc>
#include <tlm>
#include <tlm_utils/multi_passthrough_target_socket.h>

#include "oit_rop/memory/MemorySystem.hpp"
#include "oit_rop/stages/PipelineQueues.hpp"

namespace oit::rop {

// The MemorySystem (DRAM) as a MemoryPort: the level below the last cache.
class DramPort final : public MemoryPort {
 public:
  explicit DramPort(MemorySystem& memory) : memory_(memory) {}
  Cycle access(Cycle now, uint64_t addr, uint32_t bytes, bool write, Surface s) override {
    return memory_.access(now, addr, bytes, write, s);
  }

 private:
  MemorySystem& memory_;
};

struct DramExtension : tlm::tlm_extension<DramExtension> {
  Cycle now = 0;
  Cycle done = 0;
  Surface surface = Surface::BlendArrays;
  tlm::tlm_extension_base* clone() const override { return new DramExtension(*this); }
  void copy_from(const tlm::tlm_extension_base& o) override { *this = static_cast<const DramExtension&>(o); }
};

// Core cycles <-> SystemC time (absolute conversions only, so rounding to the
// time resolution never accumulates).
struct CoreClock {
  double period_ns = 1.0;
  explicit CoreClock(double mhz = 1000.0) : period_ns(1000.0 / mhz) {}
  sc_core::sc_time time(Cycle c) const { return sc_core::sc_time(double(c) * period_ns, sc_core::SC_NS); }
  Cycle cycle(const sc_core::sc_time& t) const { return Cycle(t.to_seconds() * 1e9 / period_ns + 0.5); }
};

class DramSystem : public sc_core::sc_module {
 public:
  // One binding per RopPartition's initiator socket.
  tlm_utils::multi_passthrough_target_socket<DramSystem> target;

  DramSystem(sc_core::sc_module_name name, const DramConfig& cfg, double core_mhz);
  MemorySystem& memory() { return memory_; }
  // The first level the partitions' requests go to: the DRAM until set
  // (OitRop sets its l2 when there is one).
  MemoryPort& entry() { return *entry_; }
  void setEntry(MemoryPort& entry) { entry_ = &entry; }

 private:
  void b_transport(int initiator, tlm::tlm_generic_payload& p, sc_core::sc_time& delay);
  MemorySystem memory_;
  DramPort dram_port_;
  MemoryPort* entry_;
  CoreClock clock_;
};

}  // namespace oit::rop
