#include <string>

#include "apps/Commands.hpp"

namespace oit::cli {
namespace {
std::string g_command_line;
}

void setCommandLine(int argc, char* argv[]) {
  g_command_line.clear();
  for (int i = 0; i < argc; ++i) {
    if (i) g_command_line += ' ';
    const std::string arg = argv[i];
    // Quote what a shell would split, so the recorded line can be pasted back.
    if (arg.empty() || arg.find_first_of(" \t\"'\\$") != std::string::npos) {
      g_command_line += '\'';
      for (char c : arg) g_command_line += c == '\'' ? std::string("'\\''") : std::string(1, c);
      g_command_line += '\'';
    } else {
      g_command_line += arg;
    }
  }
}

const std::string& commandLine() { return g_command_line; }

}  // namespace oit::cli
