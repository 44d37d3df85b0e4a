#include "traces/InputFile.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace oit {

FileDescriptor& FileDescriptor::operator=(FileDescriptor&& o) noexcept {
  if (this != &o) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = o.fd_;
    o.fd_ = -1;
  }
  return *this;
}

FileDescriptor::~FileDescriptor() {
  if (fd_ >= 0) ::close(fd_);
}

std::string fileKind(unsigned mode) {
  switch (mode & S_IFMT) {
    case S_IFREG: return "a regular file";
    case S_IFDIR: return "a directory";
    case S_IFIFO: return "a FIFO (named pipe)";
    case S_IFCHR: return "a character device";
    case S_IFBLK: return "a block device";
    case S_IFSOCK: return "a socket";
    case S_IFLNK: return "a symbolic link";
  }
  return "not a regular file";
}

namespace {

std::string notRegular(unsigned mode) { return fmt::format("is {}, not a regular file", fileKind(mode)); }

}  // namespace

InputFile openInputFile(const std::string& path) {
  InputFile f;
  if (path.empty()) {
    f.problem = "empty path: expected a file name";
    return f;
  }
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    f.error = errno;
    f.problem = fmt::format("cannot open: {}", std::strerror(errno));
    return f;
  }
  if (!S_ISREG(st.st_mode)) {
    f.problem = notRegular(st.st_mode);
    return f;
  }
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) {
    f.error = errno;
    f.problem = fmt::format("cannot open: {}", std::strerror(errno));
    return f;
  }
  f.fd = FileDescriptor(fd);
  // The path may have been replaced between stat() and open().
  if (::fstat(fd, &st) != 0) {
    f.error = errno;
    f.problem = fmt::format("cannot stat: {}", std::strerror(errno));
  } else if (!S_ISREG(st.st_mode)) {
    f.problem = notRegular(st.st_mode);
  } else {
    f.size = static_cast<uint64_t>(st.st_size);
    return f;
  }
  f.fd = FileDescriptor();
  return f;
}

bool readAll(const InputFile& f, uint64_t max_bytes, std::string& out, std::string& problem) {
  out.clear();
  if (f.size > max_bytes) {
    problem = fmt::format("is {} bytes, expected at most {} (is this the right file?)", f.size, max_bytes);
    return false;
  }
  char buf[65536];
  for (;;) {
    const ssize_t n = ::read(f.fd.get(), buf, sizeof buf);
    if (n < 0) {
      if (errno == EINTR) continue;
      problem = fmt::format("read error: {}", std::strerror(errno));
      return false;
    }
    if (n == 0) return true;
    out.append(buf, static_cast<size_t>(n));
    if (out.size() > max_bytes) {
      problem = fmt::format("is more than {} bytes (it grew while it was read)", max_bytes);
      return false;
    }
  }
}

std::string readInputFile(const std::string& path, const std::string& role, uint64_t max_bytes) {
  InputFile f = openInputFile(path);
  std::string text, problem = f.problem;
  if (!f || !readAll(f, max_bytes, text, problem))
    throw std::runtime_error(fmt::format("{} {}: {}", role, path, problem));
  return text;
}

}  // namespace oit
