#include "oit_rop/SystemcInfo.hpp"

#include <systemc>

namespace oit::rop {

std::string systemcRelease() { return sc_core::sc_release(); }

}  // namespace oit::rop
