#include <fmt/format.h>

#include <charconv>
#include <cstdint>
#include <filesystem>
#include <system_error>
#include <stdexcept>
#include <tuple>
#include <string>

#include "apps/Commands.hpp"
#include "apps/OutputFiles.hpp"

namespace oit::cli {
namespace {
std::string g_command_line;
}

namespace {
// "" when v is a decimal unsigned integer (stored in x), else what is wrong.
std::string parseUnsigned(const std::string& v, uint64_t& x) {
  const auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), x);
  if (ec == std::errc::result_out_of_range && end == v.data() + v.size())
    return "'" + v + "' is too large for this option";
  if (v.empty() || ec != std::errc() || end != v.data() + v.size())
    return "expected a non-negative integer, got '" + v + "'";
  return {};
}
}  // namespace

CLI::Validator unsignedText() {
  return CLI::Validator(
      [](std::string& v) {
        uint64_t x = 0;
        return parseUnsigned(v, x);
      },
      "UINT");
}

CLI::Validator unsignedRange(uint64_t lo, uint64_t hi) {
  return CLI::Validator(
      [lo, hi](std::string& v) {
        uint64_t x = 0;
        std::string e = parseUnsigned(v, x);
        if (e.empty() && (x < lo || x > hi)) e = fmt::format("Value {} not in range {} to {}", v, lo, hi);
        return e;
      },
      fmt::format("UINT in [{} - {}]", lo, hi));
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

std::unique_ptr<FragmentSource> openTraceWithSize(const std::string& path, uint32_t width, uint32_t height) {
  OpenOptions opts;
  opts.width = width;
  opts.height = height;
  auto src = openTrace(path, opts);
  // The reader takes --width/--height only where the trace has no size of its
  // own; a different value given for a trace that has one would be ignored.
  const TraceHeader& h = src->header();
  for (const auto& [name, given, own] : {std::tuple{"--width", width, h.width}, {"--height", height, h.height}})
    if (given != 0 && given != own)
      throw std::invalid_argument(fmt::format(
          "{} {}: {} gives its own frame size, {} x {} (--width and --height are for CSV traces without "
          "'# width' / '# height' lines)",
          name, given, path, h.width, h.height));
  return src;
}

void checkOutputFolder(const std::string& option, const std::string& folder) {
  namespace fs = std::filesystem;
  if (folder.empty()) throw std::invalid_argument(option + ": expected a folder, got an empty path");
  std::error_code ec;
  const fs::file_status st = fs::status(folder, ec);
  if (fs::exists(st) && !fs::is_directory(st))
    throw std::invalid_argument(fmt::format("{} {}: exists and is not a directory", option, folder));
  // The folder, or the nearest part of its path that exists (where it will be created).
  fs::path probe = fs::absolute(fs::path(folder), ec);
  while (!probe.empty() && !fs::exists(probe, ec) && probe != probe.parent_path()) probe = probe.parent_path();
  checkWritableDirectory(option, folder, probe.string());
}

}  // namespace oit::cli
