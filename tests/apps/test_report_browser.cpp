// The sweep report in a real headless Chromium, at 1400 and 1920 pixels wide:
// no horizontal overflow, every image decoded, each difference image aligned
// under its image, the points table sorted by a click, every plot's axes
// labelled; and screenshots that are not blank. The measurements are taken by
// tests/apps/data/report_probe.js, injected into a copy of the page (the page
// itself carries no test code), and read back with --dump-dom.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <regex>
#include <sstream>

#include "CliRunner.hpp"

namespace oit::test {
namespace {

namespace fs = std::filesystem;

// Two scenes x two machines x (mlab and adaptive at k = 2, 4, and wboit): 20
// timing points, plus the A-buffer reference of each scene in the grid.
const char* kBrowserSpec = R"({
  "traces": [
    {"gen": "particles", "width": 96, "height": 54, "count": 120, "backdrop": true},
    {"gen": "hair", "width": 96, "height": 54}
  ],
  "base": {"mode": "timing", "format": "fp32"},
  "axes": {"preset": ["igpu", "dgpu"], "algo": ["mlab", "adaptive", "wboit"], "layers": [2, 4]}
})";

class ReportBrowser : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir("report_browser");
    writeText(dir_->file("spec.json"), kBrowserSpec);
    sweep_ = new CliResult(runOitsim("sweep -q " + dir_->file("spec.json") + " --out " + dir_->file("sw") + " -j 2"));
    if (sweep_->exit_code == 0 && haveMatplotlib()) report_ = new CliResult(runOitsim("report " + dir_->file("sw")));
  }
  static void TearDownTestSuite() {
    delete report_;
    delete sweep_;
    delete dir_;
  }
  void SetUp() override {
    ASSERT_EQ(sweep_->exit_code, 0) << sweep_->output;
    if (!haveMatplotlib()) GTEST_SKIP() << "python3-matplotlib absent (scripts/setup.sh installs it)";
    ASSERT_EQ(report_->exit_code, 0) << report_->output;
  }
  static std::string chromium(const std::string& args) {
    const std::string profile = dir_->file("chromium-profile");
    return "/usr/bin/chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run "
           "--disable-background-networking --disable-component-update --disable-sync --hide-scrollbars "
           "--user-data-dir=" + profile + " " + args;
  }
  // The probe's findings on a copy of the page (with `extra_css` added) at `width`.
  static nlohmann::json probe(int width, const std::string& name, const std::string& extra_css = "") {
    std::string page = readText(dir_->file("sw/report.html"));
    const std::string script = readText(std::string(OITSIM_SOURCE_DIR) + "/tests/apps/data/report_probe.js");
    page.replace(page.rfind("</body>"), 7, "<style>" + extra_css + "</style><script>" + script + "</script></body>");
    const std::string copy = dir_->file("sw/" + name + ".html");  // beside the page: same relative links
    writeText(copy, page);
    const std::string dom = dir_->file(name + ".dom");
    const int rc = std::system((chromium("--virtual-time-budget=20000 --window-size=" + std::to_string(width) +
                                         ",1000 --dump-dom file://" + copy) + " > " + dom + " 2>/dev/null").c_str());
    EXPECT_EQ(rc, 0);
    std::smatch m;
    const std::string text = readText(dom);
    if (!std::regex_search(text, m, std::regex("<pre id=\"probe-result\">([^<]*)</pre>"))) {
      ADD_FAILURE() << "no probe result in the DOM of " << copy;
      return nlohmann::json::object();
    }
    std::string json = m[1].str();  // --dump-dom escapes &, < and > in text
    for (const auto& [from, to] : {std::pair<std::string, std::string>{"&quot;", "\""}, {"&lt;", "<"}, {"&gt;", ">"},
                                   {"&amp;", "&"}})
      for (size_t at = json.find(from); at != std::string::npos; at = json.find(from, at + 1)) json.replace(at, from.size(), to);
    return nlohmann::json::parse(json);
  }
  void checkSections();
  void checkLayout();
  void checkProbeDetects();
  void checkScreenshots();
  static TempDir* dir_;
  static CliResult *sweep_, *report_;
};
TempDir* ReportBrowser::dir_ = nullptr;
CliResult* ReportBrowser::sweep_ = nullptr;
CliResult* ReportBrowser::report_ = nullptr;

void ReportBrowser::checkSections() {
  const std::string page = readText(dir_->file("sw/report.html"));
  for (const char* s : {"<h2 id='hardware'>Hardware configurations</h2>", "<h3>Where the time goes</h3>",
                        "<h3>Cost against image error</h3>", "<h3>Against k and the other numeric axes</h3>",
                        "<h3>Memory (as the MLAB paper's Table 1)</h3>", "<h3>Images</h3>", "<h3>Depth complexity</h3>",
                        "<h2 id='points'>All points</h2>", "Download this table as CSV", "bound by (share of frame)",
                        "FLIP error per pixel"})
    EXPECT_NE(page.find(s), std::string::npos) << s;
  // No test artefact (it said "48 of 48 images decoded"), nothing from the network.
  EXPECT_EQ(page.find("render-check"), std::string::npos);
  EXPECT_EQ(page.find("images decoded"), std::string::npos);
  EXPECT_EQ(page.find("src=\"http"), std::string::npos);
  EXPECT_EQ(page.find("src='http"), std::string::npos);
  // Every thumbnail links to its full-size PNG beside the page.
  EXPECT_NE(page.find("href=\"points/0000-particles-igpu-mlab-2/image.png\""), std::string::npos);
  EXPECT_NE(page.find("href=\"points/0000-particles-igpu-mlab-2/flip.png\""), std::string::npos);
  // Progress while it worked (stderr), then the summary.
  EXPECT_NE(report_->output.find("report: particles: cost against FLIP ("), std::string::npos) << report_->output;
  EXPECT_NE(report_->output.find("sweep: 20 points, 20 ok, 0 failed;"), std::string::npos) << report_->output;
}

void ReportBrowser::checkLayout() {
  const std::string page = readText(dir_->file("sw/report.html"));
  size_t imgs = 0;
  for (size_t at = page.find("<img "); at != std::string::npos; at = page.find("<img ", at + 1)) ++imgs;
  for (int width : {1400, 1920}) {
    const nlohmann::json r = probe(width, "probe" + std::to_string(width));
    SCOPED_TRACE("width " + std::to_string(width) + ": " + r.dump());
    EXPECT_EQ(r["innerWidth"].get<int>(), width);
    EXPECT_LE(r["scrollWidth"].get<int>(), width) << "horizontal overflow";
    EXPECT_EQ(r["images"].get<size_t>(), imgs - 1) << "the probe saw another number of images than the page has";
    EXPECT_TRUE(r["broken"].empty()) << "images that did not decode";
    // Per scene: mlab and adaptive at k = 2 and 4, and wboit.
    EXPECT_EQ(r["grid_cells"].get<int>(), 2 * 5);
    EXPECT_TRUE(r["misaligned"].empty());
    EXPECT_TRUE(r["outside"].empty());
    EXPECT_EQ(r["sort"], "ok");
    EXPECT_EQ(r["sorted_rows"].get<int>(), 20);
    EXPECT_GE(r["plots"].get<int>(), 2 * 6);  // per scene: phases, stalls, lock, 2 Pareto, k curves, heatmap
    EXPECT_TRUE(r["unlabelled"].empty());
    EXPECT_EQ(r["viewer"], "ok");
  }
}

// The probe finds what it looks for: a difference image shifted off its image,
// and a page wider than the window.
void ReportBrowser::checkProbeDetects() {
  const nlohmann::json r = probe(1400, "broken", ".grid img.diff{margin-left:40px}body{min-width:2000px}");
  EXPECT_EQ(r["misaligned"].size(), 10u) << r.dump();
  EXPECT_GT(r["scrollWidth"].get<int>(), 1400) << r.dump();
}

void ReportBrowser::checkScreenshots() {
  for (int width : {1400, 1920}) {
    const std::string shot = dir_->file("shot" + std::to_string(width) + ".png");
    ASSERT_EQ(std::system((chromium("--screenshot=" + shot + " --window-size=" + std::to_string(width) +
                                    ",3000 file://" + dir_->file("sw/report.html")) + " >/dev/null 2>&1").c_str()),
              0);
    // Non-white share (plots, tables, images, not just text), with Debian's python3.
    const CliResult r = runShell("/usr/bin/python3 -c \"import matplotlib.image as m, sys; "
                                 "a = m.imread(sys.argv[1])[:, :, :3]; print(a.shape[1], a.shape[0], "
                                 "(a.min(axis=2) < 0.9).mean())\" " + shot);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    std::istringstream in(r.output);
    int w = 0, h = 0;
    double share = 0;
    in >> w >> h >> share;
    EXPECT_EQ(w, width);
    EXPECT_EQ(h, 3000);
    EXPECT_GT(share, 0.05) << shot << " is mostly blank";
  }
}

// One test: ctest runs each test in its own process, and the suite's sweep and
// report are most of its time.
TEST_F(ReportBrowser, SectionsLayoutSortingViewerAndScreenshots) {
  {
    SCOPED_TRACE("sections");
    checkSections();
  }
  if (!fs::exists("/usr/bin/chromium")) GTEST_SKIP() << "chromium is absent (scripts/setup.sh installs it)";
  {
    SCOPED_TRACE("layout at 1400 and 1920 px");
    checkLayout();
  }
  {
    SCOPED_TRACE("the probe detects misalignment and overflow");
    checkProbeDetects();
  }
  {
    SCOPED_TRACE("screenshots");
    checkScreenshots();
  }
}

}  // namespace
}  // namespace oit::test
