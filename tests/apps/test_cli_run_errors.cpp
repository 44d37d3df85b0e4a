// `oitsim run` on bad input, end to end: every problem is reported as one clean
// line naming the option, file or offset, with exit code 1, before anything is
// written; and the bandwidth and VCD outputs of the timing mode are sound.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include "CliRunner.hpp"

namespace oit::test {
namespace {

namespace fs = std::filesystem;

// The reader's prefix of a record error (traces/FORMAT.md, section 5).
std::string fmt_prefix(const std::string& file, uint64_t byte_offset, const std::string& field) {
  return file + ": byte offset " + std::to_string(byte_offset) + ", record 0, field " + field + ": ";
}

// The audit's 64x48 glass trace (no opaque draws: every record is first read
// by the SystemC threads in timing mode).
struct CliRunErrorsTrace {
  static constexpr const char* kFolder = "cli_run_errors";
  static constexpr const char* kFile = "glass.oitt";
  static constexpr const char* kGen = "gen glass --width 64 --height 48";
};
class CliRunErrors : public GeneratedTraceSuite<CliRunErrorsTrace> {
 protected:
  // The glass trace with `size` bytes at `field_offset` of record `record` replaced.
  static std::string patched(const std::string& name, uint64_t record, size_t field_offset, const void* value,
                             size_t size, uint64_t* byte_offset = nullptr) {
    std::string bytes = readText(trace_);
    uint32_t header_bytes = 0, record_bytes = 0;
    std::memcpy(&header_bytes, bytes.data() + 12, 4);
    std::memcpy(&record_bytes, bytes.data() + 36, 4);
    const size_t at = header_bytes + record * record_bytes + field_offset;
    std::memcpy(bytes.data() + at, value, size);
    if (byte_offset) *byte_offset = at;
    const std::string path = dir_->file(name);
    writeText(path, bytes);
    return path;
  }
};

TEST_F(CliRunErrors, UnwritableVcdPathFailsNamingTheOptionBeforeTheSimulation) {
  const std::string out = dir_->file("vcd_out");
  for (const std::string vcd : {"/nonexistent_dir/y.vcd", "/proc/x/y.vcd"}) {
    SCOPED_TRACE(vcd);
    CliResult r = runOitsim("run -t " + trace_ + " -o " + out + " -q --vcd " + vcd);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_EQ(r.output, "oitsim: error: --vcd " + vcd + ": " + vcd +
                            ": cannot write the VCD file: No such file or directory\n");
    EXPECT_FALSE(fs::exists(out));
  }
  // A folder given as the VCD file.
  const std::string folder = dir_->file("folder.vcd");
  fs::create_directories(folder);
  CliResult r = runOitsim("run -t " + trace_ + " -o " + out + " -q --vcd " + folder);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output, "oitsim: error: --vcd " + folder + ": " + folder + ": cannot write the VCD file: Is a directory\n");
  EXPECT_FALSE(fs::exists(out));
}

// SystemC wraps an exception escaping a thread ("(E549) uncaught exception ...
// In process: ..."); the reader's own message must come out, as in functional mode.
TEST_F(CliRunErrors, BadRecordReadsTheSameInTimingAndFunctionalMode) {
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const uint16_t x_out = 64;
  const uint32_t no_draw = 999;
  struct Case {
    std::string name;
    size_t field;  // offset in the fp32 record (traces/FORMAT.md 4.1)
    const void* value;
    size_t size;
    std::string field_name, message;
  };
  const Case cases[] = {
      {"z_nan", 4, &nan, 4, "z", "depth is NaN, expected a finite value in [0,1]"},
      {"x_out", 0, &x_out, 2, "x", "x 64 outside the frame, expected 0 <= x < 64 (the width)"},
      {"r_inf", 8, &inf, 4, "r", "colour r is +Inf"},
      {"draw", 28, &no_draw, 4, "draw", "unknown draw id 999"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    uint64_t at = 0;
    const std::string bad = patched(c.name + ".oitt", 0, c.field, c.value, c.size, &at);
    const std::string out_f = dir_->file(c.name + "_f"), out_t = dir_->file(c.name + "_t");
    CliResult f = runOitsim("run --mode functional -t " + bad + " -o " + out_f);
    CliResult t = runOitsim("run -t " + bad + " -o " + out_t);
    EXPECT_EQ(f.exit_code, 1) << f.output;
    EXPECT_EQ(t.exit_code, f.exit_code) << t.output;
    EXPECT_NE(f.output.find(fmt_prefix(bad, at, c.field_name) + c.message), std::string::npos) << f.output;
    EXPECT_EQ(t.output, f.output);
    EXPECT_EQ(t.output.find("E549"), std::string::npos) << t.output;
    EXPECT_EQ(t.output.find("In process"), std::string::npos) << t.output;
    EXPECT_FALSE(fs::exists(out_t));
  }
}

// The configuration is resolved and validated whatever the mode.
TEST_F(CliRunErrors, FunctionalModeRejectsTheSameBadTimingOptions) {
  const std::string malformed = dir_->file("malformed.json");
  writeText(malformed, "{\"lock\": {\"capacity\": 64,}");
  const std::string options[] = {"--preset foo", "--set nosuch.key=1", "--config /nonexistent.json",
                                 "--config " + malformed};
  const std::string out = dir_->file("fn_opts");
  for (const std::string& o : options) {
    SCOPED_TRACE(o);
    CliResult f = runOitsim("run --mode functional -q -t " + trace_ + " -o " + out + " " + o);
    CliResult t = runOitsim("run -q -t " + trace_ + " -o " + out + " " + o);
    EXPECT_EQ(f.exit_code, 1) << f.output;
    EXPECT_EQ(t.exit_code, 1) << t.output;
    EXPECT_EQ(f.output, t.output);
    EXPECT_EQ(f.output.rfind("oitsim: error: ", 0), 0u) << f.output;
    EXPECT_FALSE(fs::exists(out));
  }
  CliResult r = runOitsim("run --mode functional -q -t " + trace_ + " -o " + out + " --vcd " + dir_->file("v.vcd"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output, "oitsim: error: --vcd " + dir_->file("v.vcd") +
                          ": a VCD needs the timing model; drop --mode functional (the default is timing)\n");
  EXPECT_FALSE(fs::exists(out));
  EXPECT_FALSE(fs::exists(dir_->file("v.vcd")));
  // An earlier run's VCD at the path goes too, as its other outputs do, even
  // though this run fails on an option.
  writeText(dir_->file("old.vcd"), "$date earlier run $end\n");
  r = runOitsim("run --mode functional -q -t " + trace_ + " -o " + out + " --vcd " + dir_->file("old"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_FALSE(fs::exists(dir_->file("old.vcd")));
}

// An earlier run's report.json never survives a run that fails, however early
// it fails (an option, the configuration, the trace).
TEST_F(CliRunErrors, FailedRunLeavesNoEarlierReport) {
  const std::string out = dir_->file("stale");
  CliResult ok = runOitsim("run -q --mode functional -t " + trace_ + " -o " + out);
  ASSERT_EQ(ok.exit_code, 0) << ok.output;
  const std::string cut = dir_->file("cut.oitt");
  {
    const std::string bytes = readText(trace_);
    writeText(cut, bytes.substr(0, bytes.size() - 7));  // a truncated last record
  }
  const std::vector<std::string> bad = {"-t " + trace_ + " -k 100", "-t " + trace_ + " --set lock.capacity=0",
                                        "-t " + cut};
  for (const std::string& b : bad) {
    SCOPED_TRACE(b);
    CliResult w = runOitsim("run -q --mode functional -t " + trace_ + " -o " + out);
    ASSERT_EQ(w.exit_code, 0) << w.output;
    ASSERT_TRUE(fs::exists(out + "/report.json"));
    CliResult r = runOitsim("run -q -o " + out + " " + b);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    // None of the earlier run's files stays to pass for this run's (only
    // report.json was removed: the old images stayed beside nothing), and no
    // temporary or staged file is left.
    EXPECT_TRUE(fs::is_empty(out)) << fs::begin(fs::directory_iterator(out))->path();
  }
}

// --out is checked before the simulation: an empty path, or a path through a
// file (it failed after the run with a raw filesystem error).
TEST_F(CliRunErrors, OutThatCannotBeAFolderIsRefusedFirst) {
  CliResult r = runOitsim("run -q -t " + trace_ + " -o ''");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output, "oitsim: error: --out: expected a folder, got an empty path\n");
  r = runOitsim("run -q -t " + trace_ + " -o " + trace_ + "/sub");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output, "oitsim: error: --out " + trace_ + "/sub: " + fs::absolute(trace_).string() + " is not a directory\n");
}

// No output may be the input trace: a --vcd or an --out file of the trace's
// name emptied or replaced it (a 128 MB trace replaced by image.pfm).
TEST_F(CliRunErrors, OutputsThatWouldOverwriteTheTraceAreRefused) {
  const std::string keep = readText(trace_);
  const std::string vcd = dir_->file("t.vcd");
  writeText(vcd, keep);
  CliResult r = runOitsim("run -q -t " + vcd + " -o " + dir_->file("tvv") + " --vcd " + vcd);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output, "oitsim: error: --vcd " + vcd + ": " + vcd + " is the input trace --trace " + vcd + "\n");
  EXPECT_EQ(readText(vcd), keep);
  const std::string od = dir_->file("od");
  fs::create_directories(od);
  for (const char* name : {"image.pfm", "report.json"}) {
    const std::string t = od + "/" + name;
    writeText(t, keep);
    r = runOitsim("run -q --mode functional -t " + t + " -o " + od);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_EQ(r.output, "oitsim: error: --out " + od + ": " + t + " would overwrite the input trace --trace " + t + "\n");
    EXPECT_EQ(readText(t), keep) << name;
    fs::remove(t);
  }
}

// A config file naming its preset selects it when --preset is not given (as in
// `oitsim config`); with a different --preset the load fails naming both.
TEST_F(CliRunErrors, ConfigFilePresetSelectsThePresetWithoutPresetOption) {
  const std::string cfg = dir_->file("dgpu.json");
  writeText(cfg, "{\"preset\": \"dgpu\", \"lock\": {\"capacity\": 64}}");
  const std::string out = dir_->file("cfg_preset");
  CliResult r = runOitsim("run -q -t " + trace_ + " -o " + out + " --config " + cfg);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = readJson(out + "/report.json");
  EXPECT_EQ(j["config"]["rop"]["preset"], "titan-x-maxwell");  // dgpu is its alias
  EXPECT_EQ(j["config"]["rop"]["lock"]["capacity"], 64);
  EXPECT_EQ(j["config"]["rop"]["clock"]["core_mhz"], 1075.0);
  CliResult c = runOitsim("run -q -t " + trace_ + " -o " + dir_->file("cfg_clash") + " --config " + cfg +
                          " --preset igpu");
  EXPECT_EQ(c.exit_code, 1) << c.output;
  EXPECT_NE(c.output.find("the file is for preset \"dgpu\""), std::string::npos) << c.output;
}

// The audit's case: the last time-series interval is cut short by the end of
// the frame; peak must still be a rate at least the frame's mean.
TEST_F(CliRunErrors, PeakBandwidthIsNeverBelowMean) {
  for (const std::string algo : {"mlab", "abuffer", "alpha"}) {
    SCOPED_TRACE(algo);
    const std::string out = dir_->file("bw_" + algo);
    // (DRAM only: with the preset's LLC this small frame moves nothing to DRAM.)
    CliResult r = runOitsim("run -q -t " + trace_ + " --algo " + algo + " -o " + out +
                            " --set l3.size_bytes=0 --set l2.size_bytes=0");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const nlohmann::json m = readJson(out + "/report.json")["memory"];
    const double peak = m["peak_gbps"], mean = m["mean_gbps"], channels = m["channel_peak_gbps"];
    EXPECT_GT(mean, 0.0);
    EXPECT_GE(peak, mean);
    EXPECT_LE(peak, channels);
  }
}

TEST_F(CliRunErrors, VcdAtTheDefaultClockHasNoSystemcWarnings) {
  const std::string out = dir_->file("vcd_ok"), vcd = dir_->file("v.vcd");
  CliResult r = runOitsim("run -q -t " + trace_ + " -o " + out + " --vcd " + vcd + " --set stats.interval_cycles=1000");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, "");  // no (W713) "not representable in VCD time units", no (I703)
  const std::string text = readText(vcd);
  EXPECT_NE(text.find("$timescale\n     1 ps\n$end"), std::string::npos) << text.substr(0, 400);
  // The last grid sample's time, in ps: cycle x 1e6 / 1150 MHz (the report's
  // very last sample, at the frame's end, is not the sampler's and not traced).
  const nlohmann::json j = readJson(out + "/report.json");
  EXPECT_EQ(j["timing"]["clock_mhz"].get<double>(), 1150.0);
  const auto& samples = j["timeseries"]["samples"];
  ASSERT_GE(samples.size(), 2u);
  const uint64_t cycle = samples[samples.size() - 2]["cycle"];
  const auto ps = uint64_t(std::llround(double(cycle) * 1e6 / 1150.0));
  EXPECT_NE(text.find("\n#" + std::to_string(ps) + "\n"), std::string::npos) << "no time stamp #" << ps;
}

TEST_F(CliRunErrors, OutThatIsAFileIsRefusedAndLeftAlone) {
  const std::string afile = dir_->file("afile");
  writeText(afile, "keep me\n");
  CliResult r = runOitsim("run -q -t " + trace_ + " -o " + afile);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output, "oitsim: error: --out " + afile + ": exists and is not a directory\n");
  EXPECT_EQ(readText(afile), "keep me\n");
}

TEST_F(CliRunErrors, ZeroWidthOrHeightIsRefusedAtTheOption) {
  const std::string csv = dir_->file("nosize.csv");
  writeText(csv, "draw,prim,x,y,z,r,g,b,a,opaque\n0,0,0,0,0.5,1,0,0,0.5,0\n");
  const std::string out = dir_->file("zero");
  CliResult r = runOitsim("run --mode functional -q -t " + csv + " -o " + out + " --width 0 --height 4");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output, "oitsim: error: --width 0: expected a frame width of at least 1 pixel\n");
  r = runOitsim("run --mode functional -q -t " + csv + " -o " + out + " --width 4 --height 0");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output, "oitsim: error: --height 0: expected a frame height of at least 1 pixel\n");
  // An empty --vcd is an error, not "no VCD" (it was silently ignored).
  r = runOitsim("run -q -t " + csv + " -o " + out + " --width 4 --height 4 --vcd ''");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output, "oitsim: error: --vcd: expected a file name, got an empty path\n");
  // Too large is the option's fault too, not the CSV's (as in info and convert).
  r = runOitsim("run --mode functional -q -t " + csv + " -o " + out + " --width 70000 --height 4");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output, "oitsim: error: --width 70000: expected a frame width of 1..65535 pixels (x and y are u16)\n");
  EXPECT_FALSE(fs::exists(out));
  r = runOitsim("run --mode functional -q -t " + csv + " -o " + out + " --width 4 --height 4");
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

// Unsigned options take digits only (CLI11 alone wrapped "-5" to 2^64 - 5 and
// saturated 2^64); option errors the parser finds are one line with exit code 1
// (CLI11's own exit codes were 104-106 with a second line), --help still 0.
TEST_F(CliRunErrors, BadNumbersAreOneLineErrorsNamingTheOption) {
  const std::string out = dir_->file("badnum");
  const std::pair<const char*, const char*> cases[] = {
      {"--seed -5", "oitsim: error: --seed: expected a non-negative integer, got '-5' (see --help)\n"},
      {"--seed 18446744073709551616",
       "oitsim: error: --seed: '18446744073709551616' is too large for this option (see --help)\n"},
      // Below 2^64 but beyond a 32-bit option: named, not the library's "Could not convert".
      {"--width 4294967297",
       "oitsim: error: --width 4294967297: not a value this option takes (too large?) (see --help)\n"},
      {"-k 2.0", "oitsim: error: --layers: expected a non-negative integer, got '2.0' (see --help)\n"},
      {"-k 4294967296", "oitsim: error: --layers 4294967296: not a value this option takes (too large?) (see --help)\n"},
  };
  for (const auto& [args, message] : cases) {
    CliResult r = runOitsim("run --mode functional -q -t " + trace_ + " -o " + out + " " + args);
    EXPECT_EQ(r.exit_code, 1) << args;
    EXPECT_EQ(r.output, message) << args;
  }
  EXPECT_FALSE(fs::exists(out));
  CliResult r = runOitsim("gen glass -o " + dir_->file("g.oitt") + " --width 0");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output, "oitsim: error: --width: Value 0 not in range 1 to 65535 (see --help)\n");
  // A ranged option checks the number first (the range check alone said "Value abc not in range").
  for (const std::string& cmd : {"gen glass -o " + dir_->file("g.oitt"), "capture --mesh bunny -o " + dir_->file("c.oitt")}) {
    r = runOitsim(cmd + " --width abc");
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_EQ(r.output, "oitsim: error: --width: expected a non-negative integer, got 'abc' (see --help)\n") << cmd;
    r = runOitsim(cmd + " --height -3");
    EXPECT_EQ(r.output, "oitsim: error: --height: expected a non-negative integer, got '-3' (see --help)\n") << cmd;
  }
  r = runOitsim("capture --mesh bunny -o " + dir_->file("c.oitt") + " --frames 100001");
  EXPECT_EQ(r.output, "oitsim: error: --frames '100001': expected a frame count 1..100000 with --mesh\n");
  EXPECT_FALSE(fs::exists(dir_->file("g.oitt")));
  EXPECT_FALSE(fs::exists(dir_->file("c.oitt")));
  EXPECT_EQ(runOitsim("run --help").exit_code, 0);
  r = runOitsim("run --mode functional -q -t " + trace_ + " -o " + out + " --seed 18446744073709551615");
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

// --width/--height are for CSV traces without a size; a different size for a
// trace that gives its own was silently ignored.
TEST_F(CliRunErrors, FrameSizeOptionThatDisagreesWithTheTraceIsRefused) {
  const std::string out = dir_->file("resize");
  CliResult r = runOitsim("run --mode functional -q -t " + trace_ + " -o " + out + " --width 1280");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output, "oitsim: error: --width 1280: " + trace_ + " gives its own frame size, 64 x 48 (--width and "
                      "--height are for CSV traces without '# width' / '# height' lines)\n");
  EXPECT_FALSE(fs::exists(out));
  r = runOitsim("info " + trace_ + " --height 10");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("oitsim: error: --height 10: "), std::string::npos) << r.output;
  r = runOitsim("run --mode functional -q -t " + trace_ + " -o " + out + " --width 64 --height 48");  // agrees
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

// Options are checked before the trace is opened: a bad algorithm or k is
// reported as such even when the trace does not exist (it said "cannot open").
TEST_F(CliRunErrors, AlgorithmAndLayersAreCheckedBeforeTheTrace) {
  const std::string missing = dir_->file("missing.oitt");
  CliResult r = runOitsim("run -q -t " + missing + " -o " + dir_->file("o1") + " --algo foo");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("foo"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("cannot open"), std::string::npos) << r.output;
  r = runOitsim("run -q -t " + missing + " -o " + dir_->file("o1") + " --algo mlab -k 65");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output.find("cannot open"), std::string::npos) << r.output;
}

// An insert gets all its cache lines or waits: a miss queue shorter than the
// lines one insert touches (k = 64 fp32 rows of 20 B = 1280 B per pixel: 20
// lines of 64 B) could never serve one, so it is refused before any work,
// naming the option and the rule.
TEST_F(CliRunErrors, MissQueueShorterThanOneInsertsLinesIsRefused) {
  const std::string out = dir_->file("bigk");
  CliResult r = runOitsim("run -q -t " + trace_ + " -o " + out + " -a mlab -k 64 --format fp32");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output, "oitsim: error: cache.miss_queue (16) is smaller than the 20 cache lines one mlab insert "
                      "touches (1280 bytes per pixel, memory.array_layout pixel_major, cache.line_bytes 64): an "
                      "insert gets all its lines or waits, so it could never start; raise cache.miss_queue or "
                      "cache.line_bytes\n");
  EXPECT_FALSE(fs::exists(out));
  r = runOitsim("run -q -t " + trace_ + " -o " + out + " -a mlab -k 64 --format fp32 --set cache.miss_queue=20");
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

// The hierarchy's configuration rules are one line naming the parameter.
TEST_F(CliRunErrors, BadHierarchyIsOneLineNamingTheParameter) {
  const std::string out = dir_->file("badl2");
  CliResult r = runOitsim("run -q -t " + trace_ + " -o " + out + " --set cache.sector_bytes=48");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output, "oitsim: error: invalid configuration (preset iris-pro-5200): cache.sector_bytes (48) must be a "
                      "power of two dividing cache.line_bytes (64)\n");
  EXPECT_FALSE(fs::exists(out));
  // The DRAM controller's rules too (the write queue's watermarks out of order).
  r = runOitsim("run -q -t " + trace_ + " -o " + out + " --set dram.write_low=60");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output, "oitsim: error: invalid configuration (preset iris-pro-5200): dram.write_low (60) >= "
                      "dram.write_high (56): the low watermark must be below the high one\n");
  EXPECT_FALSE(fs::exists(out));
  // An l2 line smaller than the ROP cache's, on another preset.
  r = runOitsim("run -q -t " + trace_ + " -o " + out + " --preset titan-x-maxwell --set l2.line_bytes=64");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output, "oitsim: error: invalid configuration (preset titan-x-maxwell): l2.line_bytes (64) is smaller "
                      "than cache.line_bytes (128): a line of the level above must fit in one l2 line\n");
  EXPECT_FALSE(fs::exists(out));
}

// The activate limits: a tFAW below 4 x tRRD (a window that could never
// bind) is one line naming both, exit 1, nothing written; from a config file
// as from --set.
TEST_F(CliRunErrors, ActivateWindowBelowFourTrrdIsRefused) {
  const std::string out = dir_->file("badfaw");
  CliResult r = runOitsim("run -q -t " + trace_ + " -o " + out + " --set dram.tfaw=19");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output, "oitsim: error: invalid configuration (preset iris-pro-5200): dram.tfaw (19 tCK) is below 4 x "
                      "dram.trrd (5 tCK): four activates tRRD apart already span 20 tCK, so the window could never "
                      "bind (JEDEC parts have tFAW >= 4 tRRD); set dram.tfaw to 0 (no window) or at least 20\n");
  EXPECT_FALSE(fs::exists(out));
  const std::string cfg = dir_->file("faw.json");
  writeText(cfg, R"({"dram": {"trrd": 10, "tfaw": 30}})");
  r = runOitsim("run -q -t " + trace_ + " -o " + out + " --config " + cfg + " --preset titan-x-maxwell");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("dram.tfaw (30 tCK) is below 4 x dram.trrd (10 tCK)"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
}

// Bank groups: groups not dividing the banks, or an in-group timing without
// groups, is one line naming the parameter and the rule, exit 1, nothing written.
TEST_F(CliRunErrors, BadBankGroupsAreRefused) {
  const std::string out = dir_->file("badbg");
  CliResult r = runOitsim("run -q -t " + trace_ + " -o " + out + " --preset titan-x-maxwell --set dram.bank_groups=32");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output, "oitsim: error: invalid configuration (preset titan-x-maxwell): dram.bank_groups (32) must be a "
                      "power of two dividing dram.banks (16): each group holds the same number of banks\n");
  EXPECT_FALSE(fs::exists(out));
  r = runOitsim("run -q -t " + trace_ + " -o " + out + " --set dram.tccd_l=5");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output, "oitsim: error: invalid configuration (preset iris-pro-5200): dram.tccd_l (5 tCK) needs "
                      "dram.bank_groups > 1: without bank groups every bank keeps dram.tccd_s (0 tCK); set "
                      "dram.tccd_l to 0 or dram.bank_groups to the part's groups\n");
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
}  // namespace oit::test
