// Reports appear whole or not at all: write to a temporary file beside the
// target, flush, then rename over it (rename is atomic within a filesystem).
#pragma once

#include <string>
#include <string_view>

namespace oit::reports {

// Throws (a std::runtime_error naming the path) on any I/O failure; the target is
// untouched then and the temporary removed.
void writeFileAtomically(const std::string& path, std::string_view content);

}  // namespace oit::reports
