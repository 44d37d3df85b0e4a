// oitsim: command-line entry. SystemC's library owns main() and calls sc_main().
#include <CLI/CLI.hpp>
#include <fmt/core.h>

#include <charconv>
#include <cstdint>
#include <cstdio>
#include <string>
#include <system_error>
#include <cstdlib>
#include <stdlib.h>
#include <exception>
#include <new>

#include "apps/Commands.hpp"
#include "oit_rop/SystemcInfo.hpp"
#include "traces/TempFiles.hpp"

// libsystemc's entry (C linkage), normally called by its own main().
extern "C" int sc_elab_and_sim(int argc, char* argv[]);

extern "C" int sc_main(int argc, char* argv[]) {
  oit::cli::setCommandLine(argc, argv);
  oit::removeTempFilesOnSignals();  // an interrupt leaves no partial outputs
  CLI::App app{"oitsim: cycle-approximate GPU ROP model for order-independent transparency"};
  app.set_version_flag("--version",
                       std::string("oitsim ") + OITSIM_VERSION + " (SystemC " + oit::rop::systemcRelease() + ")");
  app.require_subcommand(1);
  oit::cli::addGenCommand(app);
  oit::cli::addScenesCommand(app);
  oit::cli::addCaptureCommand(app);
  oit::cli::addInfoCommand(app);
  oit::cli::addConvertCommand(app);
  oit::cli::addRunCommand(app);
  oit::cli::addStressCommand(app);
  oit::cli::addConfigCommand(app);
  oit::cli::addSweepCommand(app);
  oit::cli::addReportCommand(app);
  // Unsigned options take digits only (unsignedText()); options with a range
  // already check the digits in their unsignedRange().
  const CLI::Validator unsigned_text = oit::cli::unsignedText();
  for (CLI::App* sub : app.get_subcommands({}))
    for (CLI::Option* o : sub->get_options())
      if (o->get_type_name() == "UINT") o->check(unsigned_text);
  // CLI11 takes an unknown first word for a stray argument and says only "A
  // subcommand is required": name it and the subcommands instead.
  if (argc > 1 && argv[1][0] != '-') {
    std::string names;
    bool known = false;
    for (CLI::App* sub : app.get_subcommands({})) {
      known = known || sub->check_name(argv[1]);
      names += (names.empty() ? "" : ", ") + sub->get_name();
    }
    if (!known) {
      fmt::print(stderr, "oitsim: error: unknown subcommand '{}' (expected one of {}; see --help)\n", argv[1], names);
      return 1;
    }
  }
  // An option before the subcommand that oitsim itself does not have (CLI11
  // said "A subcommand is required", or went on to the subcommand's errors).
  if (argc > 1 && argv[1][0] == '-') {
    const std::string given(argv[1]);
    const std::string name = given.substr(0, given.find('='));
    bool known = false;
    for (const CLI::Option* o : app.get_options()) known = known || o->check_name(name);
    if (!known) {
      fmt::print(stderr,
                 "oitsim: error: unknown option '{}' before the subcommand (oitsim takes --help and --version; "
                 "a subcommand's options go after it, e.g. oitsim run --help)\n",
                 name);
      return 1;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ConversionError& e) {
    // "Could not convert: --width = 4294967297": a number too large for the
    // option's type (the digits-only check above lets up to 2^64 - 1 through).
    std::fflush(stdout);
    std::string what = e.what();
    const std::string prefix = "Could not convert: ";
    if (what.rfind(prefix, 0) == 0) {
      what = what.substr(prefix.size());
      const size_t eq = what.find(" = ");
      if (eq != std::string::npos) what = what.substr(0, eq) + " " + what.substr(eq + 3);
      what += ": not a value this option takes (too large?)";
    }
    fmt::print(stderr, "oitsim: error: {} (see --help)\n", what);
    return 1;
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    // One line naming the option, exit code 1, as for every other bad input.
    std::fflush(stdout);
    fmt::print(stderr, "oitsim: error: {} (see --help)\n", e.what());
    return 1;
  } catch (const std::bad_alloc&) {
    // `run` names the frame and what it needed; elsewhere say at least what happened.
    std::fflush(stdout);
    fmt::print(stderr, "oitsim: error: out of memory: an allocation failed (check `ulimit -v` and the frame's size)\n");
    return 1;
  } catch (const std::exception& e) {
    // Subcommand callbacks throw on bad input; the message names file, offset or option.
    std::fflush(stdout);
    fmt::print(stderr, "oitsim: error: {}\n", e.what());
    return 1;
  }
  return 0;
}

// Our own main, ahead of libsystemc's: it silences SystemC's banner (reports
// and summaries are oitsim's own; `oitsim --version` names the SystemC release)
// and then enters SystemC as its main would.
int main(int argc, char* argv[]) {
  setenv("SYSTEMC_DISABLE_COPYRIGHT_MESSAGE", "1", 0);
  return sc_elab_and_sim(argc, argv);
}
