#include "apps/OutputFiles.hpp"

#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>

namespace oit::cli {

namespace fs = std::filesystem;

bool sameFile(const std::string& a, const std::string& b) {
  struct stat sa {}, sb {};
  if (::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0)
    return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
  std::error_code ea, eb;
  const fs::path ca = fs::weakly_canonical(a, ea), cb = fs::weakly_canonical(b, eb);
  return !ea && !eb && ca == cb;
}

void checkNotInput(const std::string& option, const std::string& output, const std::string& input_what,
                   const std::string& input) {
  if (sameFile(output, input))
    throw std::invalid_argument(fmt::format("{} {}: is the input {} {}; it would be overwritten", option, output,
                                            input_what, input));
}

void checkOutputFile(const std::string& option, const std::string& path) {
  if (path.empty()) throw std::invalid_argument(option + ": expected a file name, got an empty path");
  std::error_code ec;
  if (fs::is_directory(path, ec))
    throw std::invalid_argument(fmt::format("{} {}: is a directory, expected a file name", option, path));
  const fs::path p(path);
  if (!p.has_filename())  // "dir/" that does not exist yet
    throw std::invalid_argument(fmt::format("{} {}: expected a file name, got a folder path", option, path));
  const fs::path folder = p.parent_path().empty() ? fs::path(".") : p.parent_path();
  if (!fs::exists(folder, ec))
    throw std::invalid_argument(fmt::format("{} {}: folder {} does not exist", option, path, folder.string()));
  checkWritableDirectory(option, path, folder.string());
}

void checkWritableDirectory(const std::string& option, const std::string& given, const std::string& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw std::invalid_argument(fmt::format("{} {}: {} is not a directory", option, given, dir));
  if (::access(dir.c_str(), W_OK | X_OK) != 0)
    throw std::invalid_argument(fmt::format("{} {}: cannot write in {}: {}", option, given, dir, std::strerror(errno)));
}

}  // namespace oit::cli
