// libFuzzer harness of the sweep spec (reports/SweepSpec.cpp, SweepPlan.cpp):
// any byte string as a JSON spec, loaded and planned as `oitsim sweep` does
// before anything runs (spec syntax, traces, settings, axes, every point's ROP
// configuration). It must give the points or throw std::invalid_argument
// naming what is wrong; nothing is run or written (planSweep creates nothing).
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <stdexcept>

#include "FuzzFile.hpp"
#include "reports/SweepPlan.hpp"
#include "reports/SweepSpec.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static oit::fuzz::FuzzFile file(".json");
  const std::string& path = file.write(data, size);
  try {
    const oit::sweep::ojson spec = oit::sweep::loadSpec(path);
    const oit::sweep::Plan plan = oit::sweep::planSweep(spec, path, "/nonexistent/oitsim-fuzz-out", "/bin/oitsim");
    for (const auto& p : plan.points)
      if (p.args.empty() || p.args[0] != "run") __builtin_trap();  // every point is an `oitsim run`
  } catch (const std::invalid_argument& e) {
    if (std::strlen(e.what()) == 0) __builtin_trap();  // an error says what is wrong
  }
  return 0;
}
