// Golden-file regression tests of the timing model (trace-player tests against
// golden files): 22 small runs, each a preset, an algorithm, an engine and a
// few settings over a fixed scene, whose whole timing statistics, outcome
// counts and a 64-bit hash of the image's bits must equal what
// tests/data/golden/<run>.json holds.
// Any change of a model result fails here first; once accepted
// (OITSIM_UPDATE_GOLDEN=1 rewrites the files, tests/README.md) it is a diff
// of those files, reviewed in the commit that changes the model. CI runs this
// in the g++ Release build and the clang sanitizer build: a result that
// depends on the compiler (evaluation order, floating point, UB) fails in one.
//
// The stats hold no host-dependent field (wall time and pool bytes travel
// beside them in TimingResult), so they are compared whole.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "Fnv1a.hpp"
#include "model/MemorySource.hpp"
#include "oit_rop/RopTestUtil.hpp"
#include "oit_rop/config/ConfigTree.hpp"
#include "traces/AtomicFile.hpp"
#include "traces/gen/Scenes.hpp"
#include "traces/test_gen_util.hpp"

using namespace oit;
using namespace oit::rop;
using namespace oit::rop::testutil;
namespace fs = std::filesystem;

// Named, not anonymous: unity builds compile several test files as one.
namespace oit::rop::golden_reports {

const std::string kGoldenDir = std::string(OITSIM_SOURCE_DIR) + "/tests/data/golden";

enum class Scene {
  // `oitsim gen demo --width 160 --height 120 --seed 1`: an opaque backdrop and
  // pillar, then smoke, glass and hair; 45,872 fragments in 4 draws.
  Demo160,
  // The tests' own scene (RopTestUtil.hpp smallScene(64, 48, 12, 5)): an opaque
  // backdrop over 2/3 of the frame interleaved with two transparent draws, up to
  // 12 deep, every 17th fragment with alpha 0.
  Small64,
};

struct GoldenRun {
  std::string name;  // the test's and the file's name
  Scene scene;
  std::string preset;
  std::string algo;               // mlab: k = 4 rgba8t8z32; the others: `oitsim run`'s defaults (k = 4, fp32)
  std::vector<std::string> sets;  // --set overrides, sim.engine among them
};
void PrintTo(const GoldenRun& run, std::ostream* os) { *os << run.name; }

// On iris-pro-5200 the frame's 0.8 MB fits the l2 (and the 128 MB eDRAM): no
// byte reaches DRAM, so the DRAM settings are run without the shared levels.
const std::vector<std::string> kDramOnly = {"l2.size_bytes=0", "l3.size_bytes=0"};

std::vector<std::string> with(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

const std::vector<GoldenRun>& goldenRuns() {
  static const std::vector<GoldenRun> runs = [] {
    std::vector<GoldenRun> v;
    const std::pair<const char*, const char*> presets[] = {
        {"iris", "iris-pro-5200"}, {"titan", "titan-x-maxwell"}, {"navi21", "navi21"}};
    for (const auto& [short_name, preset] : presets)
      for (const char* engine : {"cycle", "approximate"})
        v.push_back({std::string(short_name) + "_mlab_" + engine, Scene::Demo160, preset, "mlab",
                     {std::string("sim.engine=") + engine}});
    const std::string iris = "iris-pro-5200";
    v.push_back({"iris_abuffer_cycle", Scene::Demo160, iris, "abuffer", {"sim.engine=cycle"}});
    v.push_back({"iris_adaptive_approximate", Scene::Demo160, iris, "adaptive", {"sim.engine=approximate"}});
    v.push_back({"iris_wboit_cycle_small", Scene::Small64, iris, "wboit", {"sim.engine=cycle"}});
    v.push_back({"iris_mlab_dram_only_cycle", Scene::Demo160, iris, "mlab", with(kDramOnly, {"sim.engine=cycle"})});
    v.push_back({"iris_mlab_dram_only_approximate", Scene::Demo160, iris, "mlab",
                 with(kDramOnly, {"sim.engine=approximate"})});
    v.push_back({"iris_mlab_dram_only_fcfs_cycle", Scene::Demo160, iris, "mlab",
                 with(kDramOnly, {"dram.scheduler=fcfs", "sim.engine=cycle"})});
    // Every preset keeps rows open.
    v.push_back({"iris_mlab_dram_only_closed_page_cycle", Scene::Demo160, iris, "mlab",
                 with(kDramOnly, {"dram.open_row=false", "sim.engine=cycle"})});
    v.push_back({"iris_mlab_unordered_cycle_small", Scene::Small64, iris, "mlab",
                 {"lock.mode=unordered", "sim.engine=cycle"}});
    // The lock without order (its image is the race's, counted) and coarser
    // scopes, and the l2 as a victim cache of the ROP caches.
    v.push_back({"iris_mlab_lock_none_cycle_small", Scene::Small64, iris, "mlab", {"lock.mode=none", "sim.engine=cycle"}});
    v.push_back({"iris_mlab_quad_lock_cycle", Scene::Demo160, iris, "mlab",
                 {"lock.granularity=quad", "sim.engine=cycle"}});
    v.push_back({"iris_mlab_tile_lock_approximate", Scene::Demo160, iris, "mlab",
                 {"lock.granularity=tile", "sim.engine=approximate"}});
    v.push_back({"iris_mlab_victim_l2_cycle", Scene::Demo160, iris, "mlab", {"l2.victim_only=true", "sim.engine=cycle"}});
    // The GDDR presets' DRAM (their l2s hold this frame whole: 1,300-1,450
    // cycles, no DRAM byte), without their shared levels: GDDR5 and GDDR6
    // timings, refresh and activate limits on both engines.
    for (const auto& [short_name, preset] : {presets[1], presets[2]})
      for (const char* engine : {"cycle", "approximate"})
        v.push_back({std::string(short_name) + "_mlab_dram_only_" + engine, Scene::Demo160, preset, "mlab",
                     with(kDramOnly, {std::string("sim.engine=") + engine})});
    return v;
  }();
  return runs;
}

std::string sceneName(Scene s) {
  return s == Scene::Demo160 ? "oitsim gen demo --width 160 --height 120 --seed 1"
                             : "smallScene(64, 48, 12, 5) (tests/oit_rop/RopTestUtil.hpp)";
}

// Runs in the forked child: the scene, the algorithm and the simulation.
TimingResult simulate(const GoldenRun& run) {
  const RopConfig cfg = resolveConfig(run.preset, "", run.sets);
  model::AlgorithmParams p;
  if (run.algo == "mlab") p.format = model::StorageFormat::Rgba8T8Z32;
  if (run.algo == "abuffer") p.abuffer = abufferBudget(cfg.abuffer);  // as `oitsim run` does
  auto algo = model::makeAlgorithm(run.algo, p);
  if (run.scene == Scene::Demo160) {
    gen::SceneOptions o;
    o.width = 160;
    o.height = 120;
    o.seed = 1;
    test::VectorSink sink;
    gen::generateScene("demo", o, sink);
    model::MemorySource src(gen::sceneHeader("demo", o), std::move(sink.fragments), 1 << 12);
    return runTiming(src, *algo, cfg, {});
  }
  model::MemorySource src(model::testutil::header(64, 48), smallScene(64, 48, 12, 5), 333);
  return runTiming(src, *algo, cfg, {});
}

// FNV-1a over the width, the height and every pixel's float bits (-0.0 is not 0.0).
std::string imageHash(const model::Image& img) {
  uint64_t h = test::fnv1a64(&img.width, sizeof img.width);
  h = test::fnv1a64(&img.height, sizeof img.height, h);
  h = test::fnv1a64(img.pixels.data(), img.pixels.size() * sizeof(model::Rgb), h);
  std::ostringstream s;
  s << "fnv1a64:" << std::hex << h;
  return s.str();
}

// The functional outcome counts, which travel beside the stats.
nlohmann::json counts(const model::RenderCounts& c) {
  return {{"fragments_in", c.fragments_in}, {"opaque", c.opaque},
          {"culled", c.culled},             {"stored", c.stored},
          {"merged", c.merged},             {"discarded", c.discarded},
          {"pass_outcomes", c.pass_outcomes}, {"bytes_read", c.bytes_read},
          {"bytes_written", c.bytes_written}, {"source_passes", c.source_passes}};
}

// What the golden file holds: the run's description, the image and the stats.
nlohmann::json record(const GoldenRun& run, const ChildRun& r) {
  return {{"run", run.name},
          {"scene", sceneName(run.scene)},
          {"preset", run.preset},
          {"algorithm", run.algo == "mlab" ? "mlab k=4 rgba8t8z32" : run.algo + " (defaults: k=4 fp32)"},
          {"sets", run.sets},
          {"image", {{"width", r.image.width}, {"height", r.image.height}, {"bits", imageHash(r.image)}}},
          {"counts", counts(r.counts)},
          {"stats", r.stats}};
}

std::string shortValue(const nlohmann::json& j) {
  std::string s = j.dump();
  return s.size() > 80 ? s.substr(0, 77) + "..." : s;
}

std::string valueAt(const nlohmann::json& j, const char* pointer) {
  const nlohmann::json::json_pointer p(pointer);
  return j.contains(p) ? shortValue(j.at(p)) : "(missing)";
}

// Every differing JSON path (RFC 6901 style), with the expected and actual values.
void collectDiffs(const nlohmann::json& want, const nlohmann::json& got, const std::string& path,
                  std::vector<std::string>& out) {
  const std::string at = path.empty() ? "/" : path;
  if (want.is_object() && got.is_object()) {
    for (const auto& [k, v] : want.items()) {
      if (!got.contains(k)) out.push_back(path + "/" + k + ": expected " + shortValue(v) + ", actual (missing)");
      else collectDiffs(v, got[k], path + "/" + k, out);
    }
    for (const auto& [k, v] : got.items())
      if (!want.contains(k)) out.push_back(path + "/" + k + ": expected (missing), actual " + shortValue(v));
    return;
  }
  if (want.is_array() && got.is_array()) {
    if (want.size() != got.size())
      out.push_back(at + ": expected " + std::to_string(want.size()) + " elements, actual " +
                    std::to_string(got.size()));
    for (size_t i = 0; i < std::min(want.size(), got.size()); ++i)
      collectDiffs(want[i], got[i], path + "/" + std::to_string(i), out);
    return;
  }
  // nlohmann compares numbers by value across integer and float types.
  if (want != got) out.push_back(at + ": expected " + shortValue(want) + ", actual " + shortValue(got));
}

bool updating() {
  const char* u = std::getenv("OITSIM_UPDATE_GOLDEN");
  return u && std::string(u) == "1";
}

std::string relativePath(const std::string& file) { return "tests/data/golden/" + fs::path(file).filename().string(); }

// Temporary file and rename: an interrupted update leaves the old file whole.
void writeGolden(const std::string& file, const nlohmann::json& j) {
  const std::string text = j.dump(2) + "\n";
  fs::create_directories(fs::path(file).parent_path());
  detail::AtomicFile out(file);
  out.append(text.data(), text.size());
  out.commit();
}

class GoldenReports : public ::testing::TestWithParam<GoldenRun> {};

TEST_P(GoldenReports, MatchTheCommittedFile) {
  const GoldenRun& run = GetParam();
  const ChildRun r = runInChild([&] { return simulate(run); });
  ASSERT_TRUE(r.ok) << r.error;
  // Through the text, as the file holds it (the stats came back through a pipe as JSON already).
  const nlohmann::json got = nlohmann::json::parse(record(run, r).dump());
  const std::string file = kGoldenDir + "/" + run.name + ".json";

  nlohmann::json want;
  std::ifstream in(file);
  if (in) want = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  std::vector<std::string> diffs;
  if (in && !want.is_discarded()) collectDiffs(want, got, "", diffs);
  const bool missing = !in || want.is_discarded();
  if (!missing && diffs.empty()) return;

  if (updating()) {
    writeGolden(file, got);
    std::cout << "[ golden  ] " << (missing ? "wrote " : "updated ") << relativePath(file)
              << (missing ? "" : " (" + std::to_string(diffs.size()) + " value(s) changed)")
              << ": review `git diff tests/data/golden` and commit it with the change\n";
    return;
  }
  std::ostringstream msg;
  if (missing) {
    msg << relativePath(file) << " is missing or not JSON: OITSIM_UPDATE_GOLDEN=1 writes it (below).";
  } else {
    msg << "run " << run.name << ": " << diffs.size() << " value(s) differ from " << relativePath(file) << "; frame "
        << valueAt(want, "/stats/timing/cycles") << " -> " << valueAt(got, "/stats/timing/cycles")
        << " cycles, image " << (valueAt(want, "/image") == valueAt(got, "/image") ? "the same" : "changed") << ":";
    const size_t shown = std::min<size_t>(diffs.size(), 12);
    for (size_t i = 0; i < shown; ++i) msg << "\n  " << diffs[i];
    if (diffs.size() > shown) msg << "\n  ... and " << diffs.size() - shown << " more";
  }
  msg << "\nIf the change of the model is intended: OITSIM_UPDATE_GOLDEN=1 build/tests/test_oit_rop "
         "--gtest_filter='*GoldenReport*' rewrites the files; commit their diff with the change (tests/README.md).";
  FAIL() << msg.str();
}

std::string runName(const ::testing::TestParamInfo<GoldenRun>& param_info) { return param_info.param.name; }
INSTANTIATE_TEST_SUITE_P(Runs, GoldenReports, ::testing::ValuesIn(goldenRuns()), runName);

// A file of a run that is gone would pass for a guard it no longer is.
TEST(GoldenReportFiles, EachIsARunOfThisTest) {
  std::vector<std::string> stale;
  for (const auto& e : fs::directory_iterator(kGoldenDir)) {
    if (e.path().extension() != ".json") continue;
    const std::string stem = e.path().stem().string();
    bool known = false;
    for (const auto& run : goldenRuns()) known = known || run.name == stem;
    if (known) continue;
    if (updating()) {
      fs::remove(e.path());
      std::cout << "[ golden  ] removed " << relativePath(e.path().string()) << " (no run of that name)\n";
    } else {
      stale.push_back(relativePath(e.path().string()));
    }
  }
  for (const auto& s : stale)
    ADD_FAILURE() << s << " is no run of tests/oit_rop/test_golden_reports.cpp: git rm it, or add its run back";
}

}  // namespace oit::rop::golden_reports
