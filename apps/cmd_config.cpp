// oitsim config: the effective model configuration after preset, config file
// and --set overrides, as an aligned table or JSON (the JSON is a valid
// --config file). --markdown prints every preset side by side for CONFIG.md.
#include <fmt/core.h>

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "apps/Commands.hpp"
#include "oit_rop/config/ConfigTree.hpp"

namespace oit::cli {
namespace {

struct ConfigArgs {
  std::string preset;  // empty: the file's "preset" key, else iris-pro-5200
  std::string config_file;
  std::vector<std::string> sets;
  bool json = false;
  bool markdown = false;
};

void runConfig(const ConfigArgs& a, const CLI::App& cmd) {
  if (a.markdown) {
    // The table is every preset's defaults: an option that changes one
    // configuration has nothing to apply to, and would pass unchecked.
    std::string given;
    for (const char* opt : {"--preset", "--config", "--set", "--json"})
      if (cmd.count(opt)) given += (given.empty() ? "" : ", ") + std::string(opt);
    if (!given.empty())
      throw std::invalid_argument("--markdown prints every preset's defaults and takes no --preset, --config, --set "
                                  "or --json (given: " + given + ")");
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
  cmd->add_option("--preset,-p", a->preset,
                  "Hardware preset: " + names + " (aliases igpu, dgpu; default iris-pro-5200, or the file's \"preset\")");
  cmd->add_option("--config,-c", a->config_file, "JSON file of property values, nested or dotted keys");
  cmd->add_option("--set,-s", a->sets, "Override one property: path=value (repeatable)")->take_all();
  cmd->add_flag("--json", a->json, "Print the effective tree as JSON (usable as --config)");
  cmd->add_flag("--markdown", a->markdown,
                "Print all presets' defaults side by side as a Markdown table (alone: no --preset, --config, --set, "
                "--json)");
  cmd->callback([a, cmd] { runConfig(*a, *cmd); });
}

}  // namespace oit::cli
