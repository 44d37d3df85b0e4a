// report.json writing shared by every command that writes one.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace oit::reports {

// Throws std::runtime_error naming the JSON path of the first NaN or Inf:
// no non-finite number ever reaches a report.
void requireFinite(const nlohmann::json& j, const std::string& where = "");

// requireFinite, then an atomic write (temporary file + rename), pretty-printed.
void writeJsonReport(const std::string& path, const nlohmann::json& j);

// Schema identifier written as "schema" in every report (see reports/REPORT.md).
inline constexpr const char* kReportSchema = "oitsim-report/1";

}  // namespace oit::reports
