#include "oit_rop/memory/DramSystem.hpp"

namespace oit::rop {

DramSystem::DramSystem(sc_core::sc_module_name name, const DramConfig& cfg, double core_mhz)
    : sc_module(name), target("target"), memory_(cfg, core_mhz), dram_port_(memory_), entry_(&dram_port_),
      clock_(core_mhz) {
  target.register_b_transport(this, &DramSystem::b_transport);
}

void DramSystem::b_transport(int, tlm::tlm_generic_payload& p, sc_core::sc_time& delay) {
  DramExtension* ext = nullptr;
  p.get_extension(ext);
  if (!ext) {
    p.set_response_status(tlm::TLM_GENERIC_ERROR_RESPONSE);
    return;
  }
  ext->done = entry_->access(ext->now, p.get_address(), p.get_data_length(), p.is_write(), ext->surface);
  // Loosely timed: the delay annotates when the transfer completes.
  const sc_core::sc_time done = clock_.time(ext->done), stamp = sc_core::sc_time_stamp();
  delay = done > stamp ? done - stamp : sc_core::SC_ZERO_TIME;
  p.set_response_status(tlm::TLM_OK_RESPONSE);
}

}  // namespace oit::rop
