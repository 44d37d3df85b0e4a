// Runs the built oitsim executable (through RunShell.hpp) and captures its exit code and output;
// file and CSV helpers shared by the CLI tests.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "RunShell.hpp"

namespace oit::test {

inline std::string oitsimPath() { return std::string(OITSIM_BINARY_DIR) + "/apps/oitsim"; }

inline CliResult runOitsim(const std::string& args) { return runShell(oitsimPath() + " " + args); }

// Optional Python modules: `oitsim report` draws with matplotlib (and numpy);
// YAML sweep specs need PyYAML. Tests that need them skip, naming what is absent.
inline bool haveMatplotlib() {
  return std::system("/usr/bin/python3 -c 'import matplotlib, numpy' >/dev/null 2>&1") == 0;
}
inline bool haveYaml() { return std::system("/usr/bin/python3 -c 'import yaml' >/dev/null 2>&1") == 0; }

inline std::string readText(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline void writeText(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

inline nlohmann::json readJson(const std::filesystem::path& path) { return nlohmann::json::parse(readText(path)); }

inline std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

// Splits a CSV line as results.csv writes it (quoted fields may hold commas
// and doubled quotes).
inline std::vector<std::string> csvSplit(const std::string& line) {
  std::vector<std::string> out;
  std::string cur;
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        cur += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        cur += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.push_back(cur);
  return out;
}

// Compares two sweep results.csv tables (as lines) cell by cell, except the
// columns that differ by nature: wall clock, measured memory, and the paths
// and command line that name the output folder. Returns the number of cells compared (0 after
// a failed assertion on the table's shape).
inline size_t compareSweepTables(const std::vector<std::string>& a, const std::vector<std::string>& b) {
  size_t compared = 0;
  [&] {
    ASSERT_FALSE(a.empty());
    ASSERT_EQ(a.size(), b.size());
    ASSERT_EQ(a[0], b[0]);
    const auto header = csvSplit(a[0]);
    for (size_t i = 1; i < a.size(); ++i) {
      const auto ra = csvSplit(a[i]), rb = csvSplit(b[i]);
      ASSERT_EQ(ra.size(), header.size());
      ASSERT_EQ(rb.size(), header.size());
      for (size_t c = 0; c < header.size(); ++c) {
        const std::string& h = header[c];
        if (h.find("wall_seconds") != std::string::npos || h.find("per_second") != std::string::npos ||
            h.rfind("sim.memory.", 0) == 0 || h == "trace.path" || h == "oitsim.command")
          continue;
        EXPECT_EQ(ra[c], rb[c]) << "row " << i << " column " << h;
        ++compared;
      }
    }
  }();
  return compared;
}

// A fresh directory under the test's working directory, removed on destruction.
// The pid keeps tests that ctest runs in parallel processes apart.
class TempDir {
 public:
  explicit TempDir(const std::string& name)
      : path_(std::filesystem::current_path() / ("tmp_" + name + "_" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// A test suite sharing one generated trace, made once per suite: Tag names
// the suite's folder (kFolder), the trace's file name (kFile) and the
// `oitsim gen` arguments (kGen, without -o).
template <class Tag>
class GeneratedTraceSuite : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir(Tag::kFolder);
    trace_ = dir_->file(Tag::kFile);
    CliResult r = runOitsim(std::string(Tag::kGen) + " -o " + trace_);
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static inline TempDir* dir_ = nullptr;
  static inline std::string trace_;
};

}  // namespace oit::test
