// oitsim convert IN OUT: binary <-> CSV, losslessly (the CSV form carries the
// header in comment lines), or binary fp32 <-> unorm8 with --encoding.
#include <fmt/core.h>

#include "apps/Commands.hpp"
#include "apps/OutputFiles.hpp"
#include "apps/TraceOptions.hpp"
#include "apps/Progress.hpp"
#include "traces/TraceIO.hpp"

namespace oit::cli {
namespace {

struct ConvertArgs {
  std::string in, out, encoding;
  uint32_t width = 0, height = 0;
  bool width_given = false, height_given = false;
};

void runConvert(const ConvertArgs& a) {
  checkFrameSizeOptions(a.width_given, a.width, a.height_given, a.height);
  checkOutputFile("output", a.out);
  // The same file also through a symlink or another spelling of the path.
  checkNotInput("output", a.out, "trace", a.in);
  auto src = openTraceWithSize(a.in, a.width, a.height);
  TraceHeader h = src->header();
  if (a.encoding == "fp32")
    h.encoding = ColourEncoding::Fp32;
  else if (a.encoding == "unorm8")
    h.encoding = ColourEncoding::Unorm8;
  else if (!a.encoding.empty())
    throw std::invalid_argument("--encoding: expected fp32 or unorm8, got '" + a.encoding + "'");
  auto sink = createTraceWriter(a.out, h);
  Progress progress("convert");
  for (auto batch = src->next(); !batch.empty(); batch = src->next()) {
    sink->write(batch);
    progress.update(h.fragment_count ? double(src->position()) / double(h.fragment_count) : 0.0);
  }
  progress.finish();
  sink->commit();
  fmt::print("{} -> {}: {} fragments, {} x {}, {}, {} colour\n", a.in, a.out, sink->written(),
             h.width, h.height, counted(h.draws.size(), "draw", "draws"), toString(h.encoding));
}

}  // namespace

void addConvertCommand(CLI::App& app) {
  auto args = std::make_shared<ConvertArgs>();
  CLI::App* cmd = app.add_subcommand("convert", "Convert a trace between binary (.oitt) and CSV (.csv)");
  cmd->add_option("input", args->in, "Input trace")->required();
  cmd->add_option("output", args->out, "Output trace; .csv writes CSV, anything else binary")->required();
  CLI::Option* width =
      cmd->add_option("--width", args->width, "Frame width of a CSV input without a width comment (1..65535)");
  CLI::Option* height =
      cmd->add_option("--height", args->height, "Frame height of a CSV input without a height comment (1..65535)");
  cmd->add_option("--encoding", args->encoding,
                  "Colour encoding of the output: fp32 or unorm8 (default: as the input; unorm8 rounds)");
  cmd->callback([args, width, height] {
    args->width_given = width->count() > 0;
    args->height_given = height->count() > 0;
    runConvert(*args);
  });
}

}  // namespace oit::cli
