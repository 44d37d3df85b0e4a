#include "model/AlgorithmSettings.hpp"

#include <stdexcept>

#include "model/OitAlgorithm.hpp"

namespace oit::model {

AlgorithmSettings algorithmSettings(std::string_view algorithm) {
  // From each algorithm's constructor and factory (model/Algorithm*.cpp): the
  // AlgorithmParams fields it reads or validates.
  struct Row {
    std::string_view name;
    AlgorithmSettings uses;
  };
  static const Row kRows[] = {
      {"abuffer", {.format = true}},  // the node stores its colour in the format
      {"alpha", {.format = true}},
      {"mlab", {.layers = true, .format = true}},
      {"hybrid", {.layers = true, .format = true}},
      {"adaptive", {.layers = true, .format = true}},  // fp32 only: other formats are refused
      {"kbuffer", {.layers = true, .format = true}},
      {"wsum", {.format = true}},
      {"wavg", {.format = true}},
      {"wboit", {.format = true, .weight = true}},
      {"slab", {.layers = true, .format = true, .bits = true, .seed = true}},  // fp32 only
      {"stochastic", {.format = true, .samples = true, .seed = true}},         // fp32 only
      {"mlcb", {.layers = true, .format = true, .bits = true, .seed = true}},
  };
  for (const Row& r : kRows)
    if (r.name == algorithm) return r.uses;
  std::string valid;
  for (const auto& info : algorithmNames()) valid += (valid.empty() ? "" : ", ") + std::string(info.name);
  throw std::invalid_argument("unknown OIT algorithm '" + std::string(algorithm) + "' (valid: " + valid + ")");
}

std::vector<std::string> ignoredSettings(std::string_view algorithm) {
  const AlgorithmSettings u = algorithmSettings(algorithm);
  std::vector<std::string> out;
  if (!u.layers) out.push_back("layers");
  if (!u.format) out.push_back("format");
  if (!u.bits) out.push_back("bits");
  if (!u.samples) out.push_back("samples");
  if (!u.weight) out.push_back("weight");
  if (!u.seed) out.push_back("seed");
  return out;
}

}  // namespace oit::model
