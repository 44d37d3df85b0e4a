// `oitsim run` at the edges, end to end (issue 24): odd files as the trace fail
// at once, the reference can be skipped or read from a file, memory is checked
// against a budget before any work (with an estimate that covers the measured
// peak), an allocation failure is one line, and a run killed outright leaves
// nothing that the next run into the same folder does not remove.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <thread>

#include "CliRunner.hpp"

namespace oit::test {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kAddressSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kAddressSanitizer = true;
#else
constexpr bool kAddressSanitizer = false;
#endif
#else
constexpr bool kAddressSanitizer = false;
#endif

// A glass trace without opaque draws (an A-buffer's pool is then known
// exactly), shared by the tests of this file.
struct CliReliabilityTrace {
  static constexpr const char* kFolder = "cli_reliability";
  static constexpr const char* kFile = "glass.oitt";
  static constexpr const char* kGen = "gen glass --width 96 --height 64";
};
class CliReliability : public GeneratedTraceSuite<CliReliabilityTrace> {};

// Exit code and output of `oitsim args`, failing the test instead of hanging
// when it does not end within `limit`.
CliResult runWithin(const std::string& args, std::chrono::seconds limit) {
  return runShell("timeout -s KILL " + std::to_string(limit.count()) + " " + oitsimPath() + " " + args);
}

std::vector<std::string> outputLines(const CliResult& r) {
  std::vector<std::string> out;
  for (const std::string& l : lines(r.output))
    if (!l.empty()) out.push_back(l);
  return out;
}

TEST_F(CliReliability, FifoAndDeviceAsTraceFailAtOnceWithOneLine) {
  TempDir dir("odd_traces");
  for (const char* name : {"f.oitt", "f.csv"}) {
    const std::string fifo = dir.file(name);
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    for (const std::string& cmd : {"info " + fifo, "run -q --trace " + fifo + " --out " + dir.file("out") +
                                                       " --width 8 --height 8"}) {
      const CliResult r = runWithin(cmd, 20s);
      EXPECT_EQ(r.exit_code, 1) << cmd << "\n" << r.output;  // timeout's SIGKILL would be -1
      EXPECT_EQ(outputLines(r), std::vector<std::string>{"oitsim: error: " + fifo +
                                                         ": is a FIFO (named pipe), not a regular file"})
          << cmd;
    }
  }
  const std::string zero = dir.file("zero.csv");
  ASSERT_EQ(::symlink("/dev/zero", zero.c_str()), 0);
  const CliResult r = runWithin("info " + zero + " --width 8 --height 8", 20s);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(outputLines(r),
            std::vector<std::string>{"oitsim: error: " + zero + ": is a character device, not a regular file"});
  EXPECT_FALSE(fs::exists(dir.file("out")));
}

TEST_F(CliReliability, UnclearMessagesNowNameTheOptionOrFile) {
  TempDir dir("messages");
  const std::string out = dir.file("out");
  const std::string bogus = dir.file("bogus.json");
  writeText(bogus, R"({"preset": "bogus"})");
  const struct {
    std::string args, message;
  } cases[] = {
      {"--trace ''", "oitsim: error: --trace: expected a trace file (.oitt or .csv), got an empty path"},
      {"--trace " + trace_ + " --config ''", "oitsim: error: --config: expected a JSON file, got an empty path"},
      {"--trace " + trace_ + " --config " + dir.path().string(),
       "oitsim: error: " + dir.path().string() + ": is a directory, not a regular file (expected a JSON config file)"},
      {"--trace " + trace_ + " --config " + bogus,
       "oitsim: error: " + bogus + ": key 'preset': unknown preset 'bogus'; known presets: iris-pro-5200, titan-x-maxwell, navi21 (aliases: igpu = iris-pro-5200, dgpu = titan-x-maxwell)"},
      {"--trace " + trace_ + " --reference ''",
       "oitsim: error: --reference: expected abuffer, none or a PFM file, got an empty value"},
      {"--trace " + trace_ + " --memory-budget 12X",
       "oitsim: error: --memory-budget 12X: expected bytes with an optional unit (512M, 8G, 1.5GiB; K, M, G, T are "
       "powers of 1024) or a share of physical memory (60%)"},
  };
  for (const auto& c : cases) {
    const CliResult r = runOitsim("run -q --mode functional --out " + out + " " + c.args);
    EXPECT_EQ(r.exit_code, 1) << c.args;
    EXPECT_EQ(outputLines(r), std::vector<std::string>{c.message}) << c.args;
  }
  EXPECT_EQ(runOitsim("info ''").output, "oitsim: error: '': expected a trace file, got an empty path\n");
}

TEST_F(CliReliability, ReferenceNoneWritesNoReferenceAndSaysSo) {
  const std::string out = dir_->file("none");
  const CliResult r = runOitsim("run --mode functional --algo mlab --reference none --trace " + trace_ + " --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("image       no reference (--reference none): no error metrics"), std::string::npos)
      << r.output;
  EXPECT_TRUE(fs::exists(out + "/image.png"));
  EXPECT_TRUE(fs::exists(out + "/image.pfm"));
  EXPECT_FALSE(fs::exists(out + "/reference.pfm"));
  EXPECT_FALSE(fs::exists(out + "/diff.png"));
  const nlohmann::json j = readJson(out + "/report.json");
  EXPECT_EQ(j["image"]["reference"], "none");
  EXPECT_FALSE(j["image"].contains("metrics"));
  EXPECT_EQ(j["image"]["files"], (nlohmann::json{{"image_png", "image.png"}, {"image_pfm", "image.pfm"}}));
  EXPECT_EQ(j["sim"]["memory"]["reference_bands"], 0);
}

// An earlier run's reference.pfm as --reference gives the same metrics as the
// exact reference it is (bit for bit), and a file of another size is refused
// before any work.
TEST_F(CliReliability, ReferenceFileGivesTheMetricsOfTheReferenceItHolds) {
  const std::string exact = dir_->file("exact"), from_file = dir_->file("from_file");
  ASSERT_EQ(runOitsim("run -q --mode functional --algo hybrid --trace " + trace_ + " --out " + exact).exit_code, 0);
  const std::string ref = dir_->file("kept_reference.pfm");
  fs::copy_file(exact + "/reference.pfm", ref, fs::copy_options::overwrite_existing);
  const CliResult r = runOitsim("run -q --mode functional --algo hybrid --trace " + trace_ + " --out " + from_file +
                                " --reference " + ref);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json a = readJson(exact + "/report.json"), b = readJson(from_file + "/report.json");
  EXPECT_EQ(a["image"]["reference"], "abuffer");
  EXPECT_EQ(b["image"]["reference"], "file");
  EXPECT_EQ(b["image"]["reference_file"], ref);
  EXPECT_EQ(a["image"]["metrics"], b["image"]["metrics"]);
  EXPECT_EQ(readText(exact + "/reference.pfm"), readText(from_file + "/reference.pfm"));

  TempDir other("other_size");
  const std::string small = other.file("small.oitt");
  ASSERT_EQ(runOitsim("gen glass --width 128 --height 96 -o " + small).exit_code, 0);
  const CliResult wrong = runOitsim("run -q --trace " + small + " --out " + other.file("o") + " --reference " + ref);
  EXPECT_EQ(wrong.exit_code, 1);
  EXPECT_EQ(outputLines(wrong), std::vector<std::string>{"oitsim: error: --reference " + ref +
                                                         ": is a 96 x 64 image, the trace's frame is 128 x 96"});
  // The run's own output folder's reference.pfm would be replaced by the run.
  const CliResult own = runOitsim("run -q --trace " + trace_ + " --out " + exact + " --reference " + exact +
                                  "/reference.pfm");
  EXPECT_EQ(own.exit_code, 1);
  EXPECT_NE(own.output.find("which this run replaces; copy it out of the --out folder first"), std::string::npos)
      << own.output;
  EXPECT_TRUE(fs::exists(exact + "/reference.pfm"));  // refused before the folder is touched
}

// A 16384 x 16384 A-buffer frame: the images and FLIP's planes alone need
// about 110 B per pixel (26 GiB); against an 8 GiB budget it is refused
// before any work, naming the frame, the algorithm, the memory and the budget.
TEST_F(CliReliability, AFrameOverTheBudgetIsRefusedBeforeAnyWork) {
  TempDir dir("budget");
  const std::string trace = dir.file("huge.csv");
  writeText(trace, "# width 16384\n# height 16384\ndraw,prim,x,y,z,r,g,b,a,opaque\n0,0,1,1,0.5,1,0,0,0.5,0\n");
  const auto t0 = std::chrono::steady_clock::now();
  const CliResult r = runOitsim("run -q --algo abuffer --memory-budget 8G --trace " + trace + " --out " + dir.file("o"));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(r.exit_code, 1);
  ASSERT_EQ(outputLines(r).size(), 1u) << r.output;
  EXPECT_EQ(r.output.rfind("oitsim: error: " + trace + ": a 16384 x 16384 frame with abuffer needs about ", 0), 0u)
      << r.output;
  EXPECT_NE(r.output.find("GiB at its peak (flip), more than the memory budget of 8.00 GiB (--memory-budget 8G); "
                          "--reference none skips the reference and the metrics; nothing was run"),
            std::string::npos)
      << r.output;
  EXPECT_LT(seconds, 10.0) << "refused only after work";
  EXPECT_FALSE(fs::exists(dir.file("o")));
  // Without the reference the frame is its state and its image: 4 + 16 + 12
  // B per pixel, 8 GiB, still more than 4G.
  const CliResult none =
      runOitsim("run -q --algo abuffer --reference none --memory-budget 4G --trace " + trace + " --out " + dir.file("o"));
  EXPECT_EQ(none.exit_code, 1);
  EXPECT_NE(none.output.find("at its peak (render), more than the memory budget of 4.00 GiB"), std::string::npos)
      << none.output;
}

// Peak resident set of a child running `oitsim args`, from wait4().
uint64_t peakRss(const std::string& args, int& exit_code) {
  const pid_t pid = fork();
  if (pid == 0) {
    const std::string cmd = oitsimPath() + " " + args + " >/dev/null 2>&1";
    execl("/bin/sh", "sh", "-c", ("exec " + cmd).c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  int status = 0;
  struct rusage ru {};
  wait4(pid, &status, 0, &ru);
  exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return uint64_t(ru.ru_maxrss) * 1024;
}

// The pre-check's estimate against the real peak of 1024 x 512 runs (the
// per-pixel buffers, tens of MiB, well above the process's own ~12 MiB):
// never below it, at most 20 % above. Each configuration stresses another
// phase: the render (mlab k=8's 160 B per pixel), the reference, the metrics,
// the A-buffer under test, the timing model's tables (with the shared levels,
// and without them, where the tables that grow with the state are the render's
// largest term: 242 MiB against 194 estimated at 1280 x 720 before they were
// counted).
TEST_F(CliReliability, EstimateCoversTheMeasuredPeak) {
  if (kAddressSanitizer) GTEST_SKIP() << "AddressSanitizer's shadow memory and quarantine change the resident set";
  TempDir dir("estimate");
  const std::string trace = dir.file("g.oitt");
  ASSERT_EQ(runOitsim("gen glass --width 1024 --height 512 -o " + trace).exit_code, 0);
  for (const std::string& config :
       {std::string("--mode functional --algo mlab -k 8 --reference none"), std::string("--mode functional --algo alpha"),
        std::string("--mode functional --algo abuffer"), std::string("--mode timing --algo mlab"),
        std::string("--mode timing --algo alpha --reference none"),
        std::string("--mode timing --algo mlab -k 8 --reference none --set l2.size_bytes=0 --set l3.size_bytes=0")}) {
    int code = -1;
    const std::string out = dir.file("o");
    const uint64_t peak = peakRss("run -q " + config + " --trace " + trace + " --out " + out, code);
    ASSERT_EQ(code, 0) << config;
    const nlohmann::json j = readJson(out + "/report.json");
    const uint64_t estimate = j["sim"]["memory"]["estimate_bytes"];
    EXPECT_GE(estimate, peak) << config << ": estimate " << (estimate >> 20) << " MiB, peak " << (peak >> 20) << " MiB";
    // The shared levels' tag-store pages are estimated for a frame whose every
    // pixel's lines pass through them (RunShape::timing_level_bytes); glass
    // covers part of the screen and alpha's state mostly stays in the l2, so
    // that run's estimate is up to 2.5x its peak (issue 24's 1.2x holds for
    // the others). A tighter estimate needs the trace's covered pixels.
    const double over = config.find("timing --algo alpha") != std::string::npos ? 2.5 : 1.2;
    EXPECT_LE(double(estimate), over * double(peak))
        << config << ": estimate " << (estimate >> 20) << " MiB, peak " << (peak >> 20) << " MiB";
    // The report's own measurement agrees with the parent's (the report is written last).
    EXPECT_LE(j["sim"]["memory"]["peak_rss_bytes"].get<uint64_t>(), peak) << config;
  }
}

// A failed allocation (here an address-space limit below the frame's needs,
// with a budget that lets the run start) is one line naming the frame, the
// algorithm and the memory, in both modes.
TEST_F(CliReliability, AnAllocationFailureIsOneLine) {
  if (kAddressSanitizer) GTEST_SKIP() << "AddressSanitizer reserves terabytes of address space: no limit fits it";
  TempDir dir("oom");
  const std::string trace = dir.file("big.csv");
  writeText(trace, "# width 4096\n# height 4096\ndraw,prim,x,y,z,r,g,b,a,opaque\n0,0,1,1,0.5,1,0,0,0.5,0\n");
  for (const char* mode : {"functional", "timing"}) {
    const CliResult r = runShell("prlimit --as=419430400 " + oitsimPath() + " run -q --algo mlab --mode " + mode +
                                 " --memory-budget 100G --trace " + trace + " --out " + dir.file("o") + " 2>&1");
    EXPECT_EQ(r.exit_code, 1) << r.output;
    const std::string want = "oitsim: error: " + trace + ": out of memory: the 4096 x 4096 frame with mlab (" + mode +
                             " mode) needs about ";
    EXPECT_EQ(r.output.rfind(want, 0), 0u) << r.output;
    EXPECT_EQ(outputLines(r).size(), 1u) << r.output;
    EXPECT_FALSE(fs::exists(dir.file("o")));
  }
}

// kill -9 while the run writes: its staged files (".<name>.partial.<pid>...")
// stay, since no handler runs; the next run into the same folder removes them
// once that process is gone, and never a live run's.
TEST_F(CliReliability, AKilledRunsLeftoversVanishOnTheNextRun) {
  TempDir dir("killed");
  const std::string out = dir.file("out");
  // The staged VCD exists for the whole simulation: catch it there.
  const std::string vcd = out + "/w.vcd";
  fs::create_directories(out);
  const std::string big = dir.file("big.oitt");
  // 3 M fragments: about a second of simulation even on a fast machine.
  ASSERT_EQ(runOitsim("gen particles -o " + big).exit_code, 0);
  const pid_t pid = fork();
  if (pid == 0) {
    execl(oitsimPath().c_str(), "oitsim", "run", "-q", "--trace", big.c_str(), "--out", out.c_str(), "--vcd",
          vcd.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  const std::string staged_vcd = out + "/.w.vcd.partial." + std::to_string(pid) + ".vcd";
  for (int i = 0; i < 3000 && !fs::exists(staged_vcd); ++i) std::this_thread::sleep_for(5ms);
  ::kill(pid, SIGKILL);
  waitpid(pid, nullptr, 0);
  ASSERT_TRUE(fs::exists(staged_vcd)) << "the run never staged its VCD";
  // What a kill during the commit leaves: the staged outputs, and a PNG
  // writer's own temporary inside one.
  const std::string dead = std::to_string(pid);
  for (const std::string& name : {".image.png.partial." + dead, ".report.json.partial." + dead,
                                 ".diff.png.partial." + dead + ".tmp." + dead + ".0"})
    writeText(out + "/" + name, std::string(1000, 'x'));
  // A live run's staged file (this test's process stands in for it) and a user's file stay.
  const std::string live = out + "/.image.pfm.partial." + std::to_string(::getpid());
  writeText(live, "live");
  writeText(out + "/.notes.partial.1", "user");
  const CliResult r = runOitsim("run -q --trace " + trace_ + " --out " + out + " --vcd " + vcd);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(vcd));
  std::vector<std::string> hidden;
  for (const auto& e : fs::directory_iterator(out))
    if (e.path().filename().string()[0] == '.') hidden.push_back(e.path().filename().string());
  std::sort(hidden.begin(), hidden.end());
  EXPECT_EQ(hidden, (std::vector<std::string>{".image.pfm.partial." + std::to_string(::getpid()), ".notes.partial.1"}));
  EXPECT_TRUE(fs::exists(out + "/report.json"));
}

}  // namespace
}  // namespace oit::test
