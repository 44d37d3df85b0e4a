#include "reports/JsonReport.hpp"

#include <cmath>
#include <stdexcept>

#include "reports/AtomicFile.hpp"

namespace oit::reports {

void requireFinite(const nlohmann::json& j, const std::string& where) {
  if (j.is_number_float()) {
    if (!std::isfinite(j.get<double>()))
      throw std::runtime_error("report value " + (where.empty() ? std::string("(root)") : where) +
                               " is not finite");
  } else if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it) requireFinite(it.value(), where + "." + it.key());
  } else if (j.is_array()) {
    for (size_t i = 0; i < j.size(); ++i) requireFinite(j[i], where + "[" + std::to_string(i) + "]");
  }
}

void writeJsonReport(const std::string& path, const nlohmann::json& j) {
  requireFinite(j);
  writeFileAtomically(path, j.dump(2) + "\n");
}

}  // namespace oit::reports
