#include "traces/TraceRules.hpp"

#include <fmt/format.h>

#include <cstddef>
#include <cstring>
#include <unordered_map>

#include "traces/DrawStateTable.hpp"
#include "traces/TraceIO.hpp"

namespace oit::detail {

namespace fv = format_v1;

namespace {

// Largest draw id served by the dense table (1 MiB of bytes at most).
constexpr uint32_t kDenseIdLimit = 1u << 20;

constexpr std::array<float, 256> makeUnorm8Table() {
  std::array<float, 256> t{};
  for (int i = 0; i < 256; ++i) t[static_cast<size_t>(i)] = static_cast<float>(i) / 255.0f;
  return t;
}

// NaN fails both comparisons, so it is reported as outside.
inline unsigned outsideUnit(float v) { return !(v >= 0.0f) | !(v <= 1.0f); }

#if defined(__GNUC__) && !defined(__clang__)
// GCC vector extensions (SSE2 on x86-64, NEON on arm64): one record is two
// 16-byte vectors, [xy z r g] and [b a prim draw]. Per chunk we AND the
// "in [0,1]" masks and take the max of x and y, then test once; this runs
// about 3x faster than per-field scalar compares.
typedef float V4f __attribute__((vector_size(16)));
typedef int32_t V4i __attribute__((vector_size(16)));
typedef int16_t V8s __attribute__((vector_size(16)));

template <class DrawOk>
bool chunkValid(const Fragment* f, size_t n, uint32_t w, uint32_t h, DrawOk& draw_ok) {
  const V4f zero = {0, 0, 0, 0}, one = {1, 1, 1, 1};
  V4i ok_lo = {-1, -1, -1, -1}, ok_hi = {-1, -1, -1, -1};
  // x, y are u16: flipping the top bit makes a signed max order them unsigned.
  const V8s flip = {INT16_MIN, INT16_MIN, 0, 0, 0, 0, 0, 0};
  V8s max_xy = {INT16_MIN, INT16_MIN, 0, 0, 0, 0, 0, 0};
  unsigned draw_bad = 0;
  for (size_t i = 0; i < n; ++i) {
    V4f lo, hi;
    std::memcpy(&lo, reinterpret_cast<const char*>(f + i), 16);
    std::memcpy(&hi, reinterpret_cast<const char*>(f + i) + 16, 16);
    ok_lo &= (lo >= zero) & (lo <= one);
    ok_hi &= (hi >= zero) & (hi <= one);
    const V8s xy = reinterpret_cast<V8s>(lo) ^ flip;
    max_xy = max_xy > xy ? max_xy : xy;
    draw_bad |= !draw_ok(f[i].draw);
  }
  // Lanes that are not colour or depth (xy, prim, draw) are ignored.
  const bool unit_ok = (ok_lo[1] & ok_lo[2] & ok_lo[3] & ok_hi[0] & ok_hi[1]) == -1;
  const auto max_x = static_cast<uint16_t>(max_xy[0] ^ INT16_MIN);
  const auto max_y = static_cast<uint16_t>(max_xy[1] ^ INT16_MIN);
  return unit_ok && !draw_bad && (n == 0 || (max_x < w && max_y < h));
}
#else
template <class DrawOk>
bool chunkValid(const Fragment* f, size_t n, uint32_t w, uint32_t h, DrawOk& draw_ok) {
  unsigned bad = 0;
  for (size_t i = 0; i < n; ++i) {
    const Fragment& r = f[i];
    bad |= (r.x >= w) | (r.y >= h) | outsideUnit(r.z) | outsideUnit(r.r) | outsideUnit(r.g) |
           outsideUnit(r.b) | outsideUnit(r.a) | !draw_ok(r.draw);
  }
  return bad == 0;
}
#endif

// A fast yes/no per chunk, then a precise rescan of a failing chunk only: the
// common case (valid data) stays a tight loop.
template <class DrawOk>
size_t scan(const Fragment* f, size_t n, const RecordRules& rules, DrawOk& draw_ok) {
  constexpr size_t kChunk = 512;
  for (size_t base = 0; base < n; base += kChunk) {
    const size_t end = std::min(n, base + kChunk);
    if (!chunkValid(f + base, end - base, rules.width, rules.height, draw_ok))
      for (size_t i = base; i < end; ++i)
        if (checkRecord(f[i], rules)) return i;
  }
  return n;
}

std::string fmtFloat(float v) {
  if (std::isnan(v)) return "NaN";
  if (std::isinf(v)) return v > 0 ? "+Inf" : "-Inf";
  return fmt::format("{}", v);
}

}  // namespace

const std::array<float, 256> kUnorm8ToFloat = makeUnorm8Table();

DrawSet::DrawSet(const std::vector<DrawInfo>& all) {
  // Records may name only draws whose fragments are recorded (format v2 keeps those
  // of blend modes the model does not blend out of the records).
  std::vector<uint32_t> ids;
  ids.reserve(all.size());
  for (const DrawInfo& d : all) (d.state && !d.state->recorded() ? unrecorded_ : ids).push_back(d.id);
  std::sort(unrecorded_.begin(), unrecorded_.end());
  const uint32_t max_id = ids.empty() ? 0 : *std::max_element(ids.begin(), ids.end());
  dense_ = max_id < kDenseIdLimit;
  if (dense_) {
    limit_ = ids.empty() ? 0 : max_id + 1;
    known_.assign(static_cast<size_t>(limit_) + 1, 0);
    for (const uint32_t id : ids) known_[id] = 1;
  } else {
    sorted_ = std::move(ids);
    std::sort(sorted_.begin(), sorted_.end());
  }
}

namespace {

// Calls body(draw_ok) with the fastest membership test for the set.
template <class Body>
size_t withDrawTest(const DrawSet& ds, Body body) {
  if (ds.dense()) {
    const uint8_t* known = ds.known();
    const uint32_t limit = ds.limit();
    auto ok = [known, limit](uint32_t id) { return known[std::min(id, limit)] != 0; };
    return body(ok);
  }
  // Sparse ids: remember the last id found, since fragments come in runs of one draw.
  uint32_t last = 0;
  bool have_last = false;
  auto ok = [&](uint32_t id) {
    if (have_last && id == last) return true;
    if (!ds.contains(id)) return false;
    last = id;
    have_last = true;
    return true;
  };
  return body(ok);
}

// Decodes unorm8 records and checks them in the same pass (colours decoded
// from bytes are always in [0,1]; x, y, z and draw are checked on the raw
// record), so the decoded data is not read a second time.
template <class DrawOk>
size_t decodeScan(const unsigned char* src, Fragment* dst, size_t n, const RecordRules& rules,
                  DrawOk& draw_ok) {
  constexpr size_t kChunk = 512;
  const float* lut = kUnorm8ToFloat.data();
  const uint32_t w = rules.width, h = rules.height;
  for (size_t base = 0; base < n; base += kChunk) {
    const size_t end = std::min(n, base + kChunk);
    unsigned bad = 0;
    for (size_t i = base; i < end; ++i) {
      const unsigned char* p = src + i * format_v1::kUnorm8RecordBytes;
      auto* out = reinterpret_cast<unsigned char*>(dst + i);
      uint16_t x, y;
      float z;
      uint32_t draw;
      std::memcpy(&x, p, 2);
      std::memcpy(&y, p + 2, 2);
      std::memcpy(&z, p + 4, 4);
      std::memcpy(&draw, p + 16, 4);
      std::memcpy(out, p, 8);  // x, y, z: same layout as fp32
      const float colour[4] = {lut[p[8]], lut[p[9]], lut[p[10]], lut[p[11]]};
      std::memcpy(out + 8, colour, 16);
      std::memcpy(out + 24, p + 12, 8);  // prim, draw
      bad |= (x >= w) | (y >= h) | outsideUnit(z) | !draw_ok(draw);
    }
    if (bad)
      for (size_t i = base; i < end; ++i)
        if (checkRecord(dst[i], rules)) return i;
  }
  return n;
}

}  // namespace

size_t firstInvalid(std::span<const Fragment> fs, const RecordRules& rules) {
  return withDrawTest(rules.draws, [&](auto& ok) { return scan(fs.data(), fs.size(), rules, ok); });
}

size_t decodeUnorm8(const unsigned char* src, Fragment* dst, size_t n, const RecordRules& rules) {
  static_assert(offsetof(Fragment, z) == 4 && offsetof(Fragment, r) == 8 &&
                offsetof(Fragment, prim) == 24 && offsetof(Fragment, draw) == 28);
  return withDrawTest(rules.draws, [&](auto& ok) { return decodeScan(src, dst, n, rules, ok); });
}

std::string coordMessage(fv::Field f, uint64_t value, uint32_t limit) {
  const char* name = fv::fieldName(f);
  return fmt::format("{} {} outside the frame, expected 0 <= {} < {} (the {})", name, value, name,
                     limit, f == fv::Field::X ? "width" : "height");
}

std::optional<std::string> unitMessage(fv::Field f, float v) {
  if (v >= 0.0f && v <= 1.0f) return std::nullopt;
  const std::string what =
      f == fv::Field::Z ? std::string("depth") : fmt::format("colour {}", fv::fieldName(f));
  if (!std::isfinite(v))
    return fmt::format("{} is {}, expected a finite value in [0,1]", what, fmtFloat(v));
  return fmt::format("{} {} outside [0,1]", what, fmtFloat(v));
}

std::optional<Violation> checkRecord(const Fragment& f, const RecordRules& rules) {
  if (f.x >= rules.width) return Violation{fv::Field::X, coordMessage(fv::Field::X, f.x, rules.width)};
  if (f.y >= rules.height)
    return Violation{fv::Field::Y, coordMessage(fv::Field::Y, f.y, rules.height)};
  const std::pair<fv::Field, float> unit[] = {{fv::Field::Z, f.z}, {fv::Field::R, f.r},
                                              {fv::Field::G, f.g}, {fv::Field::B, f.b},
                                              {fv::Field::A, f.a}};
  for (const auto& [field, v] : unit)
    if (auto msg = unitMessage(field, v)) return Violation{field, *msg};
  if (!rules.draws.contains(f.draw))
    return Violation{fv::Field::Draw,
                     rules.draws.unrecorded(f.draw)
                         ? fmt::format("draw {} is not modelled (its blend mode is not off, over or "
                                       "premultiplied over): version 2 keeps its fragments out of the records",
                                       f.draw)
                         : fmt::format("unknown draw id {}: not in the header's draw table", f.draw)};
  return std::nullopt;
}

std::optional<std::string> drawNameProblem(const std::string& name) {
  if (name.size() > fv::kMaxDrawNameBytes)
    return fmt::format("name is {} bytes long, at most {} allowed", name.size(),
                       fv::kMaxDrawNameBytes);
  for (size_t i = 0; i < name.size(); ++i) {
    const auto c = static_cast<unsigned char>(name[i]);
    if (c < 0x20 || c == 0x7F)
      return fmt::format("name contains control byte 0x{:02X} at index {}", c, i);
  }
  if (auto bad = invalidUtf8At(name))
    return fmt::format("name is not valid UTF-8: byte 0x{:02X} at index {} does not begin a well-formed "
                       "character",
                       static_cast<unsigned char>(name[*bad]), *bad);
  return std::nullopt;
}

size_t utf8CharBytes(std::string_view s, size_t i) {
  // Well-formed UTF-8 (Unicode table 3-7): no overlong forms, no surrogates,
  // nothing above U+10FFFF.
  const auto c = static_cast<unsigned char>(s[i]);
  size_t n = 0;
  unsigned char lo = 0x80, hi = 0xBF;  // range of the second byte
  if (c < 0x80) return 1;
  if (c >= 0xC2 && c <= 0xDF) {
    n = 1;
  } else if (c >= 0xE0 && c <= 0xEF) {
    n = 2;
    if (c == 0xE0) lo = 0xA0;
    if (c == 0xED) hi = 0x9F;
  } else if (c >= 0xF0 && c <= 0xF4) {
    n = 3;
    if (c == 0xF0) lo = 0x90;
    if (c == 0xF4) hi = 0x8F;
  } else {
    return 0;
  }
  if (i + n >= s.size()) return 0;  // cut short by the end
  for (size_t k = 1; k <= n; ++k) {
    const auto b = static_cast<unsigned char>(s[i + k]);
    if (k == 1 ? (b < lo || b > hi) : (b < 0x80 || b > 0xBF)) return 0;
  }
  return n + 1;
}

std::optional<size_t> invalidUtf8At(std::string_view s) {
  for (size_t i = 0; i < s.size();) {
    const size_t n = utf8CharBytes(s, i);
    if (n == 0) return i;
    i += n;
  }
  return std::nullopt;
}

std::optional<std::string> cameraProblem(float near_plane, float far_plane) {
  if (std::isfinite(near_plane) && std::isfinite(far_plane) && near_plane >= 0.0f &&
      far_plane > near_plane)
    return std::nullopt;
  return fmt::format("camera near {} far {}: expected finite planes with 0 <= near < far",
                     fmtFloat(near_plane), fmtFloat(far_plane));
}

const TraceHeader& checkHeaderForWrite(const std::string& file, const TraceHeader& h) {
  auto fail = [&](size_t offset, std::string field, const std::string& msg) {
    throw TraceError(file, offset, std::nullopt, std::move(field), msg);
  };
  if (h.version != fv::kVersion && h.version != fv::kVersion2)
    fail(fv::kOffVersion, "version",
         fmt::format("cannot write version {}: this library writes versions 1 and 2", h.version));
  const std::pair<const char*, uint32_t> sizes[] = {{"width", h.width}, {"height", h.height}};
  for (size_t i = 0; i < 2; ++i) {
    const auto [name, v] = sizes[i];
    const size_t off = i == 0 ? fv::kOffWidth : fv::kOffHeight;
    if (v == 0) fail(off, name, fmt::format("{} is 0, expected 1..{}", name, fv::kMaxFrameSize));
    if (v > fv::kMaxFrameSize)
      fail(off, name, fmt::format("{} {} exceeds {} (x and y are u16)", name, v, fv::kMaxFrameSize));
  }
  if (fv::recordBytes(h.encoding) == 0)
    fail(fv::kOffEncoding, "encoding",
         fmt::format("encoding {} is not 0 (fp32) or 1 (unorm8)", static_cast<uint32_t>(h.encoding)));
  if (h.camera)
    if (auto p = cameraProblem(h.camera->near_plane, h.camera->far_plane))
      fail(fv::kOffCameraNear, "camera", *p);
  if (h.draws.size() > fv::kMaxDraws)
    fail(fv::kOffDrawCount, "draw_count",
         fmt::format("{} draws, at most {} allowed", h.draws.size(), fv::kMaxDraws));
  std::unordered_map<uint32_t, size_t> seen;
  for (size_t i = 0; i < h.draws.size(); ++i) {
    const DrawInfo& d = h.draws[i];
    const size_t entry = fv::kFixedHeaderBytes + i * fv::kDrawEntryBytes;
    if (auto [it, fresh] = seen.emplace(d.id, i); !fresh)
      fail(entry + fv::kDrawOffId, fmt::format("draw[{}].id", i),
           fmt::format("duplicate draw id {} (also draw table entry {})", d.id, it->second));
    if (d.cls != DrawClass::Opaque && d.cls != DrawClass::Transparent)
      fail(entry + fv::kDrawOffClass, fmt::format("draw[{}].class", i),
           fmt::format("draw class {} is not 0 (opaque) or 1 (transparent)",
                       static_cast<uint32_t>(d.cls)));
    if (auto p = drawNameProblem(d.name)) fail(entry + fv::kDrawOffName, fmt::format("draw[{}].name", i), *p);
  }
  if (auto p = headerStatesProblem(h)) fail(p->offset, p->field, p->message);
  return h;
}

}  // namespace oit::detail
