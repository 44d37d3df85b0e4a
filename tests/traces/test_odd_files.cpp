// Inputs that are not ordinary trace files: FIFOs, devices and folders are
// refused at once (never a hang, never reading without end), an endless CSV
// line is refused with its line number, and a trace that shrinks while it is
// read is one TraceError ("the trace changed while it was read"), never a
// SIGBUS.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <future>

#include "test_format_helpers.hpp"
#include "traces/InputFile.hpp"
#include "traces/MappedCopy.hpp"
#include "traces/TraceFormat.hpp"
#include "traces/gen/Mesh.hpp"

namespace oit::test {
namespace {

using namespace std::chrono_literals;

// Runs f on another thread and fails (instead of hanging the suite) when it
// does not finish within 10 s. f returns the error message it expects.
std::string withinSeconds(std::function<std::string()> f) {
  auto done = std::async(std::launch::async, std::move(f));
  if (done.wait_for(10s) != std::future_status::ready) {
    ADD_FAILURE() << "did not return within 10 s (blocked?)";
    std::_Exit(1);  // the blocked thread cannot be joined
  }
  return done.get();
}

TEST(OddFiles, FifoAsTraceFailsAtOnceBinaryAndCsv) {
  TempDir dir;
  for (const char* name : {"f.oitt", "f.csv"}) {
    const std::string p = dir.path(name);
    ASSERT_EQ(::mkfifo(p.c_str(), 0600), 0);
    // No writer ever opens the FIFO: a blocking open would wait forever.
    const std::string e = withinSeconds([&] { return traceErrorOf([&] { openTrace(p, {.width = 4, .height = 4}); }); });
    EXPECT_EQ(e, p + ": is a FIFO (named pipe), not a regular file");
  }
}

TEST(OddFiles, DeviceAndFolderAsTraceAreRefusedByName) {
  TempDir dir;
  for (const std::string& p : {std::string("/dev/zero"), std::string("/dev/null")}) {
    EXPECT_EQ(traceErrorOf([&] { openTrace(p); }), p + ": is a character device, not a regular file");
  }
  // /dev/zero named .csv grew memory at 1.2 GB/s: a symlink gives it the name.
  const std::string zero_csv = dir.path("zero.csv");
  ASSERT_EQ(::symlink("/dev/zero", zero_csv.c_str()), 0);
  EXPECT_EQ(traceErrorOf([&] { openTrace(zero_csv, {.width = 4, .height = 4}); }),
            zero_csv + ": is a character device, not a regular file");
  const std::string folder = dir.path("t.csv");
  std::filesystem::create_directory(folder);
  EXPECT_EQ(traceErrorOf([&] { openTrace(folder); }), folder + ": is a directory, not a regular file");
  EXPECT_EQ(traceErrorOf([&] { openTrace(""); }), "'': expected a trace file, got an empty path");
}

TEST(OddFiles, InputFileNamesEveryKind) {
  TempDir dir;
  const std::string fifo = dir.path("p");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(withinSeconds([&] { return openInputFile(fifo).problem; }), "is a FIFO (named pipe), not a regular file");
  EXPECT_EQ(openInputFile(dir.path("")).problem, "is a directory, not a regular file");
  const InputFile missing = openInputFile(dir.path("none"));
  EXPECT_EQ(missing.problem, "cannot open: No such file or directory");
  EXPECT_EQ(missing.error, ENOENT);
  const std::string small = dir.path("small.json");
  writeFile(small, "{\"a\": 1}");
  EXPECT_EQ(readInputFile(small, "config", 100), "{\"a\": 1}");
  try {
    readInputFile(small, "config", 4);
    ADD_FAILURE() << "a file over the limit was read";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "config " + small + ": is 8 bytes, expected at most 4 (is this the right file?)");
  }
}

TEST(OddFiles, MeshFromFifoOrDeviceIsRefused) {
  TempDir dir;
  const std::string fifo = dir.path("m.obj");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string e = withinSeconds([&] {
    try {
      gen::loadMesh(fifo);
    } catch (const std::runtime_error& err) {
      return std::string(err.what());
    }
    return std::string("no error");
  });
  EXPECT_EQ(e, "mesh file '" + fifo + "': is a FIFO (named pipe), not a regular file");
}

// A CSV line has at most kMaxCsvLineBytes bytes: a file without line ends
// (or one runaway line) is refused at that line instead of read into memory.
TEST(OddFiles, OverlongCsvLineIsRefusedWithItsLineNumber) {
  TempDir dir;
  const std::string p = dir.path("long.csv");
  const std::string head = "# width 4\n# height 4\ndraw,prim,x,y,z,r,g,b,a,opaque\n0,0,0,0,0.5,1,1,1,0.5,0\n";
  // Line 5 is a comment of kMaxCsvLineBytes + 1 bytes.
  writeFile(p, head + "#" + std::string(format_v1::kMaxCsvLineBytes, 'x') + "\n0,0,1,1,0.5,1,1,1,0.5,0\n");
  EXPECT_EQ(traceErrorOf([&] { openTrace(p); }),
            p + ": line 5, byte offset " + std::to_string(head.size()) +
                ": line is longer than 65536 bytes, the most a CSV trace line may have (FORMAT.md section 8.2); is "
                "this a CSV trace?");
  // Exactly the limit is fine (a free comment).
  writeFile(p, head + "#" + std::string(format_v1::kMaxCsvLineBytes - 1, 'x') + "\n0,0,1,1,0.5,1,1,1,0.5,0\n");
  EXPECT_EQ(readAll(p).fragments.size(), 2u);
  // No line end at all: refused at line 1 after at most one buffer.
  writeFile(p, std::string(3 * format_v1::kMaxCsvLineBytes, '0'));
  EXPECT_TRUE(contains(traceErrorOf([&] { openTrace(p); }), {p + ": line 1, byte offset 0: line is longer"}));
}

TraceHeader oneDraw(ColourEncoding enc) {
  return makeHeader(64, 64, enc, {{0, DrawClass::Transparent, "t"}});
}

// The trace is cut while it is read, at several places: inside a later
// batch, inside the last page (those bytes would read as zeros, no SIGBUS),
// and to nothing. The next read is one TraceError naming the change.
TEST(OddFiles, BinaryTraceShrunkUnderTheReaderIsOneError) {
  for (ColourEncoding enc : {ColourEncoding::Fp32, ColourEncoding::Unorm8}) {
    for (uint64_t keep_records : {uint64_t{1000}, uint64_t{9999}, uint64_t{0}}) {
      TempDir dir;
      const std::string p = dir.path("t.oitt");
      writeTrace(p, oneDraw(enc), makeFragments(10000, 64, 64, {0}));
      const uint64_t record = enc == ColourEncoding::Fp32 ? 32 : 20;
      auto src = openTrace(p, {.batch_records = 256});
      ASSERT_EQ(src->next().size(), 256u);
      ASSERT_EQ(::truncate(p.c_str(), off_t(128 + keep_records * record)), 0);
      const std::string e = traceErrorOf([&] {
        while (!src->next().empty()) {
        }
      });
      EXPECT_TRUE(contains(e, {p + ": byte offset ", "the trace changed while it was read: it is now " +
                                                         std::to_string(128 + keep_records * record) + " bytes, it was " +
                                                         std::to_string(128 + 10000 * record) + " bytes when opened"}))
          << toString(enc) << " " << keep_records;
    }
  }
}

TEST(OddFiles, CsvTraceShrunkUnderTheReaderIsOneError) {
  TempDir dir;
  const std::string p = dir.path("t.csv");
  writeTrace(p, oneDraw(ColourEncoding::Fp32), makeFragments(1000, 64, 64, {0}));
  auto src = openTrace(p, {.batch_records = 100});
  ASSERT_EQ(src->next().size(), 100u);
  ASSERT_EQ(::truncate(p.c_str(), off_t(std::filesystem::file_size(p) / 2)), 0);
  EXPECT_TRUE(contains(traceErrorOf([&] {
                         while (!src->next().empty()) {
                         }
                       }),
                       {p + ": line ", "the trace changed while it was read: it is now "}));
}

// The guarded copy itself: reading pages of a mapping past the end of its
// (since truncated) file returns false where a plain read dies of SIGBUS.
TEST(OddFiles, CopyFromATruncatedMappingReturnsFalse) {
  TempDir dir;
  const std::string p = dir.path("m");
  const size_t page = size_t(::sysconf(_SC_PAGESIZE));
  writeFile(p, std::string(4 * page, 'a'));
  const int fd = ::open(p.c_str(), O_RDONLY);
  ASSERT_GE(fd, 0);
  void* m = ::mmap(nullptr, 4 * page, PROT_READ, MAP_SHARED, fd, 0);
  ::close(fd);
  ASSERT_NE(m, MAP_FAILED);
  std::vector<char> dst(4 * page);
  EXPECT_TRUE(detail::copyFromMapping(dst.data(), m, 4 * page));
  EXPECT_EQ(dst[4 * page - 1], 'a');
  ASSERT_EQ(::truncate(p.c_str(), off_t(page)), 0);
  EXPECT_TRUE(detail::copyFromMapping(dst.data(), m, page));  // the first page is still in the file
  EXPECT_FALSE(detail::copyFromMapping(dst.data(), static_cast<char*>(m) + page, page));
  EXPECT_FALSE(detail::copyFromMapping(dst.data(), m, 2 * page));
  ::munmap(m, 4 * page);
}

}  // namespace
}  // namespace oit::test
