// The property registry: one row per RopConfig field (its dotted path, type,
// allowed range or names, unit and description), bound to the field by member
// pointers so the tree and the struct cannot drift apart silently
// (tests/oit_rop/config/test_config_registry.cpp counts each section's fields
// against it). ConfigTree (ConfigTree.cpp) parses, sets, checks and prints
// every property through these rows; the presets' values are in Presets.cpp.
// Internal to oit_rop/config.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <variant>
#include <vector>

#include "oit_rop/config/ConfigTree.hpp"

namespace oit::rop::config_registry {

using Value = std::variant<bool, uint64_t, double, std::string>;

struct Property {
  std::string path, unit, description;
  PropertyType type = PropertyType::Integer;
  uint64_t imin = 0, imax = std::numeric_limits<uint64_t>::max();
  bool pow2 = false;
  double fmin = 0, fmax = 0;
  bool fmin_open = false;  // (fmin, fmax] instead of [fmin, fmax]
  std::vector<std::string> names;  // Enum
  std::function<Value(const RopConfig&)> get;
  std::function<void(RopConfig&, const Value&)> put;

  std::string allowed() const;  // "[1, 64], power of two", "(0, 1]", "pixel | quad | tile"
};

// Every property, in the order `oitsim config` prints them.
const std::vector<Property>& registry();

}  // namespace oit::rop::config_registry
