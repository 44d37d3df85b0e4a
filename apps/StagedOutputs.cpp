#include "apps/StagedOutputs.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <stdexcept>

namespace oit::cli {

namespace fs = std::filesystem;

std::string StagedOutputs::stage(const fs::path& final_path, const std::string& suffix) {
  const fs::path tmp =
      final_path.parent_path() / fmt::format(".{}.partial.{}{}", final_path.filename().string(), ::getpid(), suffix);
  staged_.push_back({TempFile(tmp.string()), final_path.string()});
  return staged_.back().first.path();
}

void StagedOutputs::commit() {
  std::vector<std::string> done;
  for (const auto& [tmp, path] : staged_) {
    std::error_code ec;
    fs::rename(tmp.path(), path, ec);
    if (ec) {
      const std::string why = ec.message();
      for (const std::string& d : done) fs::remove(d, ec);  // all or none
      throw std::runtime_error(fmt::format("{}: cannot rename {} to it: {}", path, tmp.path(), why));
    }
    done.push_back(path);
  }
  for (auto& staged : staged_) staged.first.keep();
}

size_t removeAbandonedOutputs(const fs::path& folder, const std::vector<std::string>& names) {
  return removeAbandoned(folder.string(), [&](std::string_view file) {
    for (const std::string& n : names)
      if (const int pid = pidAfterPrefix(file, "." + n + ".partial.")) return pid;
    return 0;
  });
}

}  // namespace oit::cli
