// oitsim stress: the numerical stress suite (model/StressSuite.hpp). Renders
// every stress case with every algorithm x storage format x k, compares with
// the abuffer reference and writes stress-table.md / stress-table.csv.
// Exits non-zero when any output is NaN/Inf, leaves [0,1], has unbalanced
// outcome counts, or a render throws; the tables are written either way, so
// the violations can be read.
#include <fmt/core.h>

#include <map>
#include <memory>

#include "apps/Commands.hpp"
#include "apps/Progress.hpp"
#include "model/StressSuite.hpp"

namespace oit::cli {
namespace {

struct StressArgs {
  std::string out = "reports/stress";
  std::vector<std::string> algos, cases;
  std::vector<unsigned> layers{1, 4, 16, 64};
  bool quiet = false;
};

void runStressCommand(const StressArgs& a) {
  namespace st = model::stress;
  st::StressOptions opt;
  opt.algorithms = a.algos;
  opt.cases = a.cases;
  opt.layers = a.layers;
  const size_t total = a.cases.empty() ? st::caseNames().size() : a.cases.size();
  Progress progress("stress", !a.quiet);
  size_t done = 0;
  opt.on_case = [&](const std::string& name) { progress.update(double(done++) / double(total), name); };
  const std::vector<st::StressRow> rows = st::runStress(opt);
  progress.finish();
  st::writeStressTables(rows, a.out, commandLine());

  // Per-case summary: configurations run, n/a, violations, worst error.
  struct Sum {
    size_t ran = 0, na = 0, bad = 0;
    double worst = 0;
  };
  std::vector<std::string> order;
  std::map<std::string, Sum> sums;
  size_t bad = 0;
  for (const st::StressRow& r : rows) {
    if (!sums.count(r.case_name)) order.push_back(r.case_name);
    Sum& s = sums[r.case_name];
    if (r.status == st::RowStatus::NotApplicable) {
      ++s.na;
      continue;
    }
    ++s.ran;
    if (r.violation()) ++s.bad, ++bad;
    if (r.max_abs_error > s.worst) s.worst = r.max_abs_error;
  }
  if (!a.quiet) {
    fmt::print("{:<28} {:>5} {:>5} {:>10} {:>14}\n", "case", "runs", "n/a", "violations", "worst max err");
    for (const std::string& c : order) {
      const Sum& s = sums[c];
      fmt::print("{:<28} {:>5} {:>5} {:>10} {:>14.3g}\n", c, s.ran, s.na, s.bad, s.worst);
    }
    for (const st::StressRow& r : rows)
      if (r.violation())
        fmt::print("VIOLATION {} {}{} {} k={}: {}\n", r.case_name, r.algorithm, r.variant.empty() ? "" : " " + r.variant,
                   r.format, r.k ? std::to_string(r.k) : "-", r.note);
    fmt::print("{} cases, {} rows, {} violations; wrote {}/stress-table.md and .csv\n", order.size(), rows.size(), bad,
               a.out);
  }
  if (bad) throw std::runtime_error(fmt::format("stress: {} violation(s) (NaN/Inf, output outside [0,1], unbalanced "
                                                "counts or render errors); see {}/stress-table.md",
                                                bad, a.out));
}

}  // namespace

void addStressCommand(CLI::App& app) {
  auto a = std::make_shared<StressArgs>();
  CLI::App* cmd = app.add_subcommand(
      "stress", "Numerical stress suite: every algorithm x format x k on extreme cases; writes stress-table.md/.csv");
  cmd->add_option("--out,-o", a->out, "Output folder for stress-table.md and stress-table.csv")->capture_default_str();
  cmd->add_option("--algo,-a", a->algos, "Only these algorithms (repeatable; default: all)");
  cmd->add_option("--case,-c", a->cases, "Only these cases (repeatable; default: all)");
  cmd->add_option("--layers,-k", a->layers, "k values for algorithms with layers")->delimiter(',')->capture_default_str();
  cmd->add_flag("--quiet,-q", a->quiet, "No progress or summary");
  cmd->callback([a] { runStressCommand(*a); });
}

}  // namespace oit::cli
