// End-to-end tests of `oitsim info` and `oitsim convert` on the real executable.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <sstream>

#include "CliRunner.hpp"
#include "apps/TraceOptions.hpp"

namespace oit::test {
namespace {

// 4x2 frame. Pixel (1,0) gets 3 transparent fragments, (2,1) one transparent
// and one opaque, (3,1) one transparent.
const char* kCsv =
    "draw,prim,x,y,z,r,g,b,a,opaque\n"
    "0,0,2,1,0.9,0.5,0.5,0.5,1,1\n"
    "1,0,1,0,0.5,1,0,0,0.5,0\n"
    "1,1,1,0,0.25,0,1,0,0.25,0\n"
    "1,2,1,0,0.75,0,0,1,0.125,0\n"
    "1,3,2,1,0.1,1,1,1,0.5,0\n"
    "1,3,3,1,0.1,1,1,1,0.5,0\n";

TEST(CliInfo, CsvStatisticsAsJson) {
  TempDir dir("info_json");
  writeText(dir.file("t.csv"), kCsv);
  CliResult r = runOitsim("info " + dir.file("t.csv") + " --width 4 --height 2 --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["format"], "csv");
  EXPECT_EQ(j["width"], 4);
  EXPECT_EQ(j["height"], 2);
  EXPECT_EQ(j["fragments"], 6);
  // ".CSV" is read as CSV, and info says so (it called it binary).
  writeText(dir.file("T.CSV"), kCsv);
  CliResult upper = runOitsim("info " + dir.file("T.CSV") + " --width 4 --height 2 --json");
  ASSERT_EQ(upper.exit_code, 0) << upper.output;
  EXPECT_EQ(nlohmann::json::parse(upper.output)["format"], "csv");
  ASSERT_EQ(j["draws"].size(), 2u);
  EXPECT_EQ(j["draws"][0]["class"], "opaque");
  EXPECT_EQ(j["draws"][0]["fragments"], 1);
  EXPECT_EQ(j["draws"][1]["class"], "transparent");
  EXPECT_EQ(j["draws"][1]["fragments"], 5);
  EXPECT_EQ(j["draws"][0]["primitives_at_least"], 1);  // prim ids 0 and 0..3, as the table's prims>=
  EXPECT_EQ(j["draws"][1]["primitives_at_least"], 4);
  const auto& t = j["depth_complexity"]["transparent"];
  EXPECT_EQ(t["covered_pixels"], 3);
  EXPECT_EQ(t["max"], 3);
  EXPECT_EQ(t["max_at"][0], 1);
  EXPECT_EQ(t["max_at"][1], 0);
  EXPECT_DOUBLE_EQ(t["mean"].get<double>(), 5.0 / 3.0);
  EXPECT_EQ(t["histogram"][0]["pixels"], 2);  // depth complexity 1
  EXPECT_EQ(t["histogram"][2]["pixels"], 1);  // 3-4
  const auto& all = j["depth_complexity"]["all"];
  EXPECT_EQ(all["covered_pixels"], 3);
  EXPECT_EQ(all["histogram"][1]["pixels"], 1);  // pixel (2,1): 2 fragments
}

TEST(CliInfo, HumanReadableSummary) {
  TempDir dir("info_text");
  writeText(dir.file("t.csv"), kCsv);
  CliResult r = runOitsim("info " + dir.file("t.csv") + " --width 4 --height 2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("4 x 2 (8 pixels)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("fragments    6 (5 transparent, 1 opaque)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("mean 1.67, max 3 at (1, 0)"), std::string::npos) << r.output;
}

TEST(CliInfo, CsvWithoutFrameSizeAsksForIt) {
  TempDir dir("info_nosize");
  writeText(dir.file("t.csv"), kCsv);
  CliResult r = runOitsim("info " + dir.file("t.csv"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("--width"), std::string::npos) << r.output;
}

TEST(CliConvert, CsvBinaryRoundTripsAreLossless) {
  TempDir dir("convert");
  writeText(dir.file("t.csv"), kCsv);
  ASSERT_EQ(runOitsim("convert " + dir.file("t.csv") + " " + dir.file("a.oitt") + " --width 4 --height 2").exit_code, 0);
  ASSERT_EQ(runOitsim("convert " + dir.file("a.oitt") + " " + dir.file("b.csv")).exit_code, 0);
  ASSERT_EQ(runOitsim("convert " + dir.file("b.csv") + " " + dir.file("c.oitt")).exit_code, 0);
  ASSERT_EQ(runOitsim("convert " + dir.file("c.oitt") + " " + dir.file("d.csv")).exit_code, 0);
  const std::string a = readText(dir.file("a.oitt")), c = readText(dir.file("c.oitt"));
  EXPECT_EQ(a.size(), c.size());
  EXPECT_TRUE(a == c) << "binary -> CSV -> binary changed bytes";
  EXPECT_EQ(readText(dir.file("b.csv")), readText(dir.file("d.csv")));
  // Every data row of the hand-written CSV survives unchanged.
  const std::string b = readText(dir.file("b.csv"));
  std::istringstream rows(kCsv);
  for (std::string line; std::getline(rows, line);)
    EXPECT_NE(b.find(line + "\n"), std::string::npos) << "missing row: " << line << "\n" << b;
}

TEST(CliInfo, TruncatedBinaryFailsNamingByteOffset) {
  TempDir dir("truncated");
  writeText(dir.file("t.csv"), kCsv);
  ASSERT_EQ(runOitsim("convert " + dir.file("t.csv") + " " + dir.file("t.oitt") + " --width 4 --height 2").exit_code, 0);
  std::string bytes = readText(dir.file("t.oitt"));
  const size_t cut = bytes.size() - 10;  // last record loses 10 of its 32 bytes
  writeText(dir.file("cut.oitt"), bytes.substr(0, cut));
  CliResult r = runOitsim("info " + dir.file("cut.oitt"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("cut.oitt"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("byte offset " + std::to_string(cut)), std::string::npos) << r.output;
}

// No output may be the input trace: not the same path string, not another
// spelling of it, not a symlink to it (the input survives byte for byte).
TEST(CliInfoConvert, OutputsNeverOverwriteTheInput) {
  TempDir dir("out_is_input");
  ASSERT_EQ(runOitsim("gen glass -q -o " + dir.file("s.oitt") + " --width 64 --height 48").exit_code, 0);
  const std::string original = readText(dir.file("s.oitt"));
  std::filesystem::create_symlink("s.oitt", dir.path() / "link.oitt");
  const std::string dotted = (dir.path() / "." / "s.oitt").string();

  CliResult heat = runOitsim("info " + dir.file("s.oitt") + " --heatmap " + dotted);
  EXPECT_EQ(heat.exit_code, 1) << heat.output;
  EXPECT_NE(heat.output.find("--heatmap " + dotted + ": is the input trace"), std::string::npos) << heat.output;
  EXPECT_EQ(lines(heat.output).size(), 1u) << heat.output;
  CliResult heat_link = runOitsim("info " + dir.file("s.oitt") + " --heatmap " + dir.file("link.oitt"));
  EXPECT_EQ(heat_link.exit_code, 1) << heat_link.output;
  EXPECT_NE(heat_link.output.find("--heatmap"), std::string::npos) << heat_link.output;

  for (const std::string& out : {dotted, dir.file("link.oitt"), dir.file("s.oitt")}) {
    CliResult r = runOitsim("convert " + dir.file("s.oitt") + " " + out);
    EXPECT_EQ(r.exit_code, 1) << out << ": " << r.output;
    EXPECT_NE(r.output.find("output " + out + ": is the input trace"), std::string::npos) << r.output;
  }
  EXPECT_TRUE(readText(dir.file("s.oitt")) == original) << "the input trace was changed";
  EXPECT_TRUE(std::filesystem::is_symlink(dir.path() / "link.oitt"));
  // A different file is fine.
  EXPECT_EQ(runOitsim("info " + dir.file("s.oitt") + " --heatmap " + dir.file("h.pfm")).exit_code, 0);
  EXPECT_EQ(runOitsim("convert " + dir.file("s.oitt") + " " + dir.file("c.oitt")).exit_code, 0);
}

// A draw name that is not UTF-8 is refused by every command with the same
// located message (info and convert passed it on; info --json and run then
// failed with a bare "[json.exception.type_error.316]" naming no file).
TEST(CliInfoConvert, NonUtf8DrawNameIsRefusedEverywhere) {
  TempDir dir("bad_utf8");
  ASSERT_EQ(runOitsim("gen glass -q -o " + dir.file("g.oitt") + " --width 64 --height 48").exit_code, 0);
  std::string bytes = readText(dir.file("g.oitt"));
  bytes[72] = '\xFF';  // first byte of draw 0's name
  writeText(dir.file("bad.oitt"), bytes);
  writeText(dir.file("bad.csv"), "# width 4\n# height 2\n# draw 1 transparent \"\xC3\x28\"\n" + std::string(kCsv));
  const std::string bin_msg = dir.file("bad.oitt") +
                              ": byte offset 72, field draw[0].name: name is not valid UTF-8: byte 0xFF at index 0";
  const std::string csv_msg = dir.file("bad.csv") +
                              ": line 3, byte offset 42, field draw: name is not valid UTF-8: byte 0xC3 at index 0";
  for (const auto& [file, msg] : {std::pair{dir.file("bad.oitt"), bin_msg}, {dir.file("bad.csv"), csv_msg}}) {
    for (const std::string& cmd :
         {"info " + file, "info --json " + file, "convert " + file + " " + dir.file("out.oitt"),
          "convert " + file + " " + dir.file("out.csv"), "run --mode functional --trace " + file + " --out " + dir.file("r"),
          "run --trace " + file + " --out " + dir.file("r")}) {
      CliResult r = runOitsim(cmd);
      EXPECT_EQ(r.exit_code, 1) << cmd << "\n" << r.output;
      EXPECT_NE(r.output.find(msg), std::string::npos) << cmd << "\n" << r.output;
      EXPECT_EQ(r.output.find("json.exception"), std::string::npos) << cmd << "\n" << r.output;
    }
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("out.oitt")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("out.csv")));
}

// A CSV with more distinct draws than a trace may hold is refused by the CSV
// reader at the row that adds one too many, in every command (info and run
// accepted it, and convert blamed its output: "c.oitt: byte offset 52, field
// draw_count: 1048577 draws").
TEST(CliInfoConvert, TooManyCsvDrawsAreRefusedAtTheRow) {
  TempDir dir("many_draws");
  std::string text = "# width 1\n# height 1\ndraw,prim,x,y,z,r,g,b,a,opaque\n";
  for (uint32_t i = 0; i < (1u << 20); ++i) text += std::to_string(i) + ",0,0,0,0,0,0,0,0,0\n";
  const size_t offset = text.size();
  text += "1048576,0,0,0,0,0,0,0,0,0\n";
  writeText(dir.file("m.csv"), text);
  const std::string msg = dir.file("m.csv") + ": line 1048580, byte offset " + std::to_string(offset) +
                          ", record 1048576, column draw: draw 1048576 would be draw number 1048577 of the trace";
  for (const std::string& cmd : {"info " + dir.file("m.csv"), "convert " + dir.file("m.csv") + " " + dir.file("c.oitt"),
                                 "run --mode functional --trace " + dir.file("m.csv") + " --out " + dir.file("r")}) {
    CliResult r = runOitsim(cmd);
    EXPECT_EQ(r.exit_code, 1) << cmd << "\n" << r.output;
    EXPECT_NE(r.output.find(msg), std::string::npos) << cmd << "\n" << r.output;
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("c.oitt")));
}

// convert's output and info --heatmap are checked before the trace is read.
TEST(CliInfoConvert, OutputPathsAreCheckedFirst) {
  TempDir dir("bad_outputs");
  writeText(dir.file("t.csv"), kCsv);
  const std::string in = dir.file("t.csv") + " --width 4 --height 2";
  struct Case {
    std::string cmd, message;
  };
  const Case cases[] = {
      {"convert " + in + " ''", "output: expected a file name, got an empty path"},
      {"convert " + in + " " + dir.file(""), "output " + dir.file("") + ": is a directory, expected a file name"},
      {"convert " + in + " " + dir.file("no/c.oitt"), "output " + dir.file("no/c.oitt") + ": folder " +
                                                          dir.file("no") + " does not exist"},
      {"info " + in + " --heatmap ''", "--heatmap: expected a file name, got an empty path"},
      {"info " + in + " --heatmap " + dir.file(""), "--heatmap " + dir.file("") + ": is a directory, expected a file name"},
      {"info " + in + " --heatmap " + dir.file("no/h.pfm"), "--heatmap " + dir.file("no/h.pfm") + ": folder " +
                                                                dir.file("no") + " does not exist"},
      // It writes PFM only; a PNG name held a PFM.
      {"info " + in + " --heatmap " + dir.file("h.png"), "--heatmap " + dir.file("h.png") +
                                                             ": expected a file name ending in .pfm (the heatmap is a "
                                                             "PFM image; no other format)"},
      {"info " + in + " --heatmap " + dir.file("h"), "--heatmap " + dir.file("h") +
                                                         ": expected a file name ending in .pfm (the heatmap is a PFM "
                                                         "image; no other format)"},
  };
  for (const Case& c : cases) {
    CliResult r = runOitsim(c.cmd);
    EXPECT_EQ(r.exit_code, 1) << c.cmd << "\n" << r.output;
    EXPECT_EQ(r.output, "oitsim: error: " + c.message + "\n") << c.cmd;
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("h.png")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("h")));
}

// A binary or gzipped trace named .csv is named as such, an empty .csv fails
// on line 1, and no message carries raw non-text bytes.
TEST(CliInfoConvert, CsvMessagesAreTextAndNameBinaryForms) {
  TempDir dir("csv_binary_forms");
  ASSERT_EQ(runOitsim("gen glass -q -o " + dir.file("g.oitt") + " --width 64 --height 48").exit_code, 0);
  writeText(dir.file("g.csv"), readText(dir.file("g.oitt")));
  writeText(dir.file("z.csv"), std::string("\x1F\x8B\x08\x00\x00\x00\x00\x00\x00\x03\xED\xC1\xFF", 13));
  writeText(dir.file("e.csv"), "");
  const std::pair<std::string, std::string> cases[] = {
      {"g.csv", ": line 1, byte offset 0, field header: found 89 4F 49 54 54 0D 0A 1A, the magic of a binary "
                "trace: this looks like a binary .oitt trace"},
      {"z.csv", ": line 1, byte offset 0, field header: found 1F 8B 08 00 00 00 00 00: the file is "
                "gzip-compressed: decompress first (gunzip)"},
      {"e.csv", ": line 1, byte offset 0, field header: no column line"},
  };
  for (const auto& [name, msg] : cases) {
    for (const std::string& cmd : {"info " + dir.file(name), "convert " + dir.file(name) + " " + dir.file("o.oitt")}) {
      CliResult r = runOitsim(cmd + " --width 4 --height 4");
      EXPECT_EQ(r.exit_code, 1) << cmd << "\n" << r.output;
      EXPECT_NE(r.output.find(dir.file(name) + msg), std::string::npos) << cmd << "\n" << r.output;
      for (const char c : r.output) EXPECT_LT(static_cast<unsigned char>(c), 0x80) << cmd << "\n" << r.output;
    }
  }
}

// --width/--height of a CSV without size comments: 0 and values above 65535
// are errors naming the option and the range, in info and convert as in run
// (info and convert took --width 0 for absent and blamed 70000 on the file).
TEST(CliInfoConvert, FrameSizeOptionsAreCheckedLikeRun) {
  TempDir dir("size_options");
  writeText(dir.file("t.csv"), kCsv);
  const std::string t = dir.file("t.csv");
  const std::pair<std::string, std::string> cases[] = {
      {"--width 0 --height 2", "--width 0: expected a frame width of at least 1 pixel"},
      {"--width 4 --height 0", "--height 0: expected a frame height of at least 1 pixel"},
      {"--width 70000 --height 2", "--width 70000: expected a frame width of 1..65535 pixels (x and y are u16)"},
      {"--width 4 --height 65536", "--height 65536: expected a frame height of 1..65535 pixels (x and y are u16)"},
  };
  for (const auto& [opts, msg] : cases) {
    for (const std::string& cmd : {"info " + t, "convert " + t + " " + dir.file("o.oitt")}) {
      CliResult r = runOitsim(cmd + " " + opts);
      EXPECT_EQ(r.exit_code, 1) << cmd << " " << opts << "\n" << r.output;
      EXPECT_EQ(r.output, "oitsim: error: " + msg + "\n") << cmd << " " << opts;
    }
  }
  // run says the same for 0.
  CliResult run = runOitsim("run --mode functional --trace " + t + " --width 0 --height 2 --out " + dir.file("r"));
  EXPECT_EQ(run.output, "oitsim: error: --width 0: expected a frame width of at least 1 pixel\n");
  EXPECT_EQ(runOitsim("info " + t + " --width 4 --height 2 --json").exit_code, 0);
}

// A legal frame too large for this machine is an error naming the trace, the
// frame and the memory (it was a bare std::bad_alloc, or the kernel killed the
// process part way through).
TEST(CliInfoConvert, FrameTooLargeForThisMachineIsNamed) {
  const uint64_t need = uint64_t(65535) * 65535 * 12;  // info's per-pixel counts
  if (cli::machineMemoryBytes() == 0 || cli::machineMemoryBytes() >= need)
    GTEST_SKIP() << "this machine has room for a 65535 x 65535 frame";
  TempDir d("cli_huge");
  const std::string t = d.file("huge.csv");
  writeText(t, "# width 65535\n# height 65535\ndraw,prim,x,y,z,r,g,b,a,opaque\n0,0,1,1,0.5,1,0,0,0.5,0\n");
  CliResult r = runOitsim("info " + t);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output.rfind("oitsim: error: " + t + ": a 65535 x 65535 frame needs at least 48.0 GiB for its per-pixel "
                           "counts (12 B per pixel); this machine has ", 0), 0u) << r.output;
  r = runOitsim("run --mode functional -q -t " + t + " -o " + d.file("out"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find(": a 65535 x 65535 frame with mlab needs about "), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(d.file("out/report.json")));
}

}  // namespace
}  // namespace oit::test
