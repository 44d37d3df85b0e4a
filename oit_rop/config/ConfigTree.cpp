// The named property tree over RopConfig: values parsed from text and JSON,
// set, checked (one field and across fields) and printed, through the rows of
// the property registry (PropertyRegistry.cpp).
#include "oit_rop/config/ConfigTree.hpp"
#include "oit_rop/config/PropertyRegistry.hpp"
#include "oit_rop/memory/DramTimings.hpp"
#include "oit_rop/config/RepeatedKeys.hpp"
#include "traces/InputFile.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <stdexcept>
#include <variant>

namespace oit::rop {
namespace {

using config_registry::Property;
using config_registry::registry;
using config_registry::Value;

std::string formatValue(const Value& v) {
  struct {
    std::string operator()(bool b) const { return b ? "true" : "false"; }
    std::string operator()(uint64_t u) const { return std::to_string(u); }
    std::string operator()(double d) const { return fmt::format("{}", d); }  // shortest round-trip
    std::string operator()(const std::string& s) const { return s; }
  } f;
  return std::visit(f, v);
}

nlohmann::json jsonValue(const Value& v) {
  return std::visit([](const auto& x) { return nlohmann::json(x); }, v);
}

const Property* find(std::string_view path) {
  for (const auto& p : registry())
    if (p.path == path) return &p;
  return nullptr;
}

size_t editDistance(std::string_view a, std::string_view b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diag = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

// Properties that were replaced: setting one is an error naming its successor.
struct Retired {
  std::string_view path, message;
};
constexpr Retired kRetired[] = {
    {"lock.ordered",
     "'lock.ordered' was replaced by lock.mode (ordered | unordered | none): lock.ordered=true is "
     "lock.mode=ordered; lock.ordered=false is lock.mode=unordered, whose image now follows the order the "
     "fragments enter the lock (oit_rop/DESIGN.md)"},
};

[[noreturn]] void unknownPath(std::string_view path) {
  for (const Retired& r : kRetired)
    if (r.path == path) throw std::invalid_argument(std::string(r.message));
  // A group name ("lock") lists its properties.
  std::vector<std::string> members;
  const std::string prefix = std::string(path) + ".";
  for (const auto& p : registry())
    if (p.path.starts_with(prefix)) members.push_back(p.path);
  if (!members.empty())
    throw std::invalid_argument(fmt::format("'{}' is a group, not a property; its properties: {}", path,
                                            fmt::join(members, ", ")));
  // Closest full path; a bare leaf name ("granularity") matches its full path exactly.
  const Property* best = nullptr;
  size_t best_d = std::numeric_limits<size_t>::max();
  for (const auto& p : registry()) {
    const std::string_view leaf = std::string_view(p.path).substr(p.path.rfind('.') + 1);
    const size_t d = std::min(editDistance(path, p.path), leaf == path ? 0 : editDistance(path, leaf) + 2);
    if (d < best_d) best_d = d, best = &p;
  }
  if (best && best_d <= std::max<size_t>(3, path.size() / 3))
    throw std::invalid_argument(fmt::format("unknown property '{}'; did you mean '{}'?", path, best->path));
  throw std::invalid_argument(fmt::format(
      "unknown property '{}'; groups: clock, partitions, input, early_depth, lock, cache, alu, dram, stats, "
      "skip, sim (`oitsim config` lists every property)",
      path));
}

std::string expected(const Property& p) {
  const char* what = p.type == PropertyType::Bool      ? "a boolean"
                     : p.type == PropertyType::Integer ? "an integer"
                     : p.type == PropertyType::Float   ? "a number"
                                                       : "one of";
  return p.unit.empty() ? fmt::format("{} {}", what, p.allowed())
                        : fmt::format("{} {} ({})", what, p.allowed(), p.unit);
}

[[noreturn]] void badValue(const Property& p, std::string_view value, std::string_view why) {
  throw std::invalid_argument(
      fmt::format("{}: '{}' {}; expected {}", p.path, value, why, expected(p)));
}

// Range checks shared by text and JSON input; `shown` is the value as given.
Value checked(const Property& p, Value v, std::string_view shown) {
  if (p.type == PropertyType::Integer) {
    const uint64_t u = std::get<uint64_t>(v);
    if (u < p.imin || u > p.imax) badValue(p, shown, "is out of range");
    if (p.pow2 && !std::has_single_bit(u)) badValue(p, shown, "is not a power of two");
  } else if (p.type == PropertyType::Float) {
    const double d = std::get<double>(v);
    if (!std::isfinite(d)) badValue(p, shown, "is not a finite number");
    if (d < p.fmin || (p.fmin_open && d == p.fmin) || d > p.fmax) badValue(p, shown, "is out of range");
  } else if (p.type == PropertyType::Enum) {
    if (std::find(p.names.begin(), p.names.end(), std::get<std::string>(v)) == p.names.end())
      badValue(p, shown, "is not a known value");
  }
  return v;
}

Value parseText(const Property& p, std::string_view text) {
  std::string_view s = text;
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  if (s.empty()) badValue(p, text, "is empty");
  switch (p.type) {
    case PropertyType::Bool: {
      std::string l(s);
      std::transform(l.begin(), l.end(), l.begin(), [](unsigned char c) { return char(std::tolower(c)); });
      if (l == "true" || l == "on" || l == "yes" || l == "1") return true;
      if (l == "false" || l == "off" || l == "no" || l == "0") return false;
      badValue(p, text, "is not a boolean");
    }
    case PropertyType::Integer: {
      uint64_t u = 0;
      const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), u);
      if (ec == std::errc::result_out_of_range) badValue(p, text, "is out of range");
      if (ec != std::errc() || end == s.data()) badValue(p, text, "is not a non-negative integer");
      std::string_view suffix(end, size_t(s.data() + s.size() - end));
      uint64_t scale = 1;
      // Sizes in bytes read naturally as 64KiB or 2MiB.
      if (!suffix.empty() && p.unit == "bytes") {
        if (suffix == "KiB" || suffix == "K") scale = uint64_t(1) << 10;
        else if (suffix == "MiB" || suffix == "M") scale = uint64_t(1) << 20;
        else if (suffix == "GiB" || suffix == "G") scale = uint64_t(1) << 30;
        else if (suffix != "B") badValue(p, text, "has an unknown suffix (use B, KiB, MiB or GiB)");
      } else if (!suffix.empty()) {
        badValue(p, text, "is not a non-negative integer");
      }
      if (u > std::numeric_limits<uint64_t>::max() / scale) badValue(p, text, "is out of range");
      return checked(p, u * scale, text);
    }
    case PropertyType::Float: {
      double d = 0;
      const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), d);
      if (ec == std::errc::result_out_of_range && end == s.data() + s.size()) badValue(p, text, "is out of range");
      if (ec != std::errc() || end != s.data() + s.size()) badValue(p, text, "is not a number");
      return checked(p, d, text);
    }
    case PropertyType::Enum: return checked(p, std::string(s), text);
  }
  return {};
}

Value parseJson(const Property& p, const nlohmann::json& j) {
  if (j.is_string()) return parseText(p, j.get<std::string>());
  const std::string shown = j.dump();
  switch (p.type) {
    case PropertyType::Bool:
      if (j.is_boolean()) return j.get<bool>();
      break;
    case PropertyType::Integer:
      if (j.is_number_unsigned()) return checked(p, j.get<uint64_t>(), shown);
      if (j.is_number_integer()) badValue(p, shown, "is out of range");  // negative
      if (j.is_number_float()) {
        const double d = j.get<double>();
        // 65536.0 is an integer; 1e30 or 2.5 are not.
        if (d >= 0 && d < 18446744073709551616.0 && std::floor(d) == d) return checked(p, uint64_t(d), shown);
        // A whole number past 2^64 - 1 (JSON reads it as a double) is a range error.
        if (d >= 18446744073709551616.0 && std::isfinite(d) && std::floor(d) == d) badValue(p, shown, "is out of range");
        badValue(p, shown, "is not a non-negative integer");
      }
      break;
    case PropertyType::Float:
      if (j.is_number()) return checked(p, j.get<double>(), shown);
      break;
    case PropertyType::Enum: break;
  }
  badValue(p, shown, fmt::format("has the wrong JSON type ({})", j.type_name()));
}

}  // namespace

std::string approximateLockModeProblem(LockMode mode) {
  return fmt::format(
      "lock.mode={} is not modelled by sim.engine=approximate (it visits fragments in submission order, so it "
      "cannot apply inserts in lock-entry order or race them); use sim.engine=cycle or lock.mode=ordered",
      lockModeName(mode));
}

const char* lockModeName(LockMode m) {
  switch (m) {
    case LockMode::Ordered: return "ordered";
    case LockMode::Unordered: return "unordered";
    case LockMode::None: return "none";
  }
  return "?";
}

const char* toString(PropertyType t) {
  switch (t) {
    case PropertyType::Bool: return "bool";
    case PropertyType::Integer: return "integer";
    case PropertyType::Float: return "float";
    case PropertyType::Enum: return "enum";
  }
  return "?";
}

ConfigTree::ConfigTree(RopConfig preset_cfg) : cfg_(preset_cfg), defaults_(std::move(preset_cfg)) {}

ConfigTree ConfigTree::forPreset(std::string_view name) { return ConfigTree(presetConfig(name)); }

void ConfigTree::set(std::string_view path, std::string_view value) {
  const Property* p = find(path);
  if (!p) {
    if (path == "preset")
      throw std::invalid_argument("'preset' is not a property: choose it with --preset or a file's \"preset\" key");
    unknownPath(path);
  }
  p->put(cfg_, parseText(*p, value));
}

void ConfigTree::setJson(std::string_view path, const nlohmann::json& value) {
  const Property* p = find(path);
  if (!p) unknownPath(path);
  p->put(cfg_, parseJson(*p, value));
}

void ConfigTree::applyJson(const nlohmann::json& j, const std::string& origin) {
  if (!j.is_object())
    throw std::invalid_argument(fmt::format("{}: expected a JSON object, found {}", origin, j.type_name()));
  std::map<std::string, std::string> seen;  // property path -> key as written
  std::function<void(const nlohmann::json&, const std::string&)> walk = [&](const nlohmann::json& obj,
                                                                            const std::string& prefix) {
    for (const auto& [key, val] : obj.items()) {
      const std::string path = prefix.empty() ? key : prefix + "." + key;
      const std::string shown = prefix.empty() ? key : prefix + "/" + key;  // where it sits in the file
      if (prefix.empty() && key == "preset") {
        if (!val.is_string() || canonicalPresetName(val.get<std::string>()) != cfg_.preset)
          throw std::invalid_argument(fmt::format(
              "{}: key 'preset': the file is for preset {} but the tree was built from preset '{}'; pass "
              "--preset {} (or drop the key)",
              origin, val.dump(), cfg_.preset, val.is_string() ? val.get<std::string>() : "NAME"));
        continue;
      }
      if (val.is_object() && !find(path)) {
        walk(val, path);
        continue;
      }
      try {
        if (val.is_null() || val.is_array() || val.is_object())
          throw std::invalid_argument(fmt::format("{}: expected {}, found a JSON {}", path,
                                                  find(path) ? expected(*find(path)) : "a value", val.type_name()));
        const auto [it, fresh] = seen.emplace(path, shown);
        if (!fresh)
          throw std::invalid_argument(fmt::format("{} is given twice (also as '{}')", path, it->second));
        setJson(path, val);
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument(fmt::format("{}: key '{}': {}", origin, shown, e.what()));
      }
    }
  };
  walk(j, "");
}

namespace {

// Far above any real configuration (a few KiB): a larger file is not one.
constexpr uint64_t kMaxConfigFileBytes = uint64_t{16} << 20;

// Reads a config file (JSON, comments allowed). Every error names the file:
// syntax errors with nlohmann's line and column, number overflow (1e400) and a
// key repeated within one object (JSON parsers keep the last silently).
nlohmann::json readConfigFile(const std::string& file) {
  // A regular file only, opened without blocking (a FIFO would hang, a device
  // never end, a directory gave "basic_filebuf::underflow error").
  const InputFile in = openInputFile(file);
  if (!in && in.error != 0) throw std::invalid_argument(fmt::format("{}: cannot open config file", file));
  if (!in) throw std::invalid_argument(fmt::format("{}: {} (expected a JSON config file)", file, in.problem));
  std::string text, problem;
  if (!readAll(in, kMaxConfigFileBytes, text, problem))
    throw std::invalid_argument(fmt::format("{}: config file {}", file, problem));
  const auto cb = refuseRepeatedKeys<nlohmann::json>(
      [&](const std::string& key) {
        throw std::invalid_argument(fmt::format(
            "{}: key '{}' appears twice in the same JSON object (the second would silently replace the first); "
            "give each key once",
            file, key));
      },
      KeyPath::Slashed);
  try {
    return nlohmann::json::parse(text, cb, true, /*ignore_comments=*/true);
  } catch (const nlohmann::json::exception& e) {  // parse_error (with line, column), out_of_range.406 ...
    throw std::invalid_argument(fmt::format("{}: not valid JSON: {}", file, e.what()));
  }
}

}  // namespace

void ConfigTree::loadJson(const std::string& file) { applyJson(readConfigFile(file), file); }

void ConfigTree::validate() const {
  std::vector<std::string> errs;
  const RopConfig& c = cfg_;
  if (c.input.latency_model == LatencyModel::Uniform && c.input.latency_min > c.input.latency_max)
    errs.push_back(fmt::format("input.latency_min ({}) > input.latency_max ({}) with the uniform latency model",
                               c.input.latency_min, c.input.latency_max));
  // A 2x2 quad must lie inside one tile (tile sizes are powers of two, so at
  // least 2 suffices): tiles are interleaved over the
  // partitions, each with its own scoreboard, so a quad straddling two tiles
  // would be locked in parts (audit: 1x1 tiles gave pixel-granularity waits).
  if (c.lock.granularity == LockGranularity::Quad &&
      (c.partitions.tile_width < 2 || c.partitions.tile_height < 2))
    errs.push_back(fmt::format(
        "lock.granularity quad needs partitions.tile_width and tile_height of at least 2 (now {} x {}): a 2x2 quad "
        "across two tiles would be split over partitions and locked in parts",
        c.partitions.tile_width, c.partitions.tile_height));
  // The ROP cache: lines hold whole sectors, the cache whole sets of lines.
  const auto sectorProblems = [&](const std::string& n, unsigned line, unsigned sector) {
    if (sector == 0) return;
    if (sector > line || line % sector != 0 || (sector & (sector - 1)) != 0)
      errs.push_back(fmt::format("{0}.sector_bytes ({1}) must be a power of two dividing {0}.line_bytes ({2})", n,
                                 sector, line));
    else if (line / sector > 32)
      errs.push_back(fmt::format("{0}.line_bytes ({1}) holds {2} sectors of {0}.sector_bytes ({3}); at most 32 are "
                                 "modelled (valid and dirty masks of 32 bits)",
                                 n, line, line / sector, sector));
    if (sector != 0 && sector < 8)
      errs.push_back(fmt::format("{}.sector_bytes ({}) must be at least 8 (or 0, the whole line)", n, sector));
  };
  if (c.cache.line_bytes > c.cache.size_bytes)
    errs.push_back(fmt::format("cache.line_bytes ({}) is larger than the cache, cache.size_bytes ({})",
                               c.cache.line_bytes, c.cache.size_bytes));
  else if (c.cache.size_bytes % (uint64_t(c.cache.ways) * c.cache.line_bytes) != 0)
    errs.push_back(fmt::format(
        "cache.size_bytes ({}) is not a multiple of cache.ways x cache.line_bytes ({} x {} = {}): every set holds "
        "whole lines",
        c.cache.size_bytes, c.cache.ways, c.cache.line_bytes, uint64_t(c.cache.ways) * c.cache.line_bytes));
  sectorProblems("cache", c.cache.line_bytes, c.cache.sector_bytes);
  // The shared levels: l3 behind l2, lines no smaller than the level above's
  // (a line above must fit in one line below).
  const auto levelProblems = [&](const std::string& n, const SharedCacheConfig& l, const std::string& above,
                                 unsigned above_line) {
    if (l.size_bytes == 0) return;
    if (l.line_bytes < above_line)
      errs.push_back(fmt::format("{}.line_bytes ({}) is smaller than {}.line_bytes ({}): a line of the level above "
                                 "must fit in one {} line",
                                 n, l.line_bytes, above, above_line, n));
    const uint64_t set_bytes = uint64_t(l.ways) * l.line_bytes * l.slices;
    if (l.line_bytes > l.size_bytes)
      errs.push_back(
          fmt::format("{}.line_bytes ({}) is larger than the cache, {}.size_bytes ({})", n, l.line_bytes, n, l.size_bytes));
    else if (l.size_bytes % set_bytes != 0)
      errs.push_back(fmt::format("{0}.size_bytes ({1}) is not a multiple of {0}.slices x {0}.ways x {0}.line_bytes "
                                 "({2} x {3} x {4} = {5}): every slice holds whole sets",
                                 n, l.size_bytes, l.slices, l.ways, l.line_bytes, set_bytes));
    sectorProblems(n, l.line_bytes, l.sector_bytes);
  };
  levelProblems("l2", c.l2, "cache", c.cache.line_bytes);
  if (c.l3.size_bytes != 0 && c.l2.size_bytes == 0)
    errs.push_back("l3.size_bytes is set but l2.size_bytes is 0: the l3 is the level behind the l2 (to model one "
                   "shared level, set l2.* instead)");
  else
    levelProblems("l3", c.l3, "l2", c.l2.line_bytes);
  if (c.dram.burst_bytes > c.dram.interleave_bytes)
    errs.push_back(fmt::format("dram.burst_bytes ({}) > dram.interleave_bytes ({}): a burst would span channels",
                               c.dram.burst_bytes, c.dram.interleave_bytes));
  if (c.dram.burst_bytes > c.dram.row_bytes)
    errs.push_back(fmt::format("dram.burst_bytes ({}) > dram.row_bytes ({})", c.dram.burst_bytes, c.dram.row_bytes));
  // The write queue's watermarks (MEMORY.md): a drain starts at write_high
  // waiting bursts and stops at or below write_low, within write_queue entries.
  if (c.dram.write_high > c.dram.write_queue)
    errs.push_back(fmt::format(
        "dram.write_high ({}) > dram.write_queue ({}): the high watermark must fit in the write queue",
        c.dram.write_high, c.dram.write_queue));
  if (c.dram.write_low >= c.dram.write_high)
    errs.push_back(fmt::format("dram.write_low ({}) >= dram.write_high ({}): the low watermark must be below the high one",
                               c.dram.write_low, c.dram.write_high));
  if (c.dram.trefi_ns > 0 && c.clock.core_mhz > 0 && c.dram.channel_gbps > 0 && c.dram.tck_ns > 0) {
    const std::string problem = DramTimings::refreshProblem(c.dram, c.clock.core_mhz);
    if (!problem.empty()) errs.push_back(problem);
  }
  if (const std::string problem = DramTimings::activateProblem(c.dram); !problem.empty()) errs.push_back(problem);
  for (const std::string& problem : DramTimings::bankGroupProblems(c.dram)) errs.push_back(problem);
  if (c.alu.fp32_rate > c.alu.fp16_rate)
    errs.push_back(fmt::format("alu.fp32_rate ({}) > alu.fp16_rate ({}): wider rows cannot blend faster",
                               c.alu.fp32_rate, c.alu.fp16_rate));
  // The DRAM model keeps time in 2^-16 core cycles (MEMORY.md): a burst must
  // take at least one such tick on its channel's bus.
  if (c.clock.core_mhz > 0 && c.dram.channel_gbps > 0) {
    const double burst_cycles = double(c.dram.burst_bytes) * c.clock.core_mhz / (c.dram.channel_gbps * 1000.0);
    if (!(burst_cycles >= 1.0 / 65536))
      errs.push_back(fmt::format(
          "dram.channel_gbps ({} GB/s) at clock.core_mhz ({} MHz): a {}-byte burst takes {:.3g} core cycles, below "
          "the DRAM model's resolution of 2^-16 cycles; lower the bandwidth or raise the clock",
          c.dram.channel_gbps, c.clock.core_mhz, c.dram.burst_bytes, burst_cycles));
  }
  // Partitions resume 1 to N ps after each quantum boundary, in round-robin
  // order (DESIGN.md): those offsets must stay within half a cycle.
  if (c.clock.core_mhz > 0 && double(c.partitions.count) >= 0.5e6 / c.clock.core_mhz)
    errs.push_back(fmt::format(
        "partitions.count ({}) at clock.core_mhz ({} MHz): partition resume offsets of up to {} ps do not fit in half "
        "a {:.1f} ps cycle; use fewer partitions or a slower clock",
        c.partitions.count, c.clock.core_mhz, c.partitions.count, 1e6 / c.clock.core_mhz));
  // The approximate engine visits fragments in submission order and applies
  // no insert out of that order (DESIGN.md): it refuses what it cannot model.
  if (c.sim.engine == SimEngine::Approximate && c.lock.mode != LockMode::Ordered)
    errs.push_back(approximateLockModeProblem(c.lock.mode));
  // Single-field limits hold by construction via set(); recheck in case the
  // struct was edited directly (a programmatic caller).
  for (const auto& p : registry()) {
    const Value v = p.get(c);
    try {
      checked(p, v, formatValue(v));
    } catch (const std::invalid_argument& e) {
      errs.push_back(e.what());
    }
  }
  // One problem is one line; several are listed one per line.
  if (errs.size() == 1) throw std::invalid_argument(fmt::format("invalid configuration (preset {}): {}", c.preset, errs[0]));
  if (!errs.empty())
    throw std::invalid_argument(fmt::format("invalid configuration (preset {}):\n  {}", c.preset,
                                            fmt::join(errs, "\n  ")));
}

nlohmann::json ConfigTree::toJson() const {
  nlohmann::json j = nlohmann::json::object();
  j["preset"] = cfg_.preset;
  for (const auto& p : registry()) {
    std::string pointer = "/" + p.path;  // "/lock/granularity": nested objects
    std::replace(pointer.begin(), pointer.end(), '.', '/');
    j[nlohmann::json::json_pointer(pointer)] = jsonValue(p.get(cfg_));
  }
  return j;
}

std::vector<PropertyInfo> ConfigTree::properties() const {
  std::vector<PropertyInfo> out;
  out.reserve(registry().size());
  for (const auto& p : registry()) {
    out.push_back(PropertyInfo{.path = p.path,
                               .type = p.type,
                               .unit = p.unit,
                               .description = p.description,
                               .value = formatValue(p.get(cfg_)),
                               .default_value = formatValue(p.get(defaults_)),
                               .allowed = p.allowed(),
                               .enum_values = p.names,
                               .inferred = presetValueInferred(cfg_.preset, p.path)});
  }
  return out;
}

std::string ConfigTree::describe() const {
  const auto props = properties();
  size_t wp = 8, wv = 5, wu = 4, wd = 7;
  for (const auto& i : props) {
    wp = std::max(wp, i.path.size());
    wv = std::max(wv, i.value.size());
    wu = std::max(wu, i.unit.size());
    if (i.value != i.default_value) wd = std::max(wd, i.default_value.size());
  }
  std::string out = fmt::format("effective configuration (preset {}; * = changed from the preset)\n", cfg_.preset);
  out += fmt::format("  {:<{}} {:<{}} {:<{}} {:<{}} {}\n", "property", wp, "value", wv, "unit", wu, "default", wd,
                     "description");
  for (const auto& i : props) {
    const bool changed = i.value != i.default_value;
    out += fmt::format("{} {:<{}} {:<{}} {:<{}} {:<{}} {}\n", changed ? '*' : ' ', i.path, wp, i.value, wv, i.unit,
                       wu, changed ? i.default_value : "", wd, i.description);
  }
  return out;
}

ConfigTree resolveTree(const std::string& preset, const std::string& config_file,
                       const std::vector<std::string>& sets) {
  std::string name = preset, preset_from_file;
  nlohmann::json file_json;
  if (!config_file.empty()) {
    file_json = readConfigFile(config_file);
    // A file naming its preset supplies it when --preset was not given.
    if (file_json.is_object() && file_json.contains("preset") && file_json["preset"].is_string())
      preset_from_file = file_json["preset"].get<std::string>();
  }
  const bool from_file = name.empty() && !preset_from_file.empty();
  if (from_file) name = preset_from_file;
  if (name.empty()) name = "iris-pro-5200";
  ConfigTree tree = [&] {
    try {
      return ConfigTree::forPreset(name);
    } catch (const std::invalid_argument& e) {
      if (!from_file) throw;
      throw std::invalid_argument(fmt::format("{}: key 'preset': {}", config_file, e.what()));
    }
  }();
  if (!config_file.empty()) tree.applyJson(file_json, config_file);
  for (const auto& s : sets) {
    const size_t eq = s.find('=');
    if (eq == std::string::npos || eq == 0)
      throw std::invalid_argument(
          fmt::format("--set '{}': expected path=value, e.g. --set lock.granularity=quad", s));
    try {
      tree.set(std::string_view(s).substr(0, eq), std::string_view(s).substr(eq + 1));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(fmt::format("--set '{}': {}", s, e.what()));
    }
  }
  tree.validate();
  return tree;
}

RopConfig resolveConfig(const std::string& preset, const std::string& config_file,
                        const std::vector<std::string>& sets) {
  return resolveTree(preset, config_file, sets).config();
}

std::string presetTableMarkdown() {
  std::vector<std::vector<PropertyInfo>> cols;
  const auto names = presetNames();
  for (const auto& n : names) cols.push_back(ConfigTree::forPreset(n).properties());
  std::string out = "| property | unit |";
  for (const auto& n : names) out += " " + n + " |";
  out += " allowed | description |\n| --- | --- |";
  for (size_t k = 0; k < names.size(); ++k) out += " --- |";
  out += " --- | --- |\n";
  for (size_t r = 0; r < cols[0].size(); ++r) {
    const PropertyInfo& i = cols[0][r];
    out += fmt::format("| `{}` | {} |", i.path, i.unit);
    for (const auto& c : cols) out += fmt::format(" {}{} |", c[r].value, c[r].inferred ? " (i)" : "");
    // A bare '|' ("pixel | quad") would split the Markdown cell.
    auto cell = [](const std::string& text) {
      std::string c;
      for (char ch : text) c += ch == '|' ? std::string("\\|") : std::string(1, ch);
      return c;
    };
    out += fmt::format(" {} | {} |\n", cell(i.allowed), cell(i.description));
  }
  return out;
}


}  // namespace oit::rop
