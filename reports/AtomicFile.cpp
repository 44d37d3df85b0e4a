#include "reports/AtomicFile.hpp"

#include "traces/AtomicFile.hpp"

namespace oit::reports {

// Same mechanism as the trace writer's: temporary file beside the target,
// renamed over it on commit, removed if anything fails.
void writeFileAtomically(const std::string& path, std::string_view content) {
  detail::AtomicFile file(path, content.size() < (size_t{1} << 20) ? content.size() + 1 : size_t{1} << 20);
  file.append(content.data(), content.size());
  file.commit();
}

}  // namespace oit::reports
