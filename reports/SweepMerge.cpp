// Merging the points of a sweep into results.csv and results.json.
#include "reports/SweepMerge.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <fstream>
#include <set>

#include "reports/AtomicFile.hpp"
#include "reports/SweepPlan.hpp"
#include "reports/SweepRunner.hpp"

namespace oit::sweep {

namespace fs = std::filesystem;

namespace {

std::string csvField(const nlohmann::json& v) {
  std::string s = v.is_string() ? v.get<std::string>() : v.is_null() ? std::string() : v.dump();
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

}  // namespace

// The time series' samples (one per stats interval) are a trace, not a metric,
// and stay in the point's report.json; its period, timeseries.interval_cycles,
// is a column like every other field.
void flattenReport(const nlohmann::json& j, const std::string& prefix, nlohmann::json& out) {
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it) {
      const std::string key = prefix.empty() ? it.key() : prefix + "." + it.key();
      if (key == "timeseries.samples") continue;
      flattenReport(it.value(), key, out);
    }
  } else if (j.is_array()) {
    bool scalars = true;
    for (const auto& e : j) scalars = scalars && !e.is_structured();
    if (scalars) {
      out[prefix] = j.dump();
    } else {
      for (size_t i = 0; i < j.size(); ++i) flattenReport(j[i], prefix + "." + std::to_string(i), out);
    }
  } else {
    out[prefix] = j;
  }
}

MergeSummary mergeSweep(const fs::path& dir_in) {
  const fs::path dir = fs::absolute(dir_in);
  const Plan plan = readPlan(dir);
  std::vector<std::string> axis_names;
  for (const auto& p : plan.points)
    for (auto it = p.axes.begin(); it != p.axes.end(); ++it)
      if (std::find(axis_names.begin(), axis_names.end(), it.key()) == axis_names.end())
        axis_names.push_back(it.key());

  MergeSummary sum;
  ojson rows = ojson::array();
  std::set<std::string> metric_keys;
  for (const auto& p : plan.points) {
    const fs::path pd = dir / "points" / p.id;
    ojson row;
    row["id"] = p.id;
    row["trace"] = p.trace;
    nlohmann::json status;
    if (fs::exists(pd / "status.json")) {
      try {
        std::ifstream s(pd / "status.json");
        status = nlohmann::json::parse(s);
      } catch (const nlohmann::json::exception&) {
        status = nlohmann::json::object();  // unreadable: the point did not finish cleanly
        status["exit_code"] = -1;
      }
    }
    std::string error;
    bool ran = true;
    nlohmann::json flat = nlohmann::json::object();
    const int exit_code = status.is_object() ? status.value("exit_code", 0) : 0;
    if (exit_code != 0) {  // failed, whatever else the folder holds
      error = tailOf(pd / "stderr.txt");
      if (error.empty()) error = fmt::format("exit code {}", exit_code);
    } else if (fs::exists(pd / "report.json")) {
      try {
        std::ifstream r(pd / "report.json");
        flattenReport(nlohmann::json::parse(r), "", flat);
      } catch (const std::exception& e) {
        error = std::string("unreadable report.json: ") + e.what();
      }
    } else if (status.is_null() && !fs::exists(pd / "stderr.txt")) {
      ran = false;  // e.g. after --emit slurm, before its task ran: not a failure
    } else {
      error = tailOf(pd / "stderr.txt");
      if (error.empty())
        error = status.is_object()
                    ? fmt::format("exit code {} and no report.json", status.value("exit_code", -1))
                    : "no status.json and no report.json: the point started but did not finish (interrupted?)";
    }
    if (!error.empty()) {
      ++sum.failed;
      sum.failures.emplace_back(p.id, error);
      flat = nlohmann::json::object();
    }
    if (!ran) {
      ++sum.not_run;
      sum.not_run_ids.push_back(p.id);
    }
    row["status"] = !ran ? "not run" : error.empty() ? "ok" : "failed";
    row["error"] = error;
    row["wall_seconds"] = status.contains("wall_seconds") ? status["wall_seconds"] : nlohmann::json();
    row["axes"] = p.axes;
    row["command"] = p.args;
    for (auto it = flat.begin(); it != flat.end(); ++it) metric_keys.insert(it.key());
    row["metrics"] = flat;
    rows.push_back(row);
  }

  // CSV: fixed columns, axes, then every metric key in sorted order. Fields are
  // appended one by one (GCC 12's -Wrestrict misfires on "," + string).
  std::string csv = "id,trace,status,error,wall_seconds";
  auto field = [&csv](const nlohmann::json& v) {
    csv += ',';
    csv += csvField(v);
  };
  for (const auto& a : axis_names) field("axis." + a);
  for (const auto& k : metric_keys) field(k);
  csv += '\n';
  for (const auto& r : rows) {
    csv += csvField(r["id"]);
    for (const char* k : {"trace", "status", "error", "wall_seconds"}) field(r[k]);
    for (const auto& a : axis_names) field(r["axes"].contains(a) ? nlohmann::json(r["axes"][a]) : nlohmann::json());
    for (const auto& k : metric_keys) field(r["metrics"].contains(k) ? nlohmann::json(r["metrics"][k]) : nlohmann::json());
    csv += '\n';
  }
  sum.points = rows.size();
  sum.ok = sum.points - sum.failed - sum.not_run;
  sum.csv = dir / "results.csv";
  sum.json = dir / "results.json";
  reports::writeFileAtomically(sum.csv.string(), csv);
  ojson res;
  res["schema"] = "oitsim-sweep/1";
  res["spec"] = plan.spec;
  res["axes"] = axis_names;
  res["summary"] = {{"points", sum.points}, {"ok", sum.ok}, {"failed", sum.failed}, {"not_run", sum.not_run}};
  res["points"] = rows;
  ojson dups = ojson::array();
  for (const auto& d : plan.duplicates) dups.push_back({{"labels", d.labels}, {"same_as", d.same_as}, {"ignored", d.ignored}});
  res["duplicates"] = dups;
  reports::writeFileAtomically(sum.json.string(), res.dump(1) + "\n");
  return sum;
}

std::string mergeSummaryText(const MergeSummary& s, size_t list) {
  std::string text = fmt::format("sweep: {} points, {} ok, {} failed{}; results {} and {}\n", s.points, s.ok, s.failed,
                                 s.not_run ? fmt::format(", {} not run", s.not_run) : std::string(), s.csv.string(),
                                 s.json.string());
  for (const auto& [id, error] : s.failures) text += fmt::format("  FAILED {}: {}\n", id, error);
  if (!s.not_run_ids.empty()) {
    std::string ids;
    for (size_t i = 0; i < s.not_run_ids.size() && i < list; ++i) ids += (i ? ", " : "") + s.not_run_ids[i];
    if (s.not_run_ids.size() > list) ids += fmt::format(" and {} more", s.not_run_ids.size() - list);
    text += fmt::format("  not run yet: {} (rerun `oitsim sweep` with the same spec and --out to run only these, or "
                        "submit the Slurm array)\n",
                        ids);
  }
  return text;
}

}  // namespace oit::sweep
