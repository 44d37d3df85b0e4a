// The top-level command line and `oitsim config`: one-line errors naming what
// was wrong, exit code 1.
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <sstream>
#include <string>

#include "CliRunner.hpp"

namespace oit::test {
namespace {

TEST(CliCommands, UnknownSubcommandIsNamed) {
  CliResult r = runOitsim("bogus");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(lines(r.output).size(), 1u) << r.output;
  EXPECT_EQ(r.output.rfind("oitsim: error: unknown subcommand 'bogus' (expected one of gen, scenes, ", 0), 0u)
      << r.output;
  // No subcommand at all is still CLI11's message.
  r = runOitsim("");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("A subcommand is required"), std::string::npos) << r.output;
  // A known one still runs.
  r = runOitsim("scenes");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  // An unknown option before the subcommand is named (it was "A subcommand is
  // required", or the subcommand's own errors when one followed).
  for (const char* args : {"--bogus", "--bogus run", "--bogus=1 scenes"}) {
    r = runOitsim(args);
    EXPECT_EQ(r.exit_code, 1) << args;
    EXPECT_EQ(r.output.rfind("oitsim: error: unknown option '--bogus' before the subcommand", 0), 0u)
        << args << ": " << r.output;
  }
  r = runOitsim("--version");
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

// --markdown prints every preset's defaults; options that pick one
// configuration are refused instead of passing unchecked.
TEST(CliCommands, ConfigMarkdownTakesNoConfigurationOptions) {
  CliResult r = runOitsim("config --markdown");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("| iris-pro-5200 |"), std::string::npos) << r.output.substr(0, 500);
  for (const std::string& extra : {std::string("--set nosuch=1"), std::string("--preset xyz"),
                                   std::string("--config /nonexistent.json"), std::string("--json")}) {
    r = runOitsim("config --markdown " + extra);
    EXPECT_EQ(r.exit_code, 1) << extra << "\n" << r.output;
    EXPECT_EQ(lines(r.output).size(), 1u) << extra << "\n" << r.output;
    EXPECT_EQ(r.output.rfind("oitsim: error: --markdown prints every preset's defaults and takes no --preset, "
                             "--config, --set or --json (given: " + extra.substr(0, extra.find(' ')) + ")", 0),
              0u)
        << r.output;
  }
  r = runOitsim("config --markdown --set nosuch=1 --preset xyz --config /nonexistent.json");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("(given: --preset, --config, --set)"), std::string::npos) << r.output;
}

// CONFIG.md's table of every property and preset is `oitsim config
// --markdown`'s output: a property, default, range or inferred mark changed in
// the code and not in the document fails here, naming the row.
TEST(CliCommands, ConfigDocumentHoldsTheGeneratedTable) {
  CliResult r = runOitsim("config --markdown");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(std::string(OITSIM_SOURCE_DIR) + "/oit_rop/config/CONFIG.md");
  ASSERT_TRUE(in) << "cannot read oit_rop/config/CONFIG.md";
  const std::string doc((std::istreambuf_iterator<char>(in)), {});
  size_t rows = 0;
  for (const std::string& line : lines(r.output)) {
    if (line.rfind("| `", 0) != 0) continue;  // the property rows
    ++rows;
    EXPECT_NE(doc.find(line + "\n"), std::string::npos)
        << "CONFIG.md lacks (or has another version of) this row; regenerate its table with `oitsim config "
           "--markdown`:\n"
        << line;
  }
  EXPECT_GT(rows, 90u) << r.output.substr(0, 500);
  // The page's count of them too ("... --markdown` (N properties)").
  std::ostringstream count;  // (not "(" + ...: g++ 12's false -Wrestrict on string concatenation)
  count << '(' << rows << " properties)";
  EXPECT_NE(doc.find(count.str()), std::string::npos) << "CONFIG.md should say " << count.str();
}

}  // namespace
}  // namespace oit::test
