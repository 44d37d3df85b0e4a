#include "traces/Fragment.hpp"

namespace oit {

const char* toString(DrawClass c) {
  switch (c) {
    case DrawClass::Opaque: return "opaque";
    case DrawClass::Transparent: return "transparent";
  }
  return "invalid";
}

const char* toString(BlendMode m) {
  switch (m) {
    case BlendMode::Off: return "off";
    case BlendMode::Over: return "over";
    case BlendMode::PremultipliedOver: return "premultiplied-over";
    case BlendMode::Additive: return "additive";
    case BlendMode::Multiplicative: return "multiplicative";
    case BlendMode::Other: return "other";
  }
  return "invalid";
}

const char* toString(ColourEncoding e) {
  switch (e) {
    case ColourEncoding::Fp32: return "fp32";
    case ColourEncoding::Unorm8: return "unorm8";
  }
  return "invalid";
}

}  // namespace oit
