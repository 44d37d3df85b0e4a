// The fuzzers feed the real readers, which open files by path (and refuse
// anything but a regular file): each input is written to one file per process,
// on /dev/shm when it is there (memory, no disk wear), else in $TMPDIR or /tmp.
#pragma once

#include <fcntl.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <string>

namespace oit::fuzz {

class FuzzFile {
 public:
  // `suffix` picks the reader where the extension does (".csv", ".oitt", ".json").
  explicit FuzzFile(const std::string& suffix) {
    const char* tmp = std::getenv("TMPDIR");
    const std::string dir = ::access("/dev/shm", W_OK) == 0 ? "/dev/shm" : (tmp && *tmp ? tmp : "/tmp");
    path_ = dir + "/oitsim-fuzz-" + std::to_string(::getpid()) + suffix;
    fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
    if (fd_ < 0) std::abort();
  }
  ~FuzzFile() {
    ::close(fd_);
    ::unlink(path_.c_str());
  }
  // Replaces the file's content.
  const std::string& write(const uint8_t* data, size_t size) {
    if (::ftruncate(fd_, 0) != 0) std::abort();
    size_t done = 0;
    while (done < size) {
      const ssize_t k = ::pwrite(fd_, data + done, size - done, off_t(done));
      if (k <= 0) std::abort();
      done += size_t(k);
    }
    return path_;
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  int fd_ = -1;
};

}  // namespace oit::fuzz
