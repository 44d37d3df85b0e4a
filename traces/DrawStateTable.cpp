#include "traces/DrawStateTable.hpp"

#include <charconv>
#include <cstring>

#include <fmt/format.h>

#include "traces/CsvTokens.hpp"
#include "traces/TraceFormat.hpp"

namespace oit::detail {

namespace fv = format_v1;

namespace {

uint64_t entryOffset(size_t n, size_t i) {
  return fv::drawStateTableOffset(n) + uint64_t{i} * fv::kDrawStateEntryBytes;
}

template <typename T>
T loadLe(const unsigned char* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

}  // namespace

std::optional<TableProblem> drawStateProblem(const DrawInfo& d, size_t i) {
  if (!d.state) return std::nullopt;
  const DrawState& s = *d.state;
  if (static_cast<uint8_t>(s.blend) > static_cast<uint8_t>(BlendMode::Other))
    return TableProblem{0, fmt::format("draw[{}].state.blend", i),
                        fmt::format("bad blend mode {}: expected 0..5 (off, over, premultiplied-over, additive, "
                                    "multiplicative, other)", static_cast<unsigned>(s.blend))};
  if (s.depth_write && !s.depth_test)
    return TableProblem{0, fmt::format("draw[{}].state.depth", i), "depth write without the depth test"};
  const DrawClass implied = s.blend == BlendMode::Off ? DrawClass::Opaque : DrawClass::Transparent;
  if (d.cls != implied)
    return TableProblem{0, fmt::format("draw[{}].class", i),
                        fmt::format("class {} but blend mode {}: expected {} (blending off is opaque, "
                                    "any blending transparent)", toString(d.cls), toString(s.blend),
                                    toString(implied))};
  return std::nullopt;
}

std::optional<TableProblem> readDrawStates(const unsigned char* table, std::vector<DrawInfo>& draws) {
  const size_t n = draws.size();
  for (size_t i = 0; i < n; ++i) {
    const unsigned char* e = table + i * fv::kDrawStateEntryBytes;
    const uint64_t at = entryOffset(n, i);
    DrawState s;
    s.blend = static_cast<BlendMode>(e[fv::kStateOffBlend]);
    const uint8_t depth = e[fv::kStateOffDepth];
    if (depth > 3)
      return TableProblem{at + fv::kStateOffDepth, fmt::format("draw[{}].state.depth", i),
                          fmt::format("bad depth flags 0x{:02X}: expected bit 0 (test) and bit 1 (write) only", depth)};
    s.depth_test = depth & 1;
    s.depth_write = depth & 2;
    s.depth_func = loadLe<uint16_t>(e + fv::kStateOffDepthFunc);
    uint16_t* enums[6] = {&s.blend_eq_rgb, &s.blend_src_rgb, &s.blend_dst_rgb,
                          &s.blend_eq_alpha, &s.blend_src_alpha, &s.blend_dst_alpha};
    for (size_t k = 0; k < 6; ++k) *enums[k] = loadLe<uint16_t>(e + fv::kStateOffBlendEnums + 2 * k);
    s.fragments = loadLe<uint64_t>(e + fv::kStateOffFragments);
    for (size_t k = 0; k < 8; ++k)
      if (e[fv::kStateOffReserved + k] != 0)
        return TableProblem{at + fv::kStateOffReserved + k, fmt::format("draw[{}].state.reserved", i),
                            fmt::format("reserved byte is 0x{:02X}, expected 0", e[fv::kStateOffReserved + k])};
    draws[i].state = s;
    if (auto p = drawStateProblem(draws[i], i)) {
      p->offset = p->field.ends_with(".class") ? fv::kFixedHeaderBytes + i * fv::kDrawEntryBytes + fv::kDrawOffClass
                                                : at + (p->field.ends_with(".blend") ? fv::kStateOffBlend
                                                                                     : fv::kStateOffDepth);
      return p;
    }
  }
  return std::nullopt;
}

std::optional<TableProblem> headerStatesProblem(const TraceHeader& h) {
  const bool v2 = h.version == fv::kVersion2;
  const size_t n = h.draws.size();
  for (size_t i = 0; i < n; ++i) {
    const DrawInfo& d = h.draws[i];
    if (v2 && !d.state)
      return TableProblem{entryOffset(n, i), fmt::format("draw[{}].state", i),
                          "version 2 needs a draw state for every draw"};
    if (!v2 && d.state)
      return TableProblem{fv::kOffVersion, "version",
                          fmt::format("draw {} has a draw state: only version 2 keeps them", d.id)};
    if (auto p = drawStateProblem(d, i)) {
      p->offset = entryOffset(n, i);
      return p;
    }
  }
  return std::nullopt;
}

void writeDrawStates(unsigned char* table, const std::vector<DrawInfo>& draws) {
  for (size_t i = 0; i < draws.size(); ++i) {
    unsigned char* e = table + i * fv::kDrawStateEntryBytes;
    const DrawState& s = *draws[i].state;
    e[fv::kStateOffBlend] = static_cast<uint8_t>(s.blend);
    e[fv::kStateOffDepth] = static_cast<uint8_t>((s.depth_test ? 1 : 0) | (s.depth_write ? 2 : 0));
    std::memcpy(e + fv::kStateOffDepthFunc, &s.depth_func, 2);
    const uint16_t enums[6] = {s.blend_eq_rgb, s.blend_src_rgb, s.blend_dst_rgb,
                               s.blend_eq_alpha, s.blend_src_alpha, s.blend_dst_alpha};
    std::memcpy(e + fv::kStateOffBlendEnums, enums, sizeof enums);
    std::memcpy(e + fv::kStateOffFragments, &s.fragments, 8);
    std::memset(e + fv::kStateOffReserved, 0, 8);
  }
}

std::string drawStateCsv(const DrawInfo& d) {
  const DrawState& s = *d.state;
  return fmt::format("{} {} {} 0x{:04X} 0x{:04X} 0x{:04X} 0x{:04X} 0x{:04X} 0x{:04X} 0x{:04X} {}", d.id,
                     toString(s.blend), s.depth_write ? "test+write" : s.depth_test ? "test" : "off", s.depth_func,
                     s.blend_eq_rgb, s.blend_src_rgb, s.blend_dst_rgb, s.blend_eq_alpha, s.blend_src_alpha,
                     s.blend_dst_alpha, s.fragments);
}

std::optional<std::string> parseDrawStateCsv(std::string_view fields, DrawState& out) {
  std::vector<std::string_view> t;
  CsvTokens tokens(fields, 0);
  for (std::string_view v = tokens.next(); !v.empty(); v = tokens.next()) t.push_back(v);
  if (t.size() != 10)
    return fmt::format("expected 10 fields after the draw id (blend, depth, depth func, 6 blend enums, "
                       "fragments), found {}", t.size());
  DrawState s;
  bool known = false;
  for (uint8_t m = 0; m <= static_cast<uint8_t>(BlendMode::Other); ++m)
    if (t[0] == toString(static_cast<BlendMode>(m))) s.blend = static_cast<BlendMode>(m), known = true;
  if (!known)
    return fmt::format("bad blend mode '{}': expected off, over, premultiplied-over, additive, multiplicative or other",
                       t[0]);
  if (t[1] == "test+write")
    s.depth_test = s.depth_write = true;
  else if (t[1] == "test")
    s.depth_test = true;
  else if (t[1] != "off")
    return fmt::format("bad depth state '{}': expected off, test or test+write", t[1]);
  uint16_t* enums[7] = {&s.depth_func, &s.blend_eq_rgb, &s.blend_src_rgb, &s.blend_dst_rgb,
                        &s.blend_eq_alpha, &s.blend_src_alpha, &s.blend_dst_alpha};
  for (size_t k = 0; k < 7; ++k) {
    const std::string_view v = t[2 + k];
    const bool hex = v.size() > 2 && v[0] == '0' && (v[1] == 'x' || v[1] == 'X');
    const auto [p, ec] = std::from_chars(v.data() + 2, v.data() + v.size(), *enums[k], 16);
    if (!hex || ec != std::errc() || p != v.data() + v.size())
      return fmt::format("'{}' is not a GL enum in hexadecimal (0x0000..0xFFFF)", v);
  }
  const std::string_view f = t[9];
  const auto [p, ec] = std::from_chars(f.data(), f.data() + f.size(), s.fragments);
  if (ec != std::errc() || p != f.data() + f.size()) return fmt::format("fragments '{}' is not a u64", f);
  out = s;
  return std::nullopt;
}

}  // namespace oit::detail
