// libFuzzer harness of the CSV trace reader (traces/CsvTraceReader.cpp): any byte
// string as a .csv file (64 x 64 when it names no frame size). It must be
// accepted or refused with TraceError; accepted traces are read twice in
// small batches, and must survive a round trip through the binary writer and
// reader bit for bit.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

#include "FuzzFile.hpp"
#include "traces/TraceIO.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static oit::fuzz::FuzzFile file(".csv");
  static oit::fuzz::FuzzFile copy(".oitt");
  const std::string& path = file.write(data, size);
  std::unique_ptr<oit::FragmentSource> src;
  std::vector<oit::Fragment> first;
  try {
    src = oit::openTrace(path, {.width = 64, .height = 64, .batch_records = 5});
    for (int pass = 0; pass < 2; ++pass) {
      uint64_t seen = 0;
      for (auto b = src->next(); !b.empty(); b = src->next()) {
        if (pass == 0) first.insert(first.end(), b.begin(), b.end());
        seen += b.size();
      }
      if (seen != src->header().fragment_count) __builtin_trap();
      src->rewind();
    }
  } catch (const oit::TraceError&) {
    return 0;
  }
  // What the reader accepted, the binary writer takes (no exception allowed
  // here) and the binary reader gives back bit for bit.
  auto w = oit::createTraceWriter(copy.path(), src->header());
  w->write(first);
  w->commit();
  auto back = oit::openTrace(copy.path());
  size_t i = 0;
  for (auto b = back->next(); !b.empty(); b = back->next())
    for (const oit::Fragment& f : b)
      if (i >= first.size() || std::memcmp(&f, &first[i++], sizeof f) != 0) __builtin_trap();
  if (i != first.size()) __builtin_trap();
  return 0;
}
