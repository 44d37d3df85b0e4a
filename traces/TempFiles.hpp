// Temporary files of the process (atomic writers' "<path>.tmp.<pid>.<n>" and
// staged outputs): registered while they exist, so an interrupt (SIGINT,
// SIGTERM, SIGHUP) removes them before the process dies by the signal instead
// of leaving partial files behind.
#pragma once

#include <string>

namespace oit {

void registerTempFile(const std::string& path);
void unregisterTempFile(const std::string& path);
// Child processes (a sweep's points): the same signal is passed on to them first,
// so interrupting the parent alone does not leave them running.
void registerChildProcess(int pid);
void unregisterChildProcess(int pid);
// Installs the handlers (once; the CLI's main calls it).
void removeTempFilesOnSignals();

// A registered temporary file: removed (and unregistered) when destroyed unless
// keep() was called, e.g. after it was renamed to its final path. An empty path
// holds nothing.
class TempFile {
 public:
  explicit TempFile(std::string path = {});
  TempFile(TempFile&& other) noexcept : path_(std::move(other.path_)) { other.path_.clear(); }
  TempFile& operator=(TempFile&&) = delete;
  TempFile(const TempFile&) = delete;
  ~TempFile();
  const std::string& path() const { return path_; }
  void keep();

 private:
  std::string path_;
};

// A temporary name next to `path` for an atomic write: "<path>.tmp.<pid>.<n>",
// or "<dir>/.oitsim.tmp.<pid>.<n>" when that would exceed the file-name limit.
std::string tempPathNextTo(const std::string& path);

}  // namespace oit
