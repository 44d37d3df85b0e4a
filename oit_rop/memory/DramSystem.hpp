// DramSystem: the sc_module around the shared MemorySystem (DramChannel
// model). Partitions reach it through a TLM-2 socket (b_transport) for the
// depth, colour, resolve and node-pool traffic; the request's cycle and
// surface travel in a DramExtension, the completion comes back both as an
// annotated delay and as the exact cycle. The BlendArrayCache's fixed
// interface takes the MemorySystem itself, so line fills and write-backs call
// MemorySystem::access directly (the thin-interface option, see DESIGN.md).
#pragma once

#include <systemc>
#include <tlm>
#include <tlm_utils/multi_passthrough_target_socket.h>

#include "oit_rop/memory/MemorySystem.hpp"

namespace oit::rop {

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

 private:
  void b_transport(int initiator, tlm::tlm_generic_payload& p, sc_core::sc_time& delay);
  MemorySystem memory_;
  CoreClock clock_;
};

}  // namespace oit::rop
