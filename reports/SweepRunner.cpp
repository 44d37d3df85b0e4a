// A sweep on this machine: traces, resumption, one `oitsim run` per point.
#include "reports/SweepRunner.hpp"

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <fcntl.h>
#include <fstream>
#include <spawn.h>
#include <sstream>
#include <sys/wait.h>
#include <thread>

#include "reports/AtomicFile.hpp"
#include "traces/TempFiles.hpp"

extern char** environ;

namespace oit::sweep {

namespace fs = std::filesystem;

namespace {

// Runs tasks on `jobs` threads, each pulling the next index (each task waits on
// its own child process, so threads, not cores, are the limit).
void runAll(const std::vector<std::function<void(size_t)>>& tasks, unsigned jobs) {
  std::atomic<size_t> next{0};
  std::vector<std::thread> workers;
  for (unsigned w = 0; w < std::max(1u, jobs); ++w)
    workers.emplace_back([&] {
      for (size_t i = next++; i < tasks.size(); i = next++) tasks[i](i);
    });
  for (auto& t : workers) t.join();
}

}  // namespace

Outcome spawnAndWait(const std::string& exe, const std::vector<std::string>& args, const fs::path& out_file,
                     const fs::path& err_file) {
  std::vector<std::string> all{exe};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& s : all) argv.push_back(s.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&fa, 2, err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  Outcome o;
  const auto t0 = std::chrono::steady_clock::now();
  pid_t pid;
  const int rc = posix_spawn(&pid, exe.c_str(), &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) {
    std::ofstream(err_file) << "cannot start " << exe << ": " << std::strerror(rc) << "\n";
    return o;
  }
  registerChildProcess(pid);  // an interrupt of the sweep reaches it too
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  unregisterChildProcess(pid);
  o.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  o.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  return o;
}

std::string tailOf(const fs::path& file, size_t max_chars) {
  std::ifstream in(file);
  std::stringstream ss;
  ss << in.rdbuf();
  std::string s = ss.str();
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  if (s.size() > max_chars) s = "..." + s.substr(s.size() - max_chars);
  return s;
}

std::string headOf(const fs::path& file, size_t max_lines) {
  std::ifstream in(file);
  std::string out, line;
  size_t n = 0;
  while (std::getline(in, line)) {
    if (n == max_lines) {
      out += "\n...";
      break;
    }
    out += (n++ ? "\n" : "") + line;
  }
  while (!out.empty() && (out.back() == '\n' || out.back() == ' ')) out.pop_back();
  return out;
}

void generateTraces(const Plan& plan, const std::map<std::string, std::string>& earlier_stamps, bool force,
                    unsigned jobs, bool out_existed, const Say& say) {
  const fs::path& out = plan.out;
  const bool traces_existed = fs::exists(out / "traces");
  std::error_code mk;
  fs::create_directories(out / "traces", mk);
  if (mk) throw std::runtime_error(fmt::format("--out {}: cannot create the folder: {}", out.string(), mk.message()));
  std::vector<const TraceEntry*> gens;
  for (const auto& t : plan.traces) {
    if (t.gen_args.empty()) continue;
    const auto earlier = earlier_stamps.find(t.name);
    const bool up_to_date = !force && fs::exists(t.path) && earlier != earlier_stamps.end() &&
                            earlier->second == currentTraceStamp(t);
    if (up_to_date) {
      say(fmt::format("trace {}: {} is up to date (same generator; --force regenerates it)", t.name, t.path));
    } else {
      gens.push_back(&t);
    }
  }
  std::vector<fs::path> made;  // files of this step that were not there before
  for (const TraceEntry* t : gens)
    for (const fs::path& f : {fs::path(t->path), out / "traces" / (t->name + ".log"), out / "traces" / (t->name + ".err")})
      if (!fs::exists(f)) made.push_back(f);
  std::vector<std::string> errors(gens.size());
  std::vector<std::function<void(size_t)>> tasks;
  for (size_t i = 0; i < gens.size(); ++i)
    tasks.push_back([&, i](size_t) {
      const TraceEntry& t = *gens[i];
      const fs::path log = out / "traces" / (t.name + ".log"), err = out / "traces" / (t.name + ".err");
      const Outcome o = spawnAndWait(plan.executable, t.gen_args, log, err);
      if (o.exit_code != 0 || !fs::exists(t.path)) {
        std::string cmd = "oitsim";
        for (const auto& g : t.gen_args) {
          cmd += ' ';
          cmd += shellQuote(g);
        }
        std::string text = headOf(err, 6);
        if (text.empty()) text = headOf(log, 6);
        if (text.empty()) text = "(no output)";
        std::string indented;
        for (std::istringstream in(text); std::getline(in, text);) indented += "\n    " + text;
        errors[i] = fmt::format("traces[{}] {}: `{}` {}:{}", t.index, t.name, cmd,
                                o.exit_code == 0 ? "wrote no trace" : fmt::format("exited with code {}", o.exit_code),
                                indented);
        say(fmt::format("trace {}: `oitsim gen` failed", t.name));
      } else {
        say(fmt::format("trace {}: generated {} ({:.1f} s)", t.name, t.path, o.wall_seconds));
      }
    });
  runAll(tasks, jobs);
  std::string failures;
  size_t failed = 0;
  for (const auto& e : errors)
    if (!e.empty()) {
      failures += "\n  " + e;
      ++failed;
    }
  if (!failed) return;
  // Nothing runs, and the folder is left as it was (the generators' errors are
  // in the message, so nothing is lost).
  std::error_code ec;
  for (const auto& f : made) fs::remove(f, ec);
  if (!traces_existed) fs::remove(out / "traces", ec);  // only if empty
  if (!out_existed) fs::remove(out, ec);
  throw std::runtime_error(fmt::format("sweep {}: {} of {} trace generator(s) failed, so nothing ran and {} {}:{}",
                                       plan.spec, failed, gens.size(), out.string(),
                                       out_existed ? "was left as it was" : "was not created", failures));
}

PendingPoints preparePoints(const Plan& plan, const Plan* earlier, const std::map<std::string, std::string>& earlier_stamps,
                            bool force) {
  std::map<std::string, const Point*> before;
  if (earlier)
    for (const Point& p : earlier->points) before[p.id] = &p;
  std::map<std::string, bool> trace_unchanged;
  for (const TraceEntry& t : plan.traces) {
    const auto e = earlier_stamps.find(t.name);
    trace_unchanged[t.name] = e != earlier_stamps.end() && e->second == currentTraceStamp(t);
  }
  PendingPoints out;
  for (size_t i = 0; i < plan.points.size(); ++i) {
    const Point& p = plan.points[i];
    const fs::path dir = plan.out / "points" / p.id;
    bool finished = false;
    if (!force && before.count(p.id) && before.at(p.id)->args == p.args && trace_unchanged[p.trace] &&
        fs::exists(dir / "report.json")) {
      finished = true;
      if (fs::exists(dir / "status.json")) {  // run here; a Slurm task leaves none
        try {
          std::ifstream in(dir / "status.json");
          finished = nlohmann::json::parse(in).value("exit_code", -1) == 0;
        } catch (const nlohmann::json::exception&) {
          finished = false;
        }
      }
    }
    if (finished) {
      ++out.kept;
    } else {
      // Nothing of an earlier run into this folder may pass for this one's.
      fs::remove_all(dir);
      out.indices.push_back(i);
    }
  }
  return out;
}

void runPoints(const Plan& plan, const std::vector<size_t>& indices, unsigned jobs, const Say& say) {
  std::atomic<size_t> done{0};
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<std::function<void(size_t)>> tasks;
  const size_t total = indices.size();
  for (size_t i : indices)
    tasks.push_back([&, i](size_t) {
      const Point& p = plan.points[i];
      const fs::path dir = plan.out / "points" / p.id;
      fs::remove_all(dir);
      fs::create_directories(dir);
      const Outcome o = spawnAndWait(plan.executable, p.args, dir / "stdout.txt", dir / "stderr.txt");
      const bool ok = o.exit_code == 0 && fs::exists(dir / "report.json");
      const nlohmann::json st{{"exit_code", o.exit_code}, {"wall_seconds", o.wall_seconds}};
      reports::writeFileAtomically((dir / "status.json").string(), st.dump(2) + "\n");
      const size_t n = ++done;
      const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      say(fmt::format("[{:>{}}/{}] {:<6} {:<40} {:6.2f} s  (elapsed {:.0f} s, ~{:.0f} s left){}", n,
                      std::to_string(total).size(), total, ok ? "ok" : "FAILED", p.id, o.wall_seconds, el,
                      el / double(n) * double(total - n), ok ? "" : "\n    " + tailOf(dir / "stderr.txt", 300)));
    });
  runAll(tasks, jobs);
}

}  // namespace oit::sweep
