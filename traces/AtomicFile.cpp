#include "traces/AtomicFile.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>

#include "traces/TempFiles.hpp"
#include "traces/TraceIO.hpp"

namespace oit::detail {


AtomicFile::AtomicFile(std::string path, size_t buffer_bytes)
    : path_(std::move(path)), buf_(std::make_unique_for_overwrite<unsigned char[]>(buffer_bytes)), buf_bytes_(buffer_bytes) {

  // pid + sequence: concurrent writers (other processes, other threads) never
  // share a temporary file; O_EXCL guarantees it.
  tmp_ = tempPathNextTo(path_);
  fd_ = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  if (fd_ < 0)
    throw TraceError(path_, fmt::format("cannot create temporary file {}: {}", tmp_,
                                        std::strerror(errno)));
  registerTempFile(tmp_);
}

AtomicFile::~AtomicFile() {
  if (!committed_) discard();
}

void AtomicFile::discard() noexcept {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  ::unlink(tmp_.c_str());
  unregisterTempFile(tmp_);
}

void AtomicFile::fail(const std::string& what) {
  const std::string msg = fmt::format("{} temporary file {}: {}", what, tmp_, std::strerror(errno));
  throw TraceError(path_, msg);
}

void AtomicFile::append(const void* data, size_t n) {
  const auto* p = static_cast<const unsigned char*>(data);
  while (n > 0) {
    if (used_ == buf_bytes_) flush();
    const size_t k = std::min(n, buf_bytes_ - used_);
    std::memcpy(buf_.get() + used_, p, k);
    used_ += k;
    p += k;
    n -= k;
  }
}

void AtomicFile::flush() {
  if (fd_ < 0) {
    errno = EBADF;
    fail("cannot write (already committed)");
  }
  size_t done = 0;
  while (done < used_) {
    const ssize_t k = ::write(fd_, buf_.get() + done, used_ - done);
    if (k < 0) {
      if (errno == EINTR) continue;
      fail("cannot write");
    }
    done += static_cast<size_t>(k);
  }
  flushed_ += used_;
  used_ = 0;
}

void AtomicFile::patch(uint64_t offset, const void* data, size_t n) {
  flush();
  const auto* p = static_cast<const unsigned char*>(data);
  size_t done = 0;
  while (done < n) {
    const ssize_t k = ::pwrite(fd_, p + done, n - done, static_cast<off_t>(offset + done));
    if (k < 0) {
      if (errno == EINTR) continue;
      fail("cannot write");
    }
    done += static_cast<size_t>(k);
  }
}

void AtomicFile::commit() {
  if (committed_) return;
  flush();
  const int fd = fd_;
  fd_ = -1;
  // close() can report a deferred write error (NFS, quota): check it.
  if (::close(fd) != 0) fail("cannot close");
  if (std::rename(tmp_.c_str(), path_.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp_.c_str());
    errno = err;
    unregisterTempFile(tmp_);
    throw TraceError(path_, fmt::format("cannot rename temporary file {} to the trace path: {}",
                                        tmp_, std::strerror(err)));
  }
  unregisterTempFile(tmp_);
  committed_ = true;
}

}  // namespace oit::detail
