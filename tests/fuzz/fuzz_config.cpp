// libFuzzer harness of the ROP configuration (oit_rop/config/ConfigTree.cpp): the
// input up to its first NUL byte is a --config JSON file, each line after it
// one --set a.b=v. resolveTree must return a valid tree or throw
// std::invalid_argument with a message; and the tree it returns must print
// and re-read as JSON without change.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "FuzzFile.hpp"
#include "oit_rop/config/ConfigTree.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static oit::fuzz::FuzzFile file(".json");
  const auto* nul = static_cast<const uint8_t*>(std::memchr(data, 0, size));
  const size_t json_size = nul ? size_t(nul - data) : size;
  const std::string& path = file.write(data, json_size);
  std::vector<std::string> sets;
  if (nul) {
    std::string rest(reinterpret_cast<const char*>(nul + 1), size - json_size - 1);
    for (size_t start = 0; start <= rest.size();) {
      const size_t nl = rest.find('\n', start);
      sets.push_back(rest.substr(start, nl == std::string::npos ? std::string::npos : nl - start));
      if (nl == std::string::npos) break;
      start = nl + 1;
    }
  }
  try {
    const oit::rop::ConfigTree tree = oit::rop::resolveTree("", path, sets);
    if (tree.config().preset.empty()) __builtin_trap();
    (void)tree.toJson().dump();
  } catch (const std::invalid_argument& e) {
    if (std::strlen(e.what()) == 0) __builtin_trap();  // an error says what is wrong
  }
  return 0;
}
