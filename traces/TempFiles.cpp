#include "traces/TempFiles.hpp"

#include <fmt/format.h>
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <charconv>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>

namespace oit {
namespace {

// Fixed slots of heap C strings: the handler only reads them (async-signal-safe
// unlink); a process has a handful of temporaries at a time.
constexpr size_t kSlots = 256;
std::atomic<char*> g_slots[kSlots];
std::atomic<uint64_t> g_seq{0};
std::atomic<int> g_children[kSlots];

void onSignal(int sig) {
  for (auto& child : g_children)
    if (const int pid = child.load(); pid > 0) ::kill(pid, sig);
  for (auto& slot : g_slots)
    if (char* p = slot.load()) ::unlink(p);
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

}  // namespace

void registerTempFile(const std::string& path) {
  char* copy = ::strdup(path.c_str());
  if (!copy) return;
  for (auto& slot : g_slots) {
    char* expected = nullptr;
    if (slot.compare_exchange_strong(expected, copy)) return;
  }
  std::free(copy);  // all slots busy: the file is still removed on normal paths
}

void unregisterTempFile(const std::string& path) {
  for (auto& slot : g_slots) {
    char* p = slot.load();
    if (p && path == p) {
      char* expected = p;
      if (slot.compare_exchange_strong(expected, nullptr)) std::free(p);
      return;
    }
  }
}

void registerChildProcess(int pid) {
  for (auto& child : g_children) {
    int expected = 0;
    if (child.compare_exchange_strong(expected, pid)) return;
  }
}

void unregisterChildProcess(int pid) {
  for (auto& child : g_children) {
    int expected = pid;
    if (child.compare_exchange_strong(expected, 0)) return;
  }
}

void removeTempFilesOnSignals() {
  static bool installed = false;
  if (installed) return;
  installed = true;
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) std::signal(sig, onSignal);
}

TempFile::TempFile(std::string path) : path_(std::move(path)) {
  if (!path_.empty()) registerTempFile(path_);
}

void TempFile::keep() {
  if (!path_.empty()) unregisterTempFile(path_);
  path_.clear();
}

TempFile::~TempFile() {
  if (path_.empty()) return;
  std::error_code ignored;
  std::filesystem::remove(path_, ignored);
  unregisterTempFile(path_);
}

bool processGone(int pid) { return pid > 0 && ::kill(pid, 0) != 0 && errno == ESRCH; }

int pidAfterPrefix(std::string_view name, std::string_view prefix) {
  if (!name.starts_with(prefix)) return 0;
  name.remove_prefix(prefix.size());
  int pid = 0;
  const auto [end, ec] = std::from_chars(name.data(), name.data() + name.size(), pid);
  if (ec != std::errc() || end == name.data() || pid <= 0) return 0;
  return end == name.data() + name.size() || *end == '.' ? pid : 0;
}

size_t removeAbandoned(const std::string& dir, const std::function<int(std::string_view name)>& pidOf) {
  namespace fs = std::filesystem;
  std::error_code ec;
  size_t removed = 0;
  fs::directory_iterator it(dir.empty() ? fs::path(".") : fs::path(dir), ec);
  for (; !ec && it != fs::directory_iterator(); it.increment(ec)) {
    const std::string name = it->path().filename().string();
    const int pid = pidOf(name);
    if (pid == 0 || pid == ::getpid() || !processGone(pid)) continue;
    std::error_code rm;
    if (it->is_regular_file(rm) && fs::remove(it->path(), rm)) ++removed;
  }
  return removed;
}

std::string tempPathNextTo(const std::string& path) {
  // What a writer of this path killed outright (kill -9) left behind: its
  // "<name>.tmp.<pid>.<n>" (or, for long names, ".oitsim.tmp.<pid>.<n>").
  const std::filesystem::path target(path);
  const std::string own = target.filename().string() + ".tmp.";
  removeAbandoned(target.parent_path().string(), [&](std::string_view name) {
    if (const int pid = pidAfterPrefix(name, own)) return pid;
    return pidAfterPrefix(name, ".oitsim.tmp.");
  });
  const std::string suffix = fmt::format(".tmp.{}.{}", ::getpid(), g_seq.fetch_add(1));
  const std::filesystem::path p(path);
  if (p.filename().string().size() + suffix.size() <= 255) return path + suffix;
  return (p.parent_path() / (".oitsim" + suffix)).string();
}

}  // namespace oit
