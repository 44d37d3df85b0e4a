// End-to-end tests of `oitsim gen` + `oitsim run` on the real executable: the
// acceptance criteria of the foundation, golden-model and timing-model issues.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cctype>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "CliRunner.hpp"

namespace oit::test {
namespace {

namespace fs = std::filesystem;

// A small particles trace, shared by the tests of this file.
struct CliRunTrace {
  static constexpr const char* kFolder = "cli_run";
  static constexpr const char* kFile = "p.oitt";
  static constexpr const char* kGen = "gen particles --width 160 --height 90 --count 300 --backdrop";
};
class CliRun : public GeneratedTraceSuite<CliRunTrace> {};

TEST_F(CliRun, GenThenInfoPrintsStatistics) {
  CliResult r = runOitsim("info " + trace_);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("160 x 90"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("particles"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("depth complexity"), std::string::npos) << r.output;
}

// gen's --help range is the format's: x and y are u16, so 65535 at most.
TEST_F(CliRun, GenRefusesAFrameTheFormatCannotHoldAtTheOption) {
  const std::string out = dir_->file("wide.oitt");
  CliResult r = runOitsim("gen glass --width 65536 --height 1 --count 1 -o " + out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("--width"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("65535"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
  CliResult h = runOitsim("gen --help");
  EXPECT_NE(h.output.find("[1 - 65535]"), std::string::npos) << h.output;
}

TEST_F(CliRun, FunctionalMlabHasErrorAndAbufferHasNone) {
  const std::string out = dir_->file("f_mlab");
  CliResult r = runOitsim("run --mode functional --algo mlab --layers 4 -q --trace " + trace_ + " --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* f : {"image.png", "image.pfm", "reference.pfm", "diff.png", "flip.png", "report.json"})
    EXPECT_TRUE(fs::exists(fs::path(out) / f)) << f;
  nlohmann::json j = readJson(out + "/report.json");
  EXPECT_GT(j["image"]["metrics"]["rmse"].get<double>(), 0.0);
  const auto& f = j["fragments"];
  EXPECT_EQ(f["in"].get<uint64_t>(), j["trace"]["fragments"].get<uint64_t>());
  EXPECT_EQ(f["opaque"].get<uint64_t>() + f["culled_by_depth"].get<uint64_t>() + f["stored"].get<uint64_t>() +
                f["merged"].get<uint64_t>() + f["discarded"].get<uint64_t>(),
            f["in"].get<uint64_t>());
  EXPECT_GT(f["merged"].get<uint64_t>(), 0u) << "300 overlapping particles must overflow 4 rows somewhere";
  EXPECT_GT(j["sim"]["wall_seconds"].get<double>(), 0.0);
  EXPECT_GT(j["sim"]["fragments_per_second"].get<double>(), 0.0);

  const std::string ref = dir_->file("f_abuffer");
  r = runOitsim("run --mode functional --algo abuffer -q --trace " + trace_ + " --out " + ref);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  nlohmann::json a = readJson(ref + "/report.json");
  EXPECT_EQ(a["image"]["metrics"]["rmse"].get<double>(), 0.0);
  EXPECT_EQ(a["image"]["metrics"]["max_abs"].get<double>(), 0.0);
  EXPECT_EQ(a["image"]["metrics"]["ssim"].get<double>(), 1.0);
}

// The trace may be given positionally, as `oitsim info` takes it: the same
// run as with --trace (the image bit for bit); two traces are one too many.
TEST_F(CliRun, RunTakesTheTraceAsAPositionalArgument) {
  const std::string named = dir_->file("pos_named"), positional = dir_->file("pos_positional");
  CliResult r = runOitsim("run --mode functional --algo mlab -q --trace " + trace_ + " --out " + named);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = runOitsim("run " + trace_ + " --mode functional --algo mlab -q --out " + positional);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream a(named + "/image.pfm", std::ios::binary), b(positional + "/image.pfm", std::ios::binary);
  const std::string image_a((std::istreambuf_iterator<char>(a)), {}), image_b((std::istreambuf_iterator<char>(b)), {});
  ASSERT_FALSE(image_a.empty());
  EXPECT_EQ(image_a, image_b);
  const std::string twice = dir_->file("pos_twice");
  r = runOitsim("run " + trace_ + " " + trace_ + " --mode functional -q --out " + twice);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("not expected"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(twice));
}

// Every key of a timing report (the A-buffer's and a bounded algorithm's with
// an l2 and l3) is named in reports/REPORT.md, so the schema page cannot fall
// behind the code. config.rop is the property tree (oit_rop/config/CONFIG.md);
// numeric keys are draw ids.
bool namedIn(const std::string& doc, const std::string& key) {
  for (size_t at = doc.find(key); at != std::string::npos; at = doc.find(key, at + 1)) {
    const auto word = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
    const bool starts = at == 0 || !word(doc[at - 1]);
    const bool ends = at + key.size() >= doc.size() || !word(doc[at + key.size()]);
    if (starts && ends) return true;
  }
  return false;
}
void collectUnnamed(const nlohmann::json& j, const std::string& path, const std::string& doc,
                    std::vector<std::string>& out) {
  if (!j.is_object() || path == "config.rop") return;
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string key = it.key(), at = path.empty() ? key : path + "." + key;
    if (key.find_first_not_of("0123456789") == std::string::npos) continue;
    if (!namedIn(doc, key)) out.push_back(at);
    collectUnnamed(it.value(), at, doc, out);
  }
}

TEST_F(CliRun, EveryReportKeyIsNamedInTheSchemaPage) {
  std::ifstream in(std::string(OITSIM_SOURCE_DIR) + "/reports/REPORT.md");
  ASSERT_TRUE(in) << "cannot read reports/REPORT.md";
  const std::string doc((std::istreambuf_iterator<char>(in)), {});
  for (const std::string algo : {"abuffer", "mlab"}) {
    const std::string out = dir_->file("schema_" + algo);
    CliResult r = runOitsim("run " + trace_ + " --algo " + algo + " --set stats.level_miss_classes=true -q --out " + out);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    std::vector<std::string> unnamed;
    collectUnnamed(readJson(out + "/report.json"), "", doc, unnamed);
    EXPECT_TRUE(unnamed.empty()) << algo << ": report keys reports/REPORT.md does not name: "
                                 << nlohmann::json(unnamed).dump();
  }
}

TEST_F(CliRun, TimingReportHasEveryFieldAndTheFunctionalImage) {
  const std::string out = dir_->file("t_mlab");
  CliResult r = runOitsim("run --trace " + trace_ + " --algo mlab --layers 4 --preset igpu -q --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  nlohmann::json j = readJson(out + "/report.json");
  EXPECT_EQ(j["config"]["mode"], "timing");
  EXPECT_EQ(j["config"]["rop"]["preset"], "iris-pro-5200");  // igpu is its alias
  const auto& t = j["timing"];
  const uint64_t cycles = t["cycles"].get<uint64_t>();
  EXPECT_GT(cycles, 0u);
  EXPECT_GT(t["frame_time_us"].get<double>(), 0.0);
  for (auto it = t["stages"].begin(); it != t["stages"].end(); ++it) {
    uint64_t sum = it.value()["busy"].get<uint64_t>() + it.value()["idle"].get<uint64_t>();
    for (const auto& s : it.value()["stalls"]) sum += s.get<uint64_t>();
    EXPECT_EQ(sum, t["partition_cycles"].get<uint64_t>()) << it.key() << ": busy + stalls + idle != cycles";
  }
  EXPECT_TRUE(t["stages"]["pixel_lock"]["stalls"].contains("lock_wait"));
  const auto& f = j["fragments"];
  EXPECT_TRUE(f["outcomes_sum_to_in"].get<bool>());
  EXPECT_EQ(f["in"].get<uint64_t>(), j["trace"]["fragments"].get<uint64_t>());
  const auto& m = j["memory"];
  for (const char* k : {"blend_arrays", "depth", "colour", "resolve"}) {
    EXPECT_TRUE(m["dram_read_bytes"].contains(k)) << k;
    EXPECT_TRUE(m["dram_write_bytes"].contains(k)) << k;
    EXPECT_TRUE(m["footprint"]["allocated"].contains(k)) << k;
  }
  // The MLAB paper's footprint: W x H x bytes per pixel (fp32 rows: 20 B each).
  EXPECT_EQ(m["footprint"]["allocated"]["blend_arrays"].get<uint64_t>(), 160u * 90u * 4u * 20u);
  // (This small frame's arrays stay in the 6 MB LLC: DRAM may see nothing during the frame.)
  EXPECT_GE(m["mean_gbps"].get<double>(), 0.0);
  // Compulsory traffic and the levels of the hierarchy (REPORT.md).
  for (const char* k : {"blend_arrays", "depth", "colour", "resolve", "total"}) {
    EXPECT_TRUE(m["compulsory_bytes"].contains(k)) << k;
    EXPECT_TRUE(m["end_dirty_bytes"].contains(k)) << k;
  }
  EXPECT_GT(m["compulsory_bytes"]["total"].get<uint64_t>(), 0u);
  EXPECT_GE(m["traffic_over_compulsory"].get<double>(), 1.0);
  ASSERT_EQ(m["levels"].size(), 3u);
  EXPECT_EQ(m["levels"][0]["name"], "rop_cache");
  EXPECT_EQ(m["levels"][1]["name"], "l2");
  EXPECT_EQ(m["levels"][2]["name"], "l3");
  for (const auto& l : m["levels"])
    for (const char* k : {"accesses", "hits", "misses", "hit_rate", "read_bytes", "write_bytes"})
      EXPECT_TRUE(l.contains(k)) << l["name"] << " " << k;
  EXPECT_TRUE(j["lock"].contains("conflicts"));
  EXPECT_TRUE(j["lock"].contains("longest_wait"));
  EXPECT_TRUE(j["lock"].contains("peak_occupancy"));
  EXPECT_GE(j["cache"]["hit_rate"].get<double>(), 0.0);
  EXPECT_LE(j["cache"]["hit_rate"].get<double>(), 1.0);
  EXPECT_FALSE(j["timeseries"]["samples"].empty());
  EXPECT_FALSE(j["per_draw"].empty());
  EXPECT_GT(j["sim"]["wall_seconds"].get<double>(), 0.0);

  // Timing decides when, the functional model what: the same image bits.
  const std::string fn = dir_->file("t_functional");
  ASSERT_EQ(runOitsim("run --mode functional --trace " + trace_ + " --algo mlab --layers 4 -q --out " + fn).exit_code, 0);
  EXPECT_TRUE(readText(out + "/image.pfm") == readText(fn + "/image.pfm"));
}

// Determinism end to end: two separate processes (own heap, own address-space
// layout) on the same trace and seed write identical images and identical
// reports apart from the wall-clock and memory fields and the command line (it
// names the --out folder). A non-default seed and two partitions at a short quantum put
// the seeded shader latency and the partitions' interleaving at DRAM to work.
TEST_F(CliRun, TwoProcessesGiveIdenticalReportsApartFromWallClock) {
  std::vector<nlohmann::json> reports;
  std::vector<std::string> images;
  for (const char* name : {"det_a", "det_b"}) {
    const std::string out = dir_->file(name);
    CliResult r = runOitsim("run --trace " + trace_ +
                            " --algo mlab --layers 4 --set input.seed=7 --set sim.quantum_cycles=50 -q --out " + out);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    nlohmann::json j = readJson(out + "/report.json");
    for (const char* k : {"wall_seconds", "fragments_per_second", "reference_wall_seconds", "memory"}) {
      ASSERT_TRUE(j["sim"].contains(k)) << k;  // the fields removed are the ones REPORT.md names
      j["sim"].erase(k);
    }
    ASSERT_TRUE(j["oitsim"].contains("command"));
    j["oitsim"].erase("command");
    reports.push_back(j);
    images.push_back(readText(out + "/image.pfm"));
  }
  EXPECT_GT(reports[0]["timing"]["cycles"].get<uint64_t>(), 0u);
  EXPECT_EQ(reports[0]["config"]["rop"]["input"]["seed"], 7);
  EXPECT_TRUE(reports[0] == reports[1]) << nlohmann::json::diff(reports[0], reports[1]).dump(1);
  EXPECT_FALSE(images[0].empty());
  EXPECT_TRUE(images[0] == images[1]);
}

TEST_F(CliRun, BadSetNamesTheOptionAndWritesNothing) {
  const std::string out = dir_->file("bad_set");
  CliResult r = runOitsim("run --trace " + trace_ + " --set lock.granularity=octagon -q --out " + out);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("lock.granularity"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(fs::path(out) / "report.json"));
}

TEST_F(CliRun, TruncatedTraceFailsNamingByteOffsetAndLeavesNoReport) {
  const std::string bytes = readText(trace_);
  const std::string cut = dir_->file("cut.oitt");
  const size_t keep = bytes.size() - 100;
  std::ofstream(cut, std::ios::binary) << bytes.substr(0, keep);
  for (const char* mode : {"functional", "timing"}) {
    const std::string out = dir_->file(std::string("cut_") + mode);
    CliResult r = runOitsim(std::string("run --mode ") + mode + " --trace " + cut + " -q --out " + out);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find("byte offset " + std::to_string(keep)), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(fs::path(out) / "report.json")) << mode;
  }
}

TEST_F(CliRun, CsvTraceRunsDirectlyWithWidthAndHeight) {
  const std::string csv = dir_->file("t.csv");
  std::ofstream(csv) << "draw,prim,x,y,z,r,g,b,a,opaque\n"
                        "0,0,1,1,0.5,1,0,0,0.5,0\n"
                        "0,1,1,1,0.25,0,0,1,0.5,0\n";
  const std::string out = dir_->file("csv_run");
  CliResult r = runOitsim("run --mode functional --algo alpha --trace " + csv + " --width 4 --height 4 -q --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  nlohmann::json j = readJson(out + "/report.json");
  EXPECT_EQ(j["trace"]["width"], 4);
  EXPECT_EQ(j["fragments"]["in"], 2);
  // Submission order = depth order reversed here, so over-blending is exact.
  EXPECT_EQ(j["image"]["metrics"]["rmse"].get<double>(), 0.0);
}

}  // namespace
}  // namespace oit::test
