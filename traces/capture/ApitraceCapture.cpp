#include "traces/capture/ApitraceCapture.hpp"
#include "traces/capture/ApitraceStream.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <fmt/format.h>

#include "traces/capture/interposer/CaptureStream.hpp"

extern char** environ;

namespace oit::capture {

namespace fs = std::filesystem;
namespace st = stream;

namespace {

// A private temporary folder for the stream and the retracer's log, removed on exit.
struct TempDir {
  std::string path;
  TempDir() {
    const char* base = std::getenv("TMPDIR");
    std::string tmpl = std::string(base && *base ? base : "/tmp") + "/oitsim-apitrace-XXXXXX";
    if (!::mkdtemp(tmpl.data()))
      throw std::runtime_error(fmt::format("cannot create a temporary folder {}: {}", tmpl, std::strerror(errno)));
    path = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

std::string findOnPath(const std::string& name) {
  if (name.find('/') != std::string::npos) return ::access(name.c_str(), X_OK) == 0 ? name : "";
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/bin:/bin";
  size_t start = 0;
  while (start <= dirs.size()) {
    const size_t colon = dirs.find(':', start);
    const std::string dir = dirs.substr(start, colon == std::string::npos ? std::string::npos : colon - start);
    const std::string candidate = (dir.empty() ? "." : dir) + "/" + name;
    if (::access(candidate.c_str(), X_OK) == 0) return candidate;
    if (colon == std::string::npos) break;
    start = colon + 1;
  }
  return "";
}

// A private X server for glretrace (which presents through GLX even with
// --headless): Xvfb on a free display it picks itself (-displayfd), stopped with the
// capture. Without Xvfb the capture uses $DISPLAY.
class PrivateXServer {
 public:
  explicit PrivateXServer(const std::string& xvfb) {
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0)
      throw std::runtime_error(fmt::format("cannot create a pipe for Xvfb: {}", std::strerror(errno)));
    std::vector<std::string> args = {xvfb, "-displayfd", "3", "-nolisten", "tcp", "-noreset", "-screen", "0", "1920x1080x24"};
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 2, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_adddup2(&fa, fds[1], 3);
    const int rc = posix_spawn(&pid_, xvfb.c_str(), &fa, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
    ::close(fds[1]);
    if (rc != 0) {
      ::close(fds[0]);
      throw std::runtime_error(fmt::format("cannot start {}: {}", xvfb, std::strerror(rc)));
    }
    std::string number;
    char c = 0;
    while (::read(fds[0], &c, 1) == 1 && c != '\n') number += c;
    ::close(fds[0]);
    if (number.empty()) {
      stop();
      throw std::runtime_error(fmt::format("{} did not start (no display number on -displayfd)", xvfb));
    }
    display_ = ":" + number;
  }
  ~PrivateXServer() { stop(); }
  // Asks the server to exit without waiting for it (the destructor reaps it).
  void terminate() {
    if (pid_ > 0 && !terminated_) ::kill(pid_, SIGTERM);
    terminated_ = true;
  }
  PrivateXServer(const PrivateXServer&) = delete;
  PrivateXServer& operator=(const PrivateXServer&) = delete;
  const std::string& display() const { return display_; }

 private:
  void stop() {
    if (pid_ <= 0) return;
    if (!terminated_) ::kill(pid_, SIGTERM);
    int status = 0;
    while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
    pid_ = 0;
  }
  pid_t pid_ = 0;
  bool terminated_ = false;
  std::string display_;
};

// Runs the retracer with the interposer as its libGL.so.1; returns its exit status
// (the raw waitpid status).
// The record buffer holds `records_per_pixel` records per pixel of the frame (0:
// `max_records`, or GL's largest storage block when that is 0).
int runRetracer(const ApitraceOptions& o, uint64_t max_records, double records_per_pixel,
                const std::string& retracer, const std::string& gl_dir, const std::string& display,
                const std::string& stream_path, const std::string& log_path) {
  std::vector<std::string> env;
  for (char** e = environ; *e; ++e) {
    const std::string_view v(*e);
    if (v.starts_with("LD_LIBRARY_PATH=") || v.starts_with("DISPLAY=") || v.starts_with("OITSIM_") ||
        v.starts_with("GLIBC_TUNABLES="))
      continue;
    env.emplace_back(v);
  }
  // llvmpipe zero-fills every buffer it allocates, the record buffer is the GL's
  // largest storage block (128 MiB on Mesa 22), and page faults are dear in a VM:
  // with 4 KiB pages they were half the retracer's CPU time on the glmark2 frame
  // (bench/RESULTS-capture-apitrace.md). malloc asking for transparent huge pages
  // (madvise) cuts them 512-fold; where THP is off it changes nothing.
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  env.push_back(std::string("GLIBC_TUNABLES=") + (tunables && *tunables ? std::string(tunables) + ":" : "") +
                "glibc.malloc.hugetlb=1");
  const char* lib_path = std::getenv("LD_LIBRARY_PATH");
  env.push_back("LD_LIBRARY_PATH=" + gl_dir + (lib_path && *lib_path ? std::string(":") + lib_path : ""));
  env.push_back("DISPLAY=" + display);
  env.push_back("OITSIM_STREAM=" + stream_path);
  env.push_back(fmt::format("OITSIM_FRAMES={}-{}", o.first_frame, o.last_frame));
  env.push_back(std::string("OITSIM_VERIFY=") + (o.verify ? "1" : "0"));
  env.push_back(fmt::format("OITSIM_MAX_RECORDS={}", max_records));
  env.push_back(fmt::format("OITSIM_RECORDS_PER_PIXEL={}", records_per_pixel));
  std::vector<char*> envp;
  for (std::string& s : env) envp.push_back(s.data());
  envp.push_back(nullptr);
  std::vector<std::string> args = {retracer, "--headless", "--singlethread", o.trace};
  std::vector<char*> argv;
  for (std::string& s : args) argv.push_back(s.data());
  argv.push_back(nullptr);

  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 1, log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, retracer.c_str(), &fa, nullptr, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) throw std::runtime_error(fmt::format("cannot start {}: {}", retracer, std::strerror(rc)));
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) throw std::runtime_error(fmt::format("waiting for {}: {}", retracer, std::strerror(errno)));
  return status;
}

}  // namespace

const char* uncapturedReasonName(uint32_t reason) { return st::reasonName(reason); }

void checkApitraceFile(const std::string& path) {
  struct stat sb{};
  if (::stat(path.c_str(), &sb) != 0)
    throw std::invalid_argument(fmt::format("{}: cannot open the apitrace trace: {}", path, std::strerror(errno)));
  if (!S_ISREG(sb.st_mode)) throw std::invalid_argument(fmt::format("{}: not a regular file (an apitrace trace)", path));
  std::ifstream f(path, std::ios::binary);
  unsigned char m[2] = {};
  f.read(reinterpret_cast<char*>(m), 2);
  const bool snappy = f.gcount() == 2 && m[0] == 'a' && m[1] == 't';
  const bool gzip = f.gcount() == 2 && m[0] == 0x1F && m[1] == 0x8B;
  if (!snappy && !gzip)
    throw std::invalid_argument(fmt::format(
        "{}: not an apitrace trace: it starts with {}, expected 61 74 ('at', snappy) or 1F 8B (gzip), as "
        "`apitrace trace -o F.trace PROGRAM` writes",
        path, f.gcount() == 0 ? std::string("nothing (empty file)") : fmt::format("{:02X} {:02X}", m[0], m[1])));
}

std::string defaultInterposerPath() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return "liboitsim_interposer.so";
  return (exe.parent_path() / "liboitsim_interposer.so").string();
}

ApitraceResult captureApitrace(const ApitraceOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  checkApitraceFile(o.trace);
  if (o.first_frame > o.last_frame)
    throw std::invalid_argument(fmt::format("--frames {}-{}: the first frame is after the last", o.first_frame,
                                            o.last_frame));
  const std::string retracer = findOnPath(o.retracer.empty() ? "glretrace" : o.retracer);
  if (retracer.empty())
    throw std::runtime_error(fmt::format(
        "{} not found: the capture replays the trace with apitrace's retracer; apt-get install apitrace "
        "(scripts/setup.sh installs it)", o.retracer.empty() ? "glretrace" : o.retracer));
  const std::string xvfb = findOnPath("Xvfb");
  const char* user_display = std::getenv("DISPLAY");
  if (xvfb.empty() && !(user_display && *user_display))
    throw std::runtime_error("Xvfb not found and DISPLAY not set: glretrace presents through GLX even headless; "
                             "apt-get install xvfb (scripts/setup.sh installs it)");
  const std::string interposer = o.interposer.empty() ? defaultInterposerPath() : o.interposer;
  if (::access(interposer.c_str(), R_OK) != 0)
    throw std::runtime_error(fmt::format("cannot read the interposer {} (built with oitsim, next to the executable): {}",
                                         interposer, std::strerror(errno)));

  TempDir tmp;
  const std::string stream_path = tmp.path + "/stream.bin", log_path = tmp.path + "/retracer.log";
  // The retracer opens "libGL.so.1": here that is the interposer.
  const std::string gl_dir = tmp.path + "/gl";
  fs::create_directory(gl_dir);
  fs::create_symlink(fs::absolute(interposer), gl_dir + "/libGL.so.1");
  std::optional<PrivateXServer> x;
  if (!xvfb.empty()) x.emplace(xvfb);
  const std::string display = x ? x->display() : std::string(user_display);
  auto replay = [&](uint64_t max_records, double records_per_pixel) {
    return runRetracer(o, max_records, records_per_pixel, retracer, gl_dir, display, stream_path, log_path);
  };
  int status = replay(o.max_records_per_draw, o.records_per_pixel);
  // A draw that outgrew the buffer sized to the frame (it has blended already and
  // cannot be drawn again): replay the trace once more with room for the largest
  // such draw, so the frames hold every draw that fits GL's largest block or
  // --max-records-per-draw (the overflowing draws' counts are exact: the shader
  // counts past the capacity).
  const StreamScan first = scanStream(stream_path);
  const uint64_t ceiling =
      o.max_records_per_draw ? std::min(o.max_records_per_draw, first.record_limit) : first.record_limit;
  const bool again = first.overflow_need > first.record_capacity && first.record_capacity < ceiling;
  if (again) status = replay(std::min(first.overflow_need, ceiling), 0);
  // The X server stops while the stream is read (reaped when `x` goes).
  if (x) x->terminate();
  // The first scan describes the stream unless the second replay wrote it anew.
  ApitraceResult result = readStream(o, retracer, interposer, status, stream_path, log_path, again ? nullptr : &first);
  if (again) {
    result.replays = 2;
    result.first_record_capacity = first.record_capacity;
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace oit::capture
