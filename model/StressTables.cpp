// The stress suite's tables (model/StressSuite.hpp): the rows as CSV and as the
// Markdown table of reports/stress/, each file written whole or not at all.
#include "model/StressSuite.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace oit::model::stress {

namespace {

std::string num(double v) {
  if (std::isnan(v)) return "nan";
  if (v == 0) return "0";
  return fmt::format("{:.3g}", v);
}
std::string kText(unsigned k) { return k ? std::to_string(k) : "-"; }
std::string mdCell(std::string s) {
  std::replace(s.begin(), s.end(), '|', '/');
  std::replace(s.begin(), s.end(), '\n', ' ');
  return s;
}
std::string csvCell(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char ch : s) q += ch == '"' ? std::string("\"\"") : std::string(1, ch);
  return q + "\"";
}
std::string algoLabel(const StressRow& r) { return r.variant.empty() ? r.algorithm : r.algorithm + " " + r.variant; }

void writeAtomically(const std::filesystem::path& path, const std::string& content) {
  const std::filesystem::path tmp = path.string() + fmt::format(".tmp.{}", ::getpid());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error(fmt::format("{}: cannot create temporary file {}", path.string(), tmp.string()));
    out.write(content.data(), std::streamsize(content.size()));
    out.flush();
    if (!out) {
      out.close();
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      throw std::runtime_error(fmt::format("{}: write failed", path.string()));
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::error_code ignore;
    std::filesystem::remove(tmp, ignore);
    throw std::runtime_error(fmt::format("{}: cannot rename {} over it: {}", path.string(), tmp.string(), ec.message()));
  }
}

}  // namespace

std::string toCsv(const std::vector<StressRow>& rows) {
  std::string s =
      "case,algorithm,variant,format,k,status,fragments,max_abs_error,rmse,min,max,non_finite,out_of_range,"
      "balanced,stored,merged,discarded,culled,bytes_per_pixel,note\n";
  auto g = [](double v) { return std::isnan(v) ? std::string("nan") : fmt::format("{:.9g}", v); };
  for (const StressRow& r : rows) {
    const bool ran = r.status == RowStatus::Ok || r.status == RowStatus::Violation;
    s += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", csvCell(r.case_name),
                     csvCell(r.algorithm), csvCell(r.variant), r.format, kText(r.k), toString(r.status), r.fragments,
                     ran ? g(r.max_abs_error) : "", ran ? g(r.rmse) : "", ran ? g(r.min_value) : "",
                     ran ? g(r.max_value) : "", r.non_finite, r.out_of_range, r.balanced ? 1 : 0, r.stored, r.merged,
                     r.discarded, r.culled, r.bytes_per_pixel, csvCell(r.note));
  }
  return s;
}

std::string toMarkdown(const std::vector<StressRow>& rows, const std::string& command) {
  size_t ran = 0, na = 0, bad = 0;
  std::vector<std::string> caseOrder, algoOrder;
  auto addUnique = [](std::vector<std::string>& v, const std::string& s) {
    if (std::find(v.begin(), v.end(), s) == v.end()) v.push_back(s);
  };
  for (const StressRow& r : rows) {
    addUnique(caseOrder, r.case_name);
    addUnique(algoOrder, r.algorithm);
    if (r.status == RowStatus::NotApplicable) ++na;
    else ++ran;
    if (r.violation()) ++bad;
  }
  std::string s = "# oitsim numerical stress table\n\n";
  s += fmt::format("Produced by `{}`. Column meanings: reports/stress/README.md.\n\n", command);
  s += fmt::format("{} cases x {} algorithms: {} configurations run, {} n/a (format or k rejected by the algorithm), "
                   "**{} violations** (NaN/Inf, output outside [0,1], unbalanced outcome counts, or a render error).\n\n",
                   caseOrder.size(), algoOrder.size(), ran, na, bad);

  s += "## Cases\n\n| case | fragments | what it stresses |\n|---|---:|---|\n";
  for (const std::string& cn : caseOrder) {
    const StressCase c = makeCase(cn);
    s += fmt::format("| {} | {} | {} |\n", cn, c.fragments.size(), mdCell(c.what));
  }

  s += "\n## Violations\n\n";
  if (!bad) {
    s += "None.\n";
  } else {
    s += "| case | algorithm | format | k | status | min | max | finding |\n|---|---|---|---|---|---:|---:|---|\n";
    for (const StressRow& r : rows)
      if (r.violation())
        s += fmt::format("| {} | {} | {} | {} | {} | {} | {} | {} |\n", r.case_name, algoLabel(r), r.format, kText(r.k),
                         toString(r.status), num(r.min_value), num(r.max_value), mdCell(r.note));
  }

  // Worst max-abs error per case and algorithm over formats, k and variants.
  s += "\n## Worst max abs error vs abuffer (over formats, k and variants; ! = violation in that cell)\n\n| case |";
  for (const std::string& a : algoOrder) s += " " + a + " |";
  s += "\n|---|";
  for (size_t i = 0; i < algoOrder.size(); ++i) s += "---:|";
  s += "\n";
  for (const std::string& cn : caseOrder) {
    s += "| " + cn + " |";
    for (const std::string& a : algoOrder) {
      double worst = -1;
      bool v = false, nan = false;
      for (const StressRow& r : rows)
        if (r.case_name == cn && r.algorithm == a && r.status != RowStatus::NotApplicable) {
          v |= r.violation();
          if (std::isnan(r.max_abs_error)) nan = true;
          else if (r.status != RowStatus::Error) worst = std::max(worst, r.max_abs_error);
        }
      // Appended piece by piece: GCC 12's -Wrestrict misfires on " " + string.
      s += ' ';
      s += nan ? std::string("nan") : worst < 0 ? std::string("n/a") : num(worst);
      s += v ? " ! |" : " |";
    }
    s += "\n";
  }

  s += "\n## All configurations\n\n"
       "| case | algorithm | format | k | status | max abs err | RMSE | min | max | stored | merged | discarded | "
       "culled | B/px | note |\n|---|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n";
  for (const StressRow& r : rows) {
    if (r.status == RowStatus::NotApplicable) {
      s += fmt::format("| {} | {} | {} | {} | n/a | | | | | | | | | | {} |\n", r.case_name, algoLabel(r), r.format,
                       kText(r.k), mdCell(r.note));
      continue;
    }
    s += fmt::format("| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n", r.case_name,
                     algoLabel(r), r.format, kText(r.k), toString(r.status), num(r.max_abs_error), num(r.rmse),
                     num(r.min_value), num(r.max_value), r.stored, r.merged, r.discarded, r.culled, r.bytes_per_pixel,
                     mdCell(r.note));
  }
  return s;
}

void writeStressTables(const std::vector<StressRow>& rows, const std::string& dir, const std::string& command) {
  const std::filesystem::path d(dir);
  std::error_code ec;
  std::filesystem::create_directories(d, ec);
  if (ec) throw std::runtime_error(fmt::format("{}: cannot create directory: {}", dir, ec.message()));
  writeAtomically(d / "stress-table.md", toMarkdown(rows, command));
  writeAtomically(d / "stress-table.csv", toCsv(rows));
}

}  // namespace oit::model::stress
