#include "oit_rop/Types.hpp"

namespace oit::rop {

const char* toString(Surface s) {
  switch (s) {
    case Surface::BlendArrays: return "blend_arrays";
    case Surface::Depth: return "depth";
    case Surface::Colour: return "colour";
    case Surface::Resolve: return "resolve";
  }
  return "unknown";
}

}  // namespace oit::rop
