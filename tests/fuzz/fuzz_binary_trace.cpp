// libFuzzer harness of the binary trace reader (traces/BinaryTrace.cpp): any
// byte string as a .oitt file. The reader must accept it or throw TraceError;
// anything else (another exception, a crash, a leak, a sanitizer report, a
// hang) is a bug. Accepted traces are read twice (rewind) in small batches.
#include <cstddef>
#include <cstdint>

#include "FuzzFile.hpp"
#include "traces/TraceIO.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static oit::fuzz::FuzzFile file(".oitt");
  const std::string& path = file.write(data, size);
  try {
    auto src = oit::openTrace(path, {.batch_records = 7});
    for (int pass = 0; pass < 2; ++pass) {
      uint64_t seen = 0;
      for (auto b = src->next(); !b.empty(); b = src->next()) seen += b.size();
      if (seen != src->header().fragment_count) __builtin_trap();  // every record, once
      src->rewind();
    }
  } catch (const oit::TraceError&) {
  }
  return 0;
}
