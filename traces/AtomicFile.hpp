// A file that appears at its path only when complete: written (buffered) to a
// temporary file in the same directory, then renamed over the path on commit().
// Without commit() the destructor removes the temporary file.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace oit::detail {

class AtomicFile {
 public:
  // Creates "<path>.tmp.<pid>.<n>". Throws TraceError naming path if it cannot.
  explicit AtomicFile(std::string path, size_t buffer_bytes = size_t{1} << 20);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  // At least n contiguous writable bytes (n <= buffer size); finish with advance(n).
  unsigned char* space(size_t n) {
    if (buf_bytes_ - used_ < n) flush();
    return buf_.get() + used_;
  }
  void advance(size_t n) { used_ += n; }
  void append(const void* data, size_t n);

  // Bytes appended so far (flushed or not).
  uint64_t size() const { return flushed_ + used_; }
  // Overwrites bytes already appended (flushes first).
  void patch(uint64_t offset, const void* data, size_t n);
  // Flushes, closes and renames the temporary file to path. Once only.
  void commit();
  bool committed() const { return committed_; }

  const std::string& path() const { return path_; }
  const std::string& tempPath() const { return tmp_; }

 private:
  void flush();
  [[noreturn]] void fail(const std::string& what);
  void discard() noexcept;

  std::string path_;
  std::string tmp_;
  int fd_ = -1;
  // Not zero-filled: only written bytes are read, and zeroing 1 MiB faults in
  // every page of it at each open (a fuzzer's whole budget for a tiny trace).
  std::unique_ptr<unsigned char[]> buf_;
  size_t buf_bytes_ = 0;
  size_t used_ = 0;
  uint64_t flushed_ = 0;
  bool committed_ = false;
};

}  // namespace oit::detail
