// The output files of `oitsim run`, staged under hidden temporary names
// (".<name>.partial.<pid>") and renamed together at the end: a run that fails
// or is interrupted (SIGINT, SIGTERM, SIGHUP) leaves none of them. A run
// killed outright (SIGKILL: no handler runs) can leave its staged files; the
// next run into the same folder removes them (removeAbandonedOutputs).
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "traces/TempFiles.hpp"

namespace oit::cli {

class StagedOutputs {
 public:
  // The temporary path to write `final_path` to: the same folder,
  // ".<name>.partial.<pid><suffix>" (suffix: what a writer insists on, e.g.
  // SystemC's ".vcd").
  std::string stage(const std::filesystem::path& final_path, const std::string& suffix = {});
  // Renames every staged file to its final path, all or none.
  void commit();

 private:
  std::vector<std::pair<TempFile, std::string>> staged_;  // temporary, final path
};

// Removes from `folder` the staged files (".<name>.partial.<pid>...") of the
// given output names whose run is gone; returns how many.
size_t removeAbandonedOutputs(const std::filesystem::path& folder, const std::vector<std::string>& names);

}  // namespace oit::cli
