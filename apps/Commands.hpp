// Subcommands of the oitsim executable; each lives in apps/cmd_<name>.cpp and
// registers itself on the top-level CLI11 app.
#pragma once

#include <CLI/CLI.hpp>

namespace oit::cli {

void addGenCommand(CLI::App& app);      // oitsim gen SCENE -o FILE
void addInfoCommand(CLI::App& app);     // oitsim info TRACE
void addConvertCommand(CLI::App& app);  // oitsim convert IN OUT
void addRunCommand(CLI::App& app);      // oitsim run --trace T ...
void addScenesCommand(CLI::App& app);   // oitsim scenes

}  // namespace oit::cli
