// oitsim report DIR: one HTML page (DIR/report.html) of a sweep, per scene and
// hardware configuration: the bottleneck, cost against error, curves against k,
// memory, the image grid, depth complexity; speed modes; every point
// (reports/SWEEP.md, "The report"). The points are merged first
// (reports/SweepMerge.hpp: points run by a Slurm array merge the same way) and
// the merge printed, then reports/make_report.py (Debian's python3-matplotlib)
// draws the page.
#include <fmt/core.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <sys/wait.h>
#include <unistd.h>

#include "apps/Commands.hpp"
#include "reports/SweepMerge.hpp"

namespace oit::cli {

// Defined in cmd_sweep.cpp.
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

// The page is written to FILE.tmp and renamed: both need a writable folder.
// Checked before anything is written or the generator starts, so a bad --out
// is one clear error rather than a failure half way through the script.
void checkWritable(const fs::path& out, bool given) {
  const std::string what = given ? "report: --out " + out.string() : "report: " + out.string();
  std::error_code ec;
  if (fs::is_directory(out, ec)) throw std::invalid_argument(what + ": is a folder (expected an HTML file path)");
  const fs::path folder = out.parent_path();
  if (!fs::is_directory(folder, ec))
    throw std::invalid_argument(what + ": folder " + folder.string() + " does not exist");
  const fs::path probe = out.string() + ".tmp";
  const bool existed = fs::exists(probe, ec);
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  if (fd < 0) throw std::invalid_argument(what + ": cannot write " + probe.string() + ": " + std::strerror(errno));
  ::close(fd);
  if (!existed) fs::remove(probe, ec);
}

void runReport(const ReportArgs& a) {
  const fs::path dir = fs::absolute(a.dir);
  if (!fs::is_directory(dir)) throw std::invalid_argument("report: " + dir.string() + " is not a folder");
  const std::string out = a.out.empty() ? (dir / "report.html").string() : fs::absolute(a.out).string();
  checkWritable(out, !a.out.empty());
  if (fs::exists(dir / "plan.json")) {
    // Failed and missing points are listed here and in the page, not an error.
    const sweep::MergeSummary sum = sweep::mergeSweep(dir);
    if (!a.quiet) fmt::print("{}", sweep::mergeSummaryText(sum));
    std::fflush(stdout);
  } else if (!fs::exists(dir / "results.json")) {
    throw std::invalid_argument("report: " + dir.string() + " has neither plan.json nor results.json (run `oitsim sweep` first)");
  }
  const std::string script = std::string(OITSIM_SOURCE_DIR) + "/reports/make_report.py";
  if (!fs::exists(script)) throw std::runtime_error("report: the report generator " + script + " is missing");
  if (std::system((quote(pythonExe()) + " -c 'import matplotlib, numpy' >/dev/null 2>&1").c_str()) != 0)
    throw std::runtime_error(
        "report: needs " + pythonExe() + " with matplotlib and numpy (Debian: apt-get install python3-matplotlib; "
        "scripts/setup.sh installs it)");
  const std::string cmd = quote(pythonExe()) + " " + quote(script) + " " + quote(dir.string()) + " --out " + quote(out) +
                          " --oitsim " + quote(selfExecutable()) + (a.quiet ? " --quiet" : "");
  // The script prints its own one-line error (to stderr) before exiting non-zero.
  const int status = std::system(cmd.c_str());
  if (status == -1) throw std::runtime_error("report: cannot start " + pythonExe() + ": " + std::strerror(errno));
  if (WIFSIGNALED(status))
    throw std::runtime_error(fmt::format("report: {} was killed by signal {}", script, WTERMSIG(status)));
  if (WIFEXITED(status) && WEXITSTATUS(status) != 0)
    throw std::runtime_error(fmt::format("report: {} failed (exit code {}); {} was not written", script,
                                         WEXITSTATUS(status), out));
}

}  // namespace

void addReportCommand(CLI::App& app) {
  auto a = std::make_shared<ReportArgs>();
  CLI::App* cmd = app.add_subcommand(
      "report", "Merge a sweep folder's points and make DIR/report.html (plots and thumbnails embedded; full-size "
                "images linked from DIR/points)");
  cmd->add_option("dir", a->dir, "Folder written by `oitsim sweep`")->required();
  cmd->add_option("--out,-o", a->out, "HTML file to write (default DIR/report.html)");
  cmd->add_flag("--quiet,-q", a->quiet, "No merge summary, progress or summary");
  cmd->callback([a] { runReport(*a); });
}

}  // namespace oit::cli
