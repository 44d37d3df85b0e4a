// What SystemC this build links against (the design card requires 2.3.4).
#pragma once

#include <string>

namespace oit::rop {

// sc_core::sc_release(), e.g. "2.3.4-Accellera".
std::string systemcRelease();

}  // namespace oit::rop
