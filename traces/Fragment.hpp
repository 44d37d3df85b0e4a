// Payload types of a fragment trace, shared by every folder (traces, model, oit_rop).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace oit {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "oitsim reads and writes little-endian traces by direct layout");

// One fragment as it leaves the pixel shader, in API submission order.
// The layout is exactly the on-disk fp32 record of trace format v1 (32 bytes),
// so an fp32 trace is read without copying.
struct Fragment {
  uint16_t x;        // GL window coordinates, origin bottom-left, pixel (x, y)
  uint16_t y;
  float z;           // window depth in [0,1], smaller is nearer
  float r, g, b, a;  // straight (not premultiplied) linear RGBA, each in [0,1]
  uint32_t prim;     // primitive id within its draw
  uint32_t draw;     // draw id, as listed in the header's draw table
};
static_assert(sizeof(Fragment) == 32, "Fragment must match the fp32 record layout");

enum class DrawClass : uint32_t { Opaque = 0, Transparent = 1 };

enum class ColourEncoding : uint32_t {
  Fp32 = 0,    // exact fp32 RGBA, 32-byte records
  Unorm8 = 1,  // compact unorm8 RGBA, 20-byte records
};

// How the application drew a captured draw (format v2, FORMAT.md section 3.1): the
// blend mode of colour attachment 0, the depth state and the GL blend enums.
enum class BlendMode : uint8_t {
  Off = 0,            // opaque
  Over = 1,           // SRC_ALPHA, ONE_MINUS_SRC_ALPHA
  PremultipliedOver = 2,  // ONE, ONE_MINUS_SRC_ALPHA
  Additive = 3,       // SRC_ALPHA or ONE, ONE
  Multiplicative = 4, // DST_COLOR, ZERO or ZERO, SRC_COLOR
  Other = 5,          // any other equation or factors
};
struct DrawState {
  BlendMode blend = BlendMode::Off;
  bool depth_test = false, depth_write = false;
  uint16_t depth_func = 0;  // GL enum (0x0201 GL_LESS ...), 0 without the test
  uint16_t blend_eq_rgb = 0, blend_src_rgb = 0, blend_dst_rgb = 0;  // GL enums, 0 with blending off
  uint16_t blend_eq_alpha = 0, blend_src_alpha = 0, blend_dst_alpha = 0;
  uint64_t fragments = 0;  // fragments the draw produced
  // The model blends only Off, Over and PremultipliedOver; the records of other
  // modes are kept out of the trace (the draw stays in the table, not modelled).
  bool recorded() const { return blend <= BlendMode::PremultipliedOver; }
  bool operator==(const DrawState&) const = default;
};

struct DrawInfo {
  uint32_t id = 0;
  DrawClass cls = DrawClass::Transparent;
  std::string name;
  std::optional<DrawState> state = std::nullopt;  // format v2 only (every draw has one there)
};

// Optional camera planes, for view-space weights (WBOIT eq. 7-9).
struct CameraPlanes {
  float near_plane = 0.0f;
  float far_plane = 0.0f;
};

struct TraceHeader {
  uint32_t version = 1;
  uint32_t width = 0;
  uint32_t height = 0;
  uint64_t fragment_count = 0;
  std::optional<CameraPlanes> camera;
  ColourEncoding encoding = ColourEncoding::Fp32;
  std::vector<DrawInfo> draws;

  // nullptr when the id is not in the draw table.
  const DrawInfo* findDraw(uint32_t id) const {
    for (const DrawInfo& d : draws)
      if (d.id == id) return &d;
    return nullptr;
  }
};

const char* toString(DrawClass c);
const char* toString(BlendMode m);
const char* toString(ColourEncoding e);

}  // namespace oit
