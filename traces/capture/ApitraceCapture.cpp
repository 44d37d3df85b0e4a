#include "traces/capture/ApitraceCapture.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <fmt/format.h>

#include "traces/capture/interposer/BlendClass.hpp"
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

std::string tail(const std::string& text, size_t lines) {
  size_t pos = text.size();
  while (pos > 0 && (text[pos - 1] == '\n')) --pos;
  for (size_t n = 0; n < lines && pos > 0; ++n) {
    pos = text.rfind('\n', pos - 1);
    if (pos == std::string::npos) {
      pos = 0;
      break;
    }
  }
  std::string t = text.substr(pos);
  while (!t.empty() && t.front() == '\n') t.erase(0, 1);
  while (!t.empty() && t.back() == '\n') t.pop_back();
  for (char& c : t)
    if (c == '\n') c = ' ';
  return t;
}

std::string readFile(const std::string& path) {
  std::ifstream f(path, std::ios::binary | std::ios::ate);
  if (!f) return {};
  std::string s(static_cast<size_t>(f.tellg()), '\0');
  f.seekg(0);
  f.read(s.data(), static_cast<std::streamsize>(s.size()));
  s.resize(static_cast<size_t>(f.gcount()));
  return s;
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
    std::vector<std::string> args = {xvfb, "-displayfd", "3", "-nolisten", "tcp", "-screen", "0", "1920x1080x24"};
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
  PrivateXServer(const PrivateXServer&) = delete;
  PrivateXServer& operator=(const PrivateXServer&) = delete;
  const std::string& display() const { return display_; }

 private:
  void stop() {
    if (pid_ <= 0) return;
    ::kill(pid_, SIGTERM);
    int status = 0;
    while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
    pid_ = 0;
  }
  pid_t pid_ = 0;
  std::string display_;
};

// Runs the retracer with the interposer as its libGL.so.1; returns its exit status
// (the raw waitpid status).
int runRetracer(const ApitraceOptions& o, const std::string& retracer, const std::string& gl_dir,
                const std::string& display, const std::string& stream_path, const std::string& log_path) {
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
  env.push_back(fmt::format("OITSIM_MAX_RECORDS={}", o.max_records_per_draw));
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

// Straight RGBA of a record, clamped to what a trace holds; counts what it changed.
void toFragment(const st::GpuRecord& r, const st::DrawChunk& d, FrameCapture& f, Fragment& out) {
  float c[4] = {r.rgba[0], r.rgba[1], r.rgba[2], r.rgba[3]};
  bool clamped = false;
  for (float& v : c) {
    if (!std::isfinite(v)) {
      v = std::isinf(v) && v > 0 ? 1.0f : 0.0f;
      clamped = true;
    } else if (v < 0.0f || v > 1.0f) {
      v = std::clamp(v, 0.0f, 1.0f);
      clamped = true;
    }
  }
  if (d.state.blend_mode == st::kBlendPremulOver) {
    // ONE, ONE_MINUS_SRC_ALPHA blends a premultiplied colour: the trace holds straight colour.
    if (c[3] > 0.0f) {
      for (int k = 0; k < 3; ++k) {
        const float s = c[k] / c[3];
        if (s > 1.0f) ++f.premultiplied_clamped;
        c[k] = std::min(s, 1.0f);
      }
    } else if (c[0] > 0.0f || c[1] > 0.0f || c[2] > 0.0f) {
      c[0] = c[1] = c[2] = 0.0f;
      ++f.premultiplied_zero_alpha;
    }
  }
  if (clamped) ++f.colour_clamped;
  float z = r.z;
  if (!(z >= 0.0f && z <= 1.0f)) {
    z = std::isfinite(z) ? std::clamp(z, 0.0f, 1.0f) : 1.0f;
    ++f.depth_clamped;
  }
  out = Fragment{static_cast<uint16_t>(r.xy & 0xFFFF), static_cast<uint16_t>(r.xy >> 16), z, c[0], c[1], c[2],
                 c[3], r.prim, d.index};
}

DrawState toDrawState(const st::DrawChunk& d, uint64_t fragments) {
  DrawState s;
  s.blend = static_cast<BlendMode>(d.state.blend_mode);
  s.depth_test = d.state.depth_test != 0;
  s.depth_write = d.state.depth_write != 0;
  s.depth_func = d.state.depth_func;
  s.blend_eq_rgb = d.state.blend_eq_rgb;
  s.blend_src_rgb = d.state.blend_src_rgb;
  s.blend_dst_rgb = d.state.blend_dst_rgb;
  s.blend_eq_alpha = d.state.blend_eq_alpha;
  s.blend_src_alpha = d.state.blend_src_alpha;
  s.blend_dst_alpha = d.state.blend_dst_alpha;
  s.fragments = fragments;
  return s;
}

// Appends one captured draw's records to the frame in API order.
void addDraw(const st::DrawChunk& d, const st::GpuRecord* recs, FrameCapture& f) {
  const auto mode = static_cast<BlendMode>(d.state.blend_mode);
  DrawInfo info;
  info.id = d.index;
  info.cls = mode == BlendMode::Off ? DrawClass::Opaque : DrawClass::Transparent;
  std::string fn(d.function, ::strnlen(d.function, sizeof d.function));
  info.name = fmt::format("{} #{} program {}", fn, d.index, d.program).substr(0, 55);
  info.state = toDrawState(d, d.records);
  f.header.draws.push_back(info);
  ++f.draws_by_mode[d.state.blend_mode];
  f.fragments_by_mode[d.state.blend_mode] += d.records;
  if (!d.state.early_tests) ++f.late_depth_draws;
  if (d.instanced) ++f.multi_draws;
  if (!info.state->recorded()) return;  // listed, not modelled: its fragments stay out
  const size_t first = f.fragments.size();
  f.fragments.reserve(first + d.records);  // not resize: its zero fill was 6 % of the capture's CPU time
  for (uint64_t i = 0; i < d.records; ++i) {
    Fragment frag;
    toFragment(recs[i], d, f, frag);
    f.fragments.push_back(frag);
  }
  // Threads append in any order. API order within a draw: primitive, then pixel
  // rows bottom-up, then x (as oitsim gen and the mesh capture emit). Instances and
  // sub-draws restart primitive ids: their fragments at one pixel are then ordered by
  // depth and colour, deterministic but not necessarily the instances' order.
  std::sort(f.fragments.begin() + static_cast<std::ptrdiff_t>(first), f.fragments.end(),
            [](const Fragment& a, const Fragment& b) {
              if (a.prim != b.prim) return a.prim < b.prim;
              if (a.y != b.y) return a.y < b.y;
              if (a.x != b.x) return a.x < b.x;
              if (a.z != b.z) return a.z < b.z;
              if (a.r != b.r) return a.r < b.r;
              if (a.g != b.g) return a.g < b.g;
              if (a.b != b.b) return a.b < b.b;
              return a.a < b.a;
            });
}

class StreamReader {
 public:
  StreamReader(const std::string& data, const std::string& trace) : d_(data), trace_(trace) {}
  bool done() const { return pos_ >= d_.size(); }
  template <typename T>
  const T* take(uint64_t n = 1) {
    const uint64_t bytes = sizeof(T) * n;
    if (d_.size() - pos_ < bytes)
      throw std::runtime_error(fmt::format("{}: the interposer's stream ends inside a chunk (the retracer stopped "
                                           "while writing it)", trace_));
    const T* p = reinterpret_cast<const T*>(d_.data() + pos_);
    pos_ += bytes;
    return p;
  }
  std::string text(uint32_t n) {
    const char* p = take<char>(n);
    return std::string(p, n);
  }

 private:
  const std::string& d_;
  const std::string& trace_;
  uint64_t pos_ = 0;
};

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
  int status = 0;
  if (!xvfb.empty()) {
    const PrivateXServer x(xvfb);
    status = runRetracer(o, retracer, gl_dir, x.display(), stream_path, log_path);
  } else {
    status = runRetracer(o, retracer, gl_dir, user_display, stream_path, log_path);
  }
  ApitraceResult result;
  result.renderer_log = readFile(log_path);
  const std::string data = readFile(stream_path);
  const std::string log_tail = tail(result.renderer_log, 3);
  auto retracerFailed = [&](const std::string& what) {
    return std::runtime_error(fmt::format("{}: {} {}{}", o.trace, retracer, what,
                                          log_tail.empty() ? "" : "; its last output: " + log_tail));
  };
  if (data.size() < sizeof(st::StreamHeader) || std::memcmp(data.data(), st::kMagic, sizeof st::kMagic) != 0) {
    if (WIFEXITED(status))
      throw retracerFailed(fmt::format("exited with status {} before the interposer started (is {} the "
                                       "interposer, and the trace an OpenGL trace?)", WEXITSTATUS(status),
                                       interposer));
    throw retracerFailed(fmt::format("was killed by signal {}", WTERMSIG(status)));
  }

  StreamReader in(data, o.trace);
  in.take<st::StreamHeader>();
  FrameCapture cur;
  bool have_frame = false;
  std::optional<st::EndChunk> end;
  auto startFrame = [&](uint32_t frame) {
    if (have_frame && cur.frame == frame) return;
    cur = FrameCapture{};
    cur.frame = frame;
    cur.header.version = 2;
    cur.header.encoding = ColourEncoding::Fp32;
    have_frame = true;
  };
  while (!in.done() && !end) {
    const st::ChunkHeader c = *in.take<st::ChunkHeader>();
    switch (c.tag) {
      case st::kDraw: {
        const st::DrawChunk d = *in.take<st::DrawChunk>();
        const st::GpuRecord* recs = in.take<st::GpuRecord>(d.records);
        startFrame(d.frame);
        ++cur.draw_calls;
        if (d.reason == st::kCaptured) {
          addDraw(d, recs, cur);
        } else {
          cur.uncaptured.push_back({d.index, d.reason, std::string(d.function, ::strnlen(d.function, sizeof d.function)),
                                    d.program, d.width, d.height, d.fragments});
        }
        break;
      }
      case st::kVerify: {
        const st::FrameChunk f = *in.take<st::FrameChunk>();
        startFrame(f.frame);
        GlTransparentReference ref;
        ref.width = f.width;
        ref.height = f.height;
        const size_t px = size_t(f.width) * f.height;
        const float* rgba = in.take<float>(px * 4);
        const uint32_t* count = in.take<uint32_t>(px);
        ref.rgba.assign(rgba, rgba + px * 4);
        ref.count.assign(count, count + px);
        cur.reference = std::move(ref);
        break;
      }
      case st::kFrame: {
        const st::FrameChunk f = *in.take<st::FrameChunk>();
        startFrame(f.frame);
        if (f.width == 0 || f.height == 0 || f.width > 65535 || f.height > 65535)
          throw std::runtime_error(fmt::format("{}: frame {}: the application's drawable size {}x{} is unknown or "
                                               "beyond a trace's 65535", o.trace, f.frame, f.width, f.height));
        cur.header.width = f.width;
        cur.header.height = f.height;
        cur.header.fragment_count = cur.fragments.size();
        result.frames.push_back(std::move(cur));
        have_frame = false;
        break;
      }
      case st::kError:
        throw std::runtime_error(fmt::format("{}: {}", o.trace, in.text(c.bytes)));
      case st::kEnd:
        end = *in.take<st::EndChunk>();
        break;
      default:
        throw std::runtime_error(fmt::format("{}: unknown chunk {} in the interposer's stream", o.trace, c.tag));
    }
  }
  if (!end) {
    if (WIFSIGNALED(status)) throw retracerFailed(fmt::format("was killed by signal {}", WTERMSIG(status)));
    throw retracerFailed(fmt::format("stopped without finishing the stream (exit status {})",
                                     WIFEXITED(status) ? WEXITSTATUS(status) : -1));
  }
  if (!end->range_done) {
    const uint32_t frames = end->frames_seen;
    throw std::runtime_error(fmt::format(
        "{}: frame range {}-{} is past the end: the trace has {} frame{} (swap-buffer counts 0-{}){}", o.trace,
        o.first_frame, o.last_frame, frames, frames == 1 ? "" : "s", frames ? frames - 1 : 0,
        frames == 0 ? "; no frame was presented (an EGL trace? the capture replays GLX traces; or the retracer failed: " + log_tail + ")" : ""));
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace oit::capture
