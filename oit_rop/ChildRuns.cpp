#include "oit_rop/ChildRuns.hpp"

#include <fmt/format.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "traces/TempFiles.hpp"

namespace oit::rop {

namespace {

using nlohmann::json;

// The pipe carries frames: one type byte, then
//   'P': the job's progress, a double;
//   'R': its result, an 8-byte length and a JSON head, then the image's floats;
//   'E': its error, an 8-byte length and the message.
constexpr char kProgress = 'P', kResult = 'R', kError = 'E';

void writeAll(int fd, const void* data, size_t n) {
  const char* p = static_cast<const char*>(data);
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) _exit(3);  // the parent is gone: nothing left to report to
    p += w;
    n -= size_t(w);
  }
}

void writeFrame(int fd, char type, const std::string& head, const void* tail = nullptr, size_t tail_bytes = 0) {
  writeAll(fd, &type, 1);
  const uint64_t n = head.size();
  writeAll(fd, &n, 8);
  writeAll(fd, head.data(), head.size());
  if (tail_bytes) writeAll(fd, tail, tail_bytes);
}

json countsJson(const model::RenderCounts& c) {
  return {{"in", c.fragments_in},       {"opaque", c.opaque},
          {"culled", c.culled},         {"stored", c.stored},
          {"merged", c.merged},         {"discarded", c.discarded},
          {"pass_outcomes", c.pass_outcomes}, {"bytes_read", c.bytes_read},
          {"bytes_written", c.bytes_written}, {"source_passes", c.source_passes}};
}

model::RenderCounts countsFrom(const json& c) {
  model::RenderCounts r;
  r.fragments_in = c.at("in");
  r.opaque = c.at("opaque");
  r.culled = c.at("culled");
  r.stored = c.at("stored");
  r.merged = c.at("merged");
  r.discarded = c.at("discarded");
  r.pass_outcomes = c.at("pass_outcomes").get<std::vector<std::array<uint64_t, model::kOutcomeCount>>>();
  r.bytes_read = c.at("bytes_read");
  r.bytes_written = c.at("bytes_written");
  r.source_passes = c.at("source_passes");
  return r;
}

// The child's side: runs the job, sends progress and then its result or error.
[[noreturn]] void childMain(const TimingJob& job, int fd) {
  int code = 0;
  try {
    double last = -1.0;
    const auto progress = [&](double fraction, const std::string&) {
      if (fraction < last + 0.002 && fraction < 1.0) return;  // a frame per 0.2 % at most
      last = fraction;
      const char type = kProgress;
      writeAll(fd, &type, 1);
      writeAll(fd, &fraction, sizeof fraction);
    };
    const TimingResult r = job(progress);
    const json head = {{"stats", r.stats},       {"counts", countsJson(r.counts)}, {"width", r.image.width},
                       {"height", r.image.height}, {"wall_seconds", r.wall_seconds}, {"pool_bytes", r.pool_bytes}};
    writeFrame(fd, kResult, head.dump(), r.image.pixels.data(), r.image.pixels.size() * sizeof(model::Rgb));
  } catch (const std::exception& e) {
    writeFrame(fd, kError, e.what());
    code = 1;
  } catch (...) {
    writeFrame(fd, kError, "unknown exception");
    code = 1;
  }
  ::close(fd);
  // No exit handlers: the SystemC kernel and the parent's objects were copied
  // into this process and must not be torn down twice.
  _exit(code);
}

struct Child {
  size_t job = 0;
  pid_t pid = -1;
  int fd = -1;
  std::string in;        // bytes not yet parsed
  double fraction = 0.0;
  bool have_result = false;
  std::string error;
};

// Parses the complete frames at the front of c.in; false on a malformed stream.
bool parseFrames(Child& c, TimingResult& out) {
  for (;;) {
    if (c.in.empty()) return true;
    const char type = c.in[0];
    if (type == kProgress) {
      if (c.in.size() < 1 + sizeof(double)) return true;
      std::memcpy(&c.fraction, c.in.data() + 1, sizeof(double));
      c.in.erase(0, 1 + sizeof(double));
      continue;
    }
    if (type != kResult && type != kError) return false;
    if (c.in.size() < 9) return true;
    uint64_t n = 0;
    std::memcpy(&n, c.in.data() + 1, 8);
    if (c.in.size() < 9 + n) return true;
    const std::string head = c.in.substr(9, n);
    if (type == kError) {
      c.error = head.empty() ? "failed" : head;
      c.in.erase(0, 9 + n);
      continue;
    }
    const json h = json::parse(head);
    const uint32_t w = h.at("width"), ht = h.at("height");
    const size_t image_bytes = size_t(w) * ht * sizeof(model::Rgb);
    if (c.in.size() < 9 + n + image_bytes) return true;
    out.stats = h.at("stats");
    out.counts = countsFrom(h.at("counts"));
    out.wall_seconds = h.at("wall_seconds");
    out.pool_bytes = h.at("pool_bytes");
    out.image = model::Image(w, ht);
    std::memcpy(out.image.pixels.data(), c.in.data() + 9 + n, image_bytes);
    c.in.erase(0, 9 + n + image_bytes);
    c.have_result = true;
    c.fraction = 1.0;
  }
}

void stopAll(std::vector<Child>& active) {
  for (Child& c : active) {
    if (c.pid > 0) ::kill(c.pid, SIGTERM);
  }
  for (Child& c : active) {
    if (c.fd >= 0) ::close(c.fd);
    if (c.pid > 0) {
      int status = 0;
      while (::waitpid(c.pid, &status, 0) < 0 && errno == EINTR) {
      }
      unregisterChildProcess(c.pid);
    }
  }
  active.clear();
}

}  // namespace

unsigned usableCores() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) == 0) return std::max(1, CPU_COUNT(&set));
  const long n = ::sysconf(_SC_NPROCESSORS_ONLN);
  return n > 0 ? unsigned(n) : 1u;
}

std::vector<TimingResult> runTimingInChildren(const std::vector<TimingJob>& jobs, const ChildRunOptions& options) {
  std::vector<TimingResult> results(jobs.size());
  std::vector<double> done(jobs.size(), 0.0);
  std::vector<Child> active;
  size_t next = 0;
  const unsigned parallel = std::max(1u, options.parallel);
  auto last_report = std::chrono::steady_clock::now() - std::chrono::seconds(1);
  const auto report = [&](bool force) {
    if (!options.progress || jobs.empty()) return;
    const auto now = std::chrono::steady_clock::now();
    if (!force && now - last_report < std::chrono::milliseconds(100)) return;
    last_report = now;
    double sum = 0;
    for (double d : done) sum += d;
    options.progress(sum / double(jobs.size()));
  };
  const auto fail = [&](size_t job, std::string why) {  // a copy: `why` may live in a Child stopAll() destroys
    std::string name = options.name ? options.name(job) : jobs.size() > 1 ? fmt::format("job {}", job) : "";
    stopAll(active);
    throw std::runtime_error(name.empty() ? why : name + ": " + why);
  };
  try {
    while (next < jobs.size() || !active.empty()) {
      while (active.size() < parallel && next < jobs.size()) {
        int fd[2];
        if (::pipe(fd) != 0) throw std::runtime_error(fmt::format("cannot create a pipe: {}", std::strerror(errno)));
        std::fflush(stdout);
        std::fflush(stderr);
        const pid_t pid = ::fork();
        if (pid < 0) {
          const int err = errno;
          ::close(fd[0]);
          ::close(fd[1]);
          throw std::runtime_error(fmt::format("cannot start a child process: {}", std::strerror(err)));
        }
        if (pid == 0) {
          ::close(fd[0]);
          for (const Child& c : active) {  // the other children are not this one's
            ::close(c.fd);
            unregisterChildProcess(c.pid);
          }
          childMain(jobs[next], fd[1]);
        }
        registerChildProcess(pid);  // an interrupt of this process reaches the child too
        ::close(fd[1]);
        Child c;
        c.job = next++;
        c.pid = pid;
        c.fd = fd[0];
        active.push_back(std::move(c));
      }
      std::vector<pollfd> fds;
      for (const Child& c : active) fds.push_back({c.fd, POLLIN, 0});
      const int ready = ::poll(fds.data(), fds.size(), 100);
      if (ready < 0 && errno != EINTR) throw std::runtime_error(fmt::format("poll: {}", std::strerror(errno)));
      std::vector<size_t> ended;
      for (size_t i = 0; ready > 0 && i < active.size(); ++i) {
        if (!(fds[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
        Child& c = active[i];
        char buf[1 << 16];
        const ssize_t got = ::read(c.fd, buf, sizeof buf);
        if (got < 0 && errno == EINTR) continue;
        if (got > 0) {
          c.in.append(buf, size_t(got));
          if (!parseFrames(c, results[c.job])) fail(c.job, "malformed output from the child process");
          done[c.job] = c.fraction;
          continue;
        }
        // End of the child's output: it has exited or is about to.
        ::close(c.fd);
        c.fd = -1;
        int status = 0;
        while (::waitpid(c.pid, &status, 0) < 0 && errno == EINTR) {
        }
        unregisterChildProcess(c.pid);
        c.pid = -1;
        if (!c.error.empty()) fail(c.job, c.error);
        if (!c.have_result || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
          fail(c.job, WIFSIGNALED(status) ? fmt::format("the child process was killed by signal {}", WTERMSIG(status))
                                          : fmt::format("the child process exited with status {} without a result",
                                                        WIFEXITED(status) ? WEXITSTATUS(status) : -1));
        done[c.job] = 1.0;
        ended.push_back(i);
      }
      for (size_t k = ended.size(); k-- > 0;) active.erase(active.begin() + ptrdiff_t(ended[k]));
      report(!ended.empty());
    }
  } catch (...) {
    stopAll(active);
    throw;
  }
  return results;
}

std::vector<TimingResult> runTimingSeeds(const SeedRunsRequest& rq) {
  if (rq.seeds == 0) throw std::invalid_argument("runTimingSeeds: at least one seed");
  std::vector<TimingJob> jobs;
  for (unsigned i = 0; i < rq.seeds; ++i) {
    jobs.push_back([&rq, i](const std::function<void(double, const std::string&)>& progress) {
      RopConfig cfg = rq.cfg;
      cfg.input.seed = rq.cfg.input.seed + i;  // wraps at 2^64, as any seed may
      TimingOptions opt = rq.options;
      if (i != 0) opt.vcd_path.clear();
      opt.progress = progress;
      auto src = rq.open_trace();
      auto algo = rq.make_algorithm();
      return runTiming(*src, *algo, cfg, opt);
    });
  }
  ChildRunOptions o;
  o.parallel = std::min(rq.parallel ? rq.parallel : usableCores(), rq.seeds);
  o.progress = rq.progress;
  o.name = [&rq](size_t i) { return fmt::format("seed {} (input.seed {})", i, rq.cfg.input.seed + i); };
  return runTimingInChildren(jobs, o);
}

}  // namespace oit::rop
