// Opening an input file so that reading it can neither hang nor run without end.
// Every reader of oitsim (traces, meshes, config files, sweep specs, reference
// images) opens its input here:
//  - the path is checked with stat() first, so a FIFO, a device, a socket or a
//    folder is refused by name before it is opened (opening a device can have
//    effects; /dev/zero never ends);
//  - open() is non-blocking (a FIFO swapped in after the check would otherwise
//    block open() until a writer appears), and fstat() of the opened file is
//    checked again. O_NONBLOCK has no effect on reads of a regular file.
#pragma once

#include <cstdint>
#include <string>

namespace oit {

// An owned file descriptor, closed on destruction.
class FileDescriptor {
 public:
  FileDescriptor() = default;
  explicit FileDescriptor(int fd) : fd_(fd) {}
  FileDescriptor(FileDescriptor&& o) noexcept : fd_(o.fd_) { o.fd_ = -1; }
  FileDescriptor& operator=(FileDescriptor&& o) noexcept;
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  ~FileDescriptor();
  int get() const { return fd_; }
  explicit operator bool() const { return fd_ >= 0; }
  // Gives up ownership (the caller closes it).
  int release() {
    const int fd = fd_;
    fd_ = -1;
    return fd;
  }

 private:
  int fd_ = -1;
};

// A regular file opened for reading (O_RDONLY | O_CLOEXEC), or why not.
struct InputFile {
  FileDescriptor fd;
  uint64_t size = 0;  // at open
  // Empty when open; else what is wrong, without the path, e.g. "cannot open:
  // No such file or directory" or "is a FIFO (named pipe), not a regular file".
  std::string problem;
  int error = 0;  // errno of the failed open() or stat(); 0 for a path that is not a regular file
  explicit operator bool() const { return problem.empty(); }
};
InputFile openInputFile(const std::string& path);

// The rest of an open input file, at most max_bytes. Returns false with
// `problem` set (no path) on a read error or a file larger than max_bytes.
bool readAll(const InputFile& f, uint64_t max_bytes, std::string& out, std::string& problem);

// What a file of this st_mode is, for messages: "a FIFO (named pipe)",
// "a character device", "a directory", ...
std::string fileKind(unsigned mode);

// The whole content of a small regular input file (a config file, a sweep
// spec). Throws std::runtime_error "<role> <path>: <problem>", also when the
// file is larger than max_bytes.
std::string readInputFile(const std::string& path, const std::string& role, uint64_t max_bytes);

}  // namespace oit
