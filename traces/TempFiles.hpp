// Temporary files of the process (atomic writers' "<path>.tmp.<pid>.<n>" and
// staged outputs): registered while they exist, so an interrupt (SIGINT,
// SIGTERM, SIGHUP) removes them before the process dies by the signal instead
// of leaving partial files behind. What a process killed outright leaves, the
// next writer into the same folder removes (removeAbandoned).
#pragma once

#include <functional>
#include <string>
#include <string_view>

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
// Every atomic writer (traces, reports, images) takes its name here, so this
// is where the temporaries of this path's earlier writers that were killed
// outright are removed (removeAbandoned: only those whose process is gone).
std::string tempPathNextTo(const std::string& path);

// Whether no process `pid` exists on this machine (kill(pid, 0) fails with
// ESRCH). A pid that was reused counts as alive: the caller keeps its files.
bool processGone(int pid);

// Temporary files that a process killed outright (kill -9, a crash, a power
// cut: no signal handler runs) left in `dir`. pidOf(name) returns the pid of
// the process that wrote a file of that name, or 0 when the name is not one of
// the caller's temporaries. Removes those whose process is gone and returns how
// many it removed; errors (a folder that cannot be read) remove nothing.
size_t removeAbandoned(const std::string& dir, const std::function<int(std::string_view name)>& pidOf);

// The pid in "<prefix><pid>" or "<prefix><pid>.<rest>", 0 otherwise.
int pidAfterPrefix(std::string_view name, std::string_view prefix);

}  // namespace oit
