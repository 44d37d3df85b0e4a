// Reading the interposer's stream (interposer/CaptureStream.hpp) of one retracer
// run into frames: the records of each captured draw in API order (ApiOrder.hpp),
// converted as a trace holds them; the check drawing's records and GL's images
// with --verify. Internal to `oitsim capture --apitrace` (ApitraceCapture.cpp).
#pragma once

#include <cstdint>
#include <string>
#include <unordered_map>

#include "traces/capture/ApitraceCapture.hpp"

namespace oit::capture {

// What the chunk headers alone say (a malformed stream is left to readStream to
// report): the records of recorded draws per frame, so each frame's fragments take
// one allocation; the largest draw that overflowed the record buffer; the buffer.
struct StreamScan {
  std::unordered_map<uint32_t, uint64_t> records;
  uint64_t overflow_need = 0;  // fragments of the largest draw that overflowed
  uint64_t record_capacity = 0, record_limit = 0;  // EndChunk's
};
StreamScan scanStream(const std::string& stream_path);

// Reads the stream of one retracer run (`status`: its raw waitpid status) into
// frames; throws one line naming the trace when the run failed or the stream says so.
// `scan`: scanStream's result for this same stream when the caller has it, else
// nullptr (the stream is scanned here).
ApitraceResult readStream(const ApitraceOptions& o, const std::string& retracer, const std::string& interposer,
                          int status, const std::string& stream_path, const std::string& log_path,
                          const StreamScan* scan);

}  // namespace oit::capture
