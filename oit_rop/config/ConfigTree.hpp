// The named property tree over RopConfig (VCML style): every model parameter is
// a dotted path with a type, a default (the preset's value), a unit, an allowed
// range or set of names and a one-line description. Values come, in order, from
// a preset, a JSON file and `--set path=value` overrides; validate() then checks
// the constraints that span several fields. See oit_rop/config/CONFIG.md.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "oit_rop/config/RopConfig.hpp"

namespace oit::rop {

enum class PropertyType : uint8_t { Bool, Integer, Float, Enum };
const char* toString(PropertyType t);

struct PropertyInfo {
  std::string path;           // "lock.granularity"
  PropertyType type = PropertyType::Integer;
  std::string unit;           // "cycles", "bytes", "GB/s", "" ...
  std::string description;    // one line; "[inferred]" where the hardware notes estimate
  std::string value;          // effective value, spelled as set() accepts it
  std::string default_value;  // the preset's value
  std::string allowed;        // "[1, 64], power of two", "(0, 1]", "pixel | quad | tile"
  std::vector<std::string> enum_values;  // Enum only
  bool inferred = false;      // the preset's value is an estimate, not a reading (CONFIG.md)
};

class ConfigTree {
 public:
  // Throws std::invalid_argument for an unknown preset, listing the known ones.
  static ConfigTree forPreset(std::string_view name);

  // One property from text: "true"/"false"/"on"/"off"/"1"/"0", decimal integers
  // (bytes also take KiB/MiB/GiB suffixes), floats, enum names. Throws
  // std::invalid_argument naming the path, the value and what was expected, or
  // the closest known path for an unknown one.
  void set(std::string_view path, std::string_view value);
  // One property from a JSON value (native type, or a string parsed as by set()).
  void setJson(std::string_view path, const nlohmann::json& value);

  // A JSON object, nested ({"lock": {"granularity": "quad"}}) and/or dotted
  // ({"lock.granularity": "quad"}) keys. An optional top-level "preset" must name
  // this tree's preset (resolveTree() picks the file's preset when none is given).
  // Errors name the file and the key; a property given twice in one file is an error.
  void loadJson(const std::string& file);
  void applyJson(const nlohmann::json& j, const std::string& origin);  // loadJson without the file

  // Cross-field constraints (latency_min <= latency_max, the cache holds whole
  // sets, DRAM burst/interleave/row sizes nest, fp32 no faster than fp16 ...).
  // Throws std::invalid_argument listing every violation.
  void validate() const;

  const RopConfig& config() const { return cfg_; }
  const std::string& preset() const { return cfg_.preset; }
  nlohmann::json toJson() const;  // {"preset": ..., "clock": {"core_mhz": ...}, ...}
  std::string describe() const;   // aligned table: path, value, unit, default if different, description
  std::vector<PropertyInfo> properties() const;

 private:
  explicit ConfigTree(RopConfig preset_cfg);
  RopConfig cfg_;
  RopConfig defaults_;  // the preset, for "default" columns
};

std::vector<std::string> presetNames();  // {"iris-pro-5200", "titan-x-maxwell", "navi21"}
// Other names a preset answers to: {alias, preset} ({"igpu", "iris-pro-5200"}, {"dgpu", "titan-x-maxwell"}).
std::vector<std::pair<std::string, std::string>> presetAliases();
// The preset an alias names; any other name unchanged.
std::string canonicalPresetName(std::string_view name);
// The preset's values (oit_rop/Presets.cpp); throws std::invalid_argument for an unknown name.
RopConfig presetConfig(std::string_view name);
// Whether the preset's value of `path` is an estimate (the notes' [inferred] or ours).
bool presetValueInferred(std::string_view preset, std::string_view path);

// Preset (empty: the file's "preset" key, else iris-pro-5200), then the file (empty: none),
// then each "path=value" in order; validated. Malformed or failing overrides throw
// std::invalid_argument naming the --set option.
ConfigTree resolveTree(const std::string& preset, const std::string& config_file,
                       const std::vector<std::string>& sets);
RopConfig resolveConfig(const std::string& preset, const std::string& config_file,
                        const std::vector<std::string>& sets);

// lock.mode's value as the property spells it ("ordered", "unordered", "none").
const char* lockModeName(LockMode mode);
// The one-line refusal of a lock.mode other than ordered on sim.engine=approximate
// (validate() and runTiming() both refuse it).
std::string approximateLockModeProblem(LockMode mode);

// Markdown table of every property for all presets side by side (CONFIG.md).
std::string presetTableMarkdown();


}  // namespace oit::rop
