// `oitsim sweep --emit slurm` on a real Slurm: a private one-node cluster on
// localhost (Debian's slurm-wlm and munge, installed by scripts/setup.sh's
// optional step), started and stopped by the test in its own temp dir, with its
// own munge key and socket, ports, state, spool, logs and pid files (no
// system-wide state). Skipped with the reason and the daemon's log tail when
// the daemons are missing or do not come up in time. Bounded: daemons get 5 s
// (munged) and 20 s (the node idle in sinfo), the job array 60 s.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <arpa/inet.h>
#include <csignal>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <cstdlib>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <map>
#include <netinet/in.h>
#include <sstream>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>
#include <vector>

#include "CliRunner.hpp"

namespace oit::test {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

std::string tail(const fs::path& path, size_t max_chars = 1500) {
  if (!fs::exists(path)) return "(" + path.string() + " does not exist)";
  std::string s = readText(path);
  if (s.size() > max_chars) s = "..." + s.substr(s.size() - max_chars);
  return path.string() + ":\n" + s;
}

// Two TCP ports free right now (held open together so they differ). They are
// closed before the daemons bind them, so another process could take one in
// between; then slurmctld/slurmd exit on the bind error, start() reports it
// with the daemon's log, and the test skips (never a false pass or failure).
// Not retried: the window is the few ms until the daemons start.
std::pair<int, int> freePorts() {
  int fds[2] = {-1, -1}, ports[2] = {0, 0};
  for (int i = 0; i < 2; ++i) {
    fds[i] = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_ANY);
    a.sin_port = 0;
    socklen_t len = sizeof a;
    if (fds[i] >= 0 && ::bind(fds[i], reinterpret_cast<sockaddr*>(&a), sizeof a) == 0 &&
        ::getsockname(fds[i], reinterpret_cast<sockaddr*>(&a), &len) == 0)
      ports[i] = ntohs(a.sin_port);
  }
  for (int fd : fds)
    if (fd >= 0) ::close(fd);
  return {ports[0], ports[1]};
}

// The private cluster. Daemons run in the foreground as this process's children
// (killed with it if the test process dies: PR_SET_PDEATHSIG), output to their
// logs; the destructor stops them (TERM, then KILL after 5 s) and removes the dir.
class LocalSlurm {
 public:
  LocalSlurm() {
    char tmpl[] = "/tmp/oitsim-slurm-XXXXXX";  // short: munge's socket path must fit sun_path
    if (::mkdtemp(tmpl)) dir_ = tmpl;
  }
  ~LocalSlurm() {
    if (!job_.empty()) runShell("timeout 10 scancel " + job_);
    // slurmd first (it owns the job steps), then the controller, then munged.
    for (auto it = pids_.rbegin(); it != pids_.rend(); ++it) stop(*it);
    if (had_conf_) ::setenv("SLURM_CONF", old_conf_.c_str(), 1);
    else ::unsetenv("SLURM_CONF");
    std::error_code ec;
    if (!dir_.empty()) fs::remove_all(dir_, ec);
  }
  LocalSlurm(const LocalSlurm&) = delete;
  LocalSlurm& operator=(const LocalSlurm&) = delete;

  const fs::path& dir() const { return dir_; }
  void setJob(const std::string& id) { job_ = id; }

  // Empty on success, else why the cluster is unavailable (for GTEST_SKIP).
  std::string start() {
    if (dir_.empty()) return "cannot create a temp dir under /tmp";
    if (::geteuid() != 0) return "needs root (slurmd launches the job steps; SlurmUser=root)";
    for (const char* exe : {"/usr/sbin/munged", "/usr/sbin/slurmctld", "/usr/sbin/slurmd", "/usr/bin/sbatch",
                            "/usr/bin/sinfo", "/usr/bin/scancel"})
      if (!fs::exists(exe)) return std::string(exe) + " is missing (Debian: slurm-wlm munge; scripts/setup.sh tries)";
    ::chmod(dir_.c_str(), 0755);
    fs::create_directories(dir_ / "state");
    fs::create_directories(dir_ / "spool");

    // A fresh 1024-byte munge key, readable by the owner only.
    {
      std::ifstream rnd("/dev/urandom", std::ios::binary);
      std::string key(1024, '\0');
      rnd.read(key.data(), static_cast<std::streamsize>(key.size()));
      const int fd = ::open((dir_ / "munge.key").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
      if (fd < 0 || !rnd || ::write(fd, key.data(), key.size()) != static_cast<ssize_t>(key.size()))
        return "cannot write the munge key";
      ::close(fd);
    }
    const fs::path sock = dir_ / "munge.sock";
    spawn({"/usr/sbin/munged", "--foreground", "--force", "--socket=" + sock.string(),
           "--key-file=" + (dir_ / "munge.key").string(), "--log-file=" + (dir_ / "munged.log").string(),
           "--pid-file=" + (dir_ / "munged.pid").string(), "--seed-file=" + (dir_ / "munge.seed").string()},
          dir_ / "munged.out");
    if (!waitFor(std::chrono::seconds(5), [&] { return fs::exists(sock); }))
      return (died_.empty() ? "munged did not create its socket within 5 s" : died_) + "\n" + tail(dir_ / "munged.log") + "\n" +
             tail(dir_ / "munged.out");

    const auto [ctld_port, slurmd_port] = freePorts();
    if (!ctld_port || !slurmd_port) return "no free TCP port for slurmctld/slurmd";
    const unsigned cpus = std::max(1u, std::thread::hardware_concurrency());
    // The node's memory in MiB, so that a job's --mem is checked against it
    // (without RealMemory Slurm assumes 1 MiB and refuses any --mem).
    const long long mem_mib = (long long)::sysconf(_SC_PHYS_PAGES) * ::sysconf(_SC_PAGESIZE) / (1024 * 1024);
    const std::string d = dir_.string();
    std::ofstream(dir_ / "slurm.conf") << "ClusterName=oitsimtest\n"
                                       << "SlurmctldHost=localhost\n"
                                       << "SlurmctldPort=" << ctld_port << "\n"
                                       << "SlurmdPort=" << slurmd_port << "\n"
                                       << "SlurmUser=root\nSlurmdUser=root\n"
                                       << "AuthType=auth/munge\nCredType=cred/munge\n"
                                       << "AuthInfo=socket=" << sock.string() << "\n"
                                       << "MpiDefault=none\n"
                                       << "ProctrackType=proctrack/linuxproc\nTaskPlugin=task/none\n"
                                       << "JobAcctGatherType=jobacct_gather/none\n"
                                       << "AccountingStorageType=accounting_storage/none\n"
                                       << "SelectType=select/cons_tres\nSelectTypeParameters=CR_CPU\n"
                                       << "ReturnToService=2\n"
                                       << "StateSaveLocation=" << d << "/state\n"
                                       << "SlurmdSpoolDir=" << d << "/spool\n"
                                       << "SlurmctldPidFile=" << d << "/slurmctld.pid\n"
                                       << "SlurmdPidFile=" << d << "/slurmd.pid\n"
                                       << "SlurmctldLogFile=" << d << "/slurmctld.log\n"
                                       << "SlurmdLogFile=" << d << "/slurmd.log\n"
                                       << "NodeName=localhost CPUs=" << cpus << " RealMemory=" << mem_mib
                                       << " State=UNKNOWN\n"
                                       << "PartitionName=test Nodes=localhost Default=YES MaxTime=INFINITE State=UP\n";
    const std::string conf = (dir_ / "slurm.conf").string();
    if (const char* c = std::getenv("SLURM_CONF")) {
      had_conf_ = true;
      old_conf_ = c;
    }
    ::setenv("SLURM_CONF", conf.c_str(), 1);  // for sinfo, sbatch, scancel
    spawn({"/usr/sbin/slurmctld", "-D", "-f", conf}, dir_ / "slurmctld.out");
    spawn({"/usr/sbin/slurmd", "-D", "-N", "localhost", "-f", conf}, dir_ / "slurmd.out");
    std::string state;
    const bool idle = waitFor(std::chrono::seconds(20), [&] {
      state = runShell("timeout 5 /usr/bin/sinfo -h -N -o %t").output;
      return state.find("idle") != std::string::npos;
    });
    if (!idle)
      return (died_.empty() ? "the node did not show idle in sinfo within 20 s (last: " + state + ")" : died_) +
             "\n" + tail(dir_ / "slurmctld.log") +
             "\n" + tail(dir_ / "slurmd.log") + "\n" + tail(dir_ / "slurmd.out");
    return "";
  }

 private:
  template <class Pred>
  bool waitFor(std::chrono::seconds bound, Pred ok) {
    const auto end = Clock::now() + bound;
    while (Clock::now() < end) {
      if (ok()) return true;
      for (size_t i = 0; i < pids_.size(); ++i) {  // a daemon that exited will not come up
        int st;
        if (::waitpid(pids_[i], &st, WNOHANG) == pids_[i]) {
          dead_.push_back(pids_[i]);
          died_ = names_[i] + (WIFEXITED(st) ? " exited with code " + std::to_string(WEXITSTATUS(st))
                                             : " was killed by signal " + std::to_string(WTERMSIG(st)));
          return false;
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(250));
    }
    return ok();
  }

  void spawn(const std::vector<std::string>& argv, const fs::path& out) {
    const pid_t parent = ::getpid();
    const pid_t pid = ::fork();
    if (pid == 0) {
      ::prctl(PR_SET_PDEATHSIG, SIGKILL);
      if (::getppid() != parent) ::_exit(127);
      const int fd = ::open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      const int nul = ::open("/dev/null", O_RDONLY);
      if (fd >= 0) {
        ::dup2(fd, 1);
        ::dup2(fd, 2);
      }
      if (nul >= 0) ::dup2(nul, 0);
      std::vector<char*> a;
      for (const auto& s : argv) a.push_back(const_cast<char*>(s.c_str()));
      a.push_back(nullptr);
      ::execv(a[0], a.data());
      const std::string msg = std::string("cannot exec ") + a[0] + ": " + std::strerror(errno) + "\n";
      if (::write(2, msg.data(), msg.size()) < 0) {
      }
      ::_exit(127);
    }
    if (pid > 0) {
      pids_.push_back(pid);
      names_.push_back(fs::path(argv[0]).filename().string());
    }
  }

  void stop(pid_t pid) {
    if (std::find(dead_.begin(), dead_.end(), pid) != dead_.end()) return;  // already reaped
    ::kill(pid, SIGTERM);
    const auto end = Clock::now() + std::chrono::seconds(5);
    int st;
    while (Clock::now() < end) {
      if (::waitpid(pid, &st, WNOHANG) != 0) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    ::kill(pid, SIGKILL);
    ::waitpid(pid, &st, 0);
  }

  fs::path dir_;
  std::vector<pid_t> pids_, dead_;
  std::vector<std::string> names_;
  std::string died_;  // which daemon exited early, and how
  std::string job_, old_conf_;
  bool had_conf_ = false;
};

// Three functional points on one small generated trace.
const char* kSlurmSpec = R"({
  "traces": [{"gen": "particles", "width": 96, "height": 54, "count": 150, "backdrop": true}],
  "base": {"mode": "functional", "format": "fp32", "layers": 4},
  "axes": {"algo": ["mlab", "hybrid", "adaptive"]}
})";

TEST(SlurmCluster, EmittedJobArrayRunsOnLocalhostAndMatchesALocalSweep) {
  if (!haveMatplotlib()) GTEST_SKIP() << "python3-matplotlib absent (scripts/setup.sh installs it): oitsim report cannot draw";
  const auto t0 = Clock::now();
  LocalSlurm cluster;
  const std::string why = cluster.start();
  if (!why.empty()) GTEST_SKIP() << "one-node Slurm on localhost unavailable: " << why;
  const fs::path d = cluster.dir();
  std::ofstream(d / "spec.json") << kSlurmSpec;
  const std::string spec = (d / "spec.json").string();

  // The same spec run locally: the reference table.
  CliResult r = runOitsim("sweep " + spec + " --out " + (d / "local").string() + " --jobs 2 -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;

  // Chunked: two points per array task, so task 0 runs points 0 and 1, task 1
  // point 2; with the site options a cluster needs passed through.
  const fs::path out = d / "slurm";
  r = runOitsim("sweep " + spec + " --out " + out.string() +
                " --emit slurm --points-per-task 2 --time 0:05:00 --mem 512M --partition test");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string script = readText(out / "sweep.slurm");
  ASSERT_NE(script.find("#SBATCH --array=0-1\n"), std::string::npos) << script;
  ASSERT_NE(script.find("#SBATCH --time=0:05:00\n#SBATCH --mem=512M\n#SBATCH --partition=test\n"), std::string::npos)
      << script;
  ASSERT_EQ(readText(out / "slurm-tasks.txt"), "0 1\n2\n");
  ASSERT_FALSE(fs::exists(out / "points/0000-particles-mlab/report.json")) << "--emit must not run points";

  // Submit and wait (bounded): sbatch --wait exits with the array's highest task exit code.
  auto [rc, sb] = runShell("cd " + d.string() + " && timeout 60 /usr/bin/sbatch --parsable --wait " +
                        (out / "sweep.slurm").string());
  std::string job = sb.substr(0, sb.find_first_of(";\n"));
  if (!job.empty() && job.find_first_not_of("0123456789") == std::string::npos) cluster.setJob(job);
  ASSERT_EQ(rc, 0) << "sbatch --wait: " << sb << "\n" << tail(d / "slurmctld.log") << "\n" << tail(d / "slurmd.log");
  ASSERT_FALSE(job.empty()) << sb;
  for (int task = 0; task < 2; ++task)
    EXPECT_TRUE(fs::exists(out / ("slurm-" + job + "_" + std::to_string(task) + ".log")))
        << "no Slurm log for task " << task;
  EXPECT_FALSE(fs::exists(out / ("slurm-" + job + "_2.log"))) << "two tasks, not one per point";

  r = runOitsim("report -q " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json res = nlohmann::json::parse(readText(out / "results.json"));
  EXPECT_EQ(res["summary"]["points"].get<int>(), 3);
  EXPECT_EQ(res["summary"]["ok"].get<int>(), 3);
  EXPECT_EQ(res["summary"]["failed"].get<int>(), 0);
  const char* ids[] = {"0000-particles-mlab", "0001-particles-hybrid", "0002-particles-adaptive"};
  const char* algos[] = {"mlab", "hybrid", "adaptive"};
  ASSERT_EQ(res["points"].size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    const auto& p = res["points"][i];
    EXPECT_EQ(p["id"], ids[i]);
    EXPECT_EQ(p["status"], "ok") << p["error"];
    EXPECT_EQ(p["metrics"]["config.algorithm"], algos[i]);
    EXPECT_EQ(p["metrics"]["config.layers"].get<int>(), 4);
    EXPECT_EQ(p["metrics"]["trace.width"].get<int>(), 96);
    EXPECT_GT(p["metrics"]["image.metrics.rmse"].get<double>(), 0.0) << p["id"];
  }

  // Same table as the local sweep, apart from wall clock and output paths.
  const auto a = lines(readText(d / "local/results.csv"));
  const auto b = lines(readText(out / "results.csv"));
  ASSERT_EQ(a.size(), 4u);
  ASSERT_EQ(b.size(), 4u);
  const size_t compared = compareSweepTables(a, b);
  EXPECT_GT(compared, 3u * 20u);
  // Informational only (no wall-clock assertion: speed lives in bench/); the
  // hang guards are the bounded waits above (daemons 5 s / 20 s, sbatch 60 s).
  const double secs = std::chrono::duration<double>(Clock::now() - t0).count();
  std::printf("one-node Slurm sweep: %.1f s (job %s)\n", secs, job.c_str());
}

}  // namespace
}  // namespace oit::test
