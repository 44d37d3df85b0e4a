#include "traces/TempFiles.hpp"

#include <fmt/format.h>
#include <signal.h>
#include <unistd.h>

#include <atomic>
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

std::string tempPathNextTo(const std::string& path) {
  const std::string suffix = fmt::format(".tmp.{}.{}", ::getpid(), g_seq.fetch_add(1));
  const std::filesystem::path p(path);
  if (p.filename().string().size() + suffix.size() <= 255) return path + suffix;
  return (p.parent_path() / (".oitsim" + suffix)).string();
}

}  // namespace oit
