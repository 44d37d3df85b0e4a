// The concrete readers and writers behind openTrace / createTraceWriter.
#pragma once

#include <memory>
#include <string>

#include "traces/TraceIO.hpp"

namespace oit::detail {

std::unique_ptr<FragmentSource> openBinaryTrace(const std::string& path, const OpenOptions& opts);
std::unique_ptr<FragmentSource> openCsvTrace(const std::string& path, const OpenOptions& opts);
std::unique_ptr<FragmentSink> createBinaryWriter(const std::string& path, const TraceHeader& header);
std::unique_ptr<FragmentSink> createCsvWriter(const std::string& path, const TraceHeader& header);

// True when the path ends in ".csv" (any letter case).
bool isCsvPath(const std::string& path);

}  // namespace oit::detail
