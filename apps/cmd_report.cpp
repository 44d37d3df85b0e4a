// oitsim report DIR: one self-contained HTML page (DIR/report.html) of a sweep:
// the table of points, Pareto plots, image strips, stall breakdowns, depth
// complexity, simulator speed modes. The tables are rebuilt from the plan and
// the points first (so points run by a Slurm array merge the same way), then
// reports/make_report.py (Debian's python3-matplotlib) draws the page.
#include <fmt/core.h>

#include <cstdlib>
#include <filesystem>

#include "apps/Commands.hpp"

namespace oit::cli {

// Defined in cmd_sweep.cpp.
int collectSweep(const std::string& dir, bool quiet);
std::string selfExecutable();

namespace {

namespace fs = std::filesystem;

struct ReportArgs {
  std::string dir, out;
  bool quiet = false;
};

// Debian's python3 (where python3-matplotlib lives) ahead of any python3 on PATH
// (pyenv shims shadow it); OITSIM_PYTHON overrides.
std::string pythonExe() {
  if (const char* p = std::getenv("OITSIM_PYTHON"); p && *p) return p;
  return fs::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
}

std::string quote(const std::string& a) {
  std::string q = "'";
  for (char c : a) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

void runReport(const ReportArgs& a) {
  const fs::path dir = fs::absolute(a.dir);
  if (!fs::is_directory(dir)) throw std::invalid_argument("report: " + dir.string() + " is not a folder");
  if (fs::exists(dir / "plan.json")) {
    collectSweep(dir.string(), true);  // failed points are listed in the page, not an error here
  } else if (!fs::exists(dir / "results.json")) {
    throw std::invalid_argument("report: " + dir.string() + " has neither plan.json nor results.json (run `oitsim sweep` first)");
  }
  const std::string script = std::string(OITSIM_SOURCE_DIR) + "/reports/make_report.py";
  if (!fs::exists(script)) throw std::runtime_error("report: the report generator " + script + " is missing");
  if (std::system((quote(pythonExe()) + " -c 'import matplotlib, numpy' >/dev/null 2>&1").c_str()) != 0)
    throw std::runtime_error(
        "report: needs " + pythonExe() + " with matplotlib and numpy (Debian: apt-get install python3-matplotlib; "
        "scripts/setup.sh installs it)");
  const std::string out = a.out.empty() ? (dir / "report.html").string() : fs::absolute(a.out).string();
  const std::string cmd = quote(pythonExe()) + " " + quote(script) + " " + quote(dir.string()) + " --out " + quote(out) +
                          " --oitsim " + quote(selfExecutable()) + (a.quiet ? " --quiet" : "");
  const int rc = std::system(cmd.c_str());
  if (rc != 0) throw std::runtime_error(fmt::format("report: {} failed (exit status {})", script, rc));
}

}  // namespace

void addReportCommand(CLI::App& app) {
  auto a = std::make_shared<ReportArgs>();
  CLI::App* cmd = app.add_subcommand("report", "Make DIR/report.html (self-contained) from a sweep folder");
  cmd->add_option("dir", a->dir, "Folder written by `oitsim sweep`")->required();
  cmd->add_option("--out,-o", a->out, "HTML file to write (default DIR/report.html)");
  cmd->add_flag("--quiet,-q", a->quiet, "No summary");
  cmd->callback([a] { runReport(*a); });
}

}  // namespace oit::cli
