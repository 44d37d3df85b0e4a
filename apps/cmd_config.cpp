// oitsim config: the effective model configuration after preset, config file
// and --set overrides, as an aligned table or JSON (the JSON is a valid
// --config file). --markdown prints every preset side by side for CONFIG.md.
#include <fmt/core.h>

#include <memory>
#include <string>
#include <vector>

#include "apps/Commands.hpp"
#include "oit_rop/ConfigTree.hpp"

namespace oit::cli {
namespace {

struct ConfigArgs {
  std::string preset;  // empty: the file's "preset" key, else igpu
  std::string config_file;
  std::vector<std::string> sets;
  bool json = false;
  bool markdown = false;
};

void runConfig(const ConfigArgs& a) {
  if (a.markdown) {
    fmt::print("{}", rop::presetTableMarkdown());
    return;
  }
  const rop::ConfigTree tree = rop::resolveTree(a.preset, a.config_file, a.sets);
  if (a.json)
    fmt::print("{}\n", tree.toJson().dump(2));
  else
    fmt::print("{}", tree.describe());
}

}  // namespace

void addConfigCommand(CLI::App& app) {
  auto a = std::make_shared<ConfigArgs>();
  CLI::App* cmd = app.add_subcommand("config", "Print the effective model configuration (preset < file < --set)");
  std::string names;
  for (const auto& n : rop::presetNames()) names += (names.empty() ? "" : ", ") + n;
  cmd->add_option("--preset,-p", a->preset, "Hardware preset: " + names + " (default igpu, or the file's \"preset\")");
  cmd->add_option("--config,-c", a->config_file, "JSON file of property values, nested or dotted keys");
  cmd->add_option("--set,-s", a->sets, "Override one property: path=value (repeatable)")->take_all();
  cmd->add_flag("--json", a->json, "Print the effective tree as JSON (usable as --config)");
  cmd->add_flag("--markdown", a->markdown, "Print all presets side by side as a Markdown table");
  cmd->callback([a] { runConfig(*a); });
}

}  // namespace oit::cli
