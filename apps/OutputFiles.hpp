// Checks on the output files of the trace commands (info --heatmap, convert,
// gen -o, capture -o), made before any work: an output path must be usable
// and must never be one of the command's inputs.
#pragma once

#include <string>

namespace oit::cli {

// Whether two paths name the same file: when both exist, the same device and
// inode (so a symlink, a hard link or another spelling of the path counts);
// otherwise the same canonical path.
bool sameFile(const std::string& a, const std::string& b);

// Throws std::invalid_argument naming the option when `output` is the same file
// as `input`: "-o my.off: is the input mesh --mesh my.off; it would be overwritten".
// `input_what` names the input as the user gave it, e.g. "trace" or "mesh --mesh".
void checkNotInput(const std::string& option, const std::string& output, const std::string& input_what,
                   const std::string& input);

// Throws std::invalid_argument "<option> <given>: ..." unless `dir` is an
// existing directory this process may create files in.
void checkWritableDirectory(const std::string& option, const std::string& given, const std::string& dir);

// Throws std::invalid_argument naming the option unless `path` can be created
// as a file: not empty, not a directory, and its folder exists and is writable.
void checkOutputFile(const std::string& option, const std::string& path);

}  // namespace oit::cli
