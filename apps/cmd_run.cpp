// oitsim run: the options; the run itself is apps/RunReplay.hpp (replay, the
// reference, the outputs written all at once, the summary).
#include <CLI/CLI.hpp>
#include <fmt/core.h>

#include <memory>
#include <new>
#include <stdexcept>
#include <string>
#include <string_view>

#include "apps/Commands.hpp"
#include "apps/RunMemory.hpp"
#include "apps/RunReplay.hpp"
#include "model/OitAlgorithm.hpp"

namespace oit::cli {

void addRunCommand(CLI::App& app) {
  auto a = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand("run", "Replay a trace through an OIT algorithm; write images and report.json");
  // A later option wins, so scripts can pass defaults and users override them.
  cmd->option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  // Positional too (`oitsim run scene.oitt -o out`), as `oitsim info` takes it.
  cmd->add_option("trace,--trace,-t", a->trace, "Trace file (.oitt binary or .csv)")->required();
  cmd->add_option("--out,-o", a->out,
                  "Output folder for image.png, image.pfm, reference.pfm, diff.png, flip.png, report.json")
      ->required();
  std::string algos;
  for (const auto& info : model::algorithmNames()) algos += (algos.empty() ? "" : ", ") + std::string(info.name);
  cmd->add_option("--algo,-a", a->algo, "OIT algorithm: " + algos)->capture_default_str();
  cmd->add_option("--mode", a->mode, "timing (SystemC ROP: cycles, stalls, DRAM) or functional (image only, faster)")
      ->capture_default_str();
  cmd->add_option("--preset", a->preset,
                  "ROP preset: iris-pro-5200, titan-x-maxwell or navi21 (aliases igpu, dgpu; default "
                  "iris-pro-5200, or the --config file's \"preset\"; used in timing mode, validated in both)");
  CLI::Option* config = cmd->add_option(
      "--config", a->config_file,
      "JSON file of ROP parameters, applied over the preset (used in timing mode, validated in both)");
  cmd->add_option("--set", a->sets, "Override one ROP parameter, a.b.c=value (repeatable; see `oitsim config`)")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  CLI::Option* vcd = cmd->add_option("--vcd", a->vcd, "Write a VCD of key signals for GTKWave (timing mode only; the folder must exist)");
  cmd->add_option("--reference", a->reference,
                  "What the image is compared with: abuffer (the exact A-buffer, built in bands that fit the memory the "
                  "rest of the run needs), none (no reference.pfm, diff.png or error metrics), or a PFM file of the "
                  "frame's size, e.g. an earlier run's reference.pfm")
      ->capture_default_str();
  cmd->add_option("--memory-budget", a->memory_budget,
                  fmt::format("Most memory the run may take, e.g. 8G, 512M or 60% (of physical memory); a frame that "
                              "needs more is refused before any work (default {}% of physical memory, or of the "
                              "cgroup's limit)",
                              kDefaultBudgetPercent));
  cmd->add_option("--layers,-k", a->params.layers, "k: rows, nodes or layers per pixel")->capture_default_str();
  cmd->add_option("--format", a->format, "Row storage format: fp32, rgba8t8z32, fp16")->capture_default_str();
  cmd->add_option("--bits", a->params.bits, "slab: virtual coverage bits b; mlcb: coverage-mask bits")->capture_default_str();
  cmd->add_option("--samples", a->params.samples, "stochastic: samples per pixel S")->capture_default_str();
  cmd->add_option("--weight", a->params.weight, "wboit: weight equation 7, 8, 9 or 10")->capture_default_str();
  cmd->add_option("--seed", a->params.seed, "Seed of the per-fragment random hash")->capture_default_str();
  cmd->add_option("--ppd", a->ppd,
                  "FLIP's viewing condition, pixels per degree (default 67.02: 0.7 m from a 0.7 m wide 3840-pixel "
                  "display; model/METRICS.md)");
  cmd->add_option("--background", a->background, "Clear colour r,g,b (linear) where no opaque fragment landed")
      ->delimiter(',')
      ->expected(3)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  CLI::Option* width = cmd->add_option("--width", a->width, "Frame width of a CSV trace without a width comment (1..65535)");
  CLI::Option* height =
      cmd->add_option("--height", a->height, "Frame height of a CSV trace without a height comment (1..65535)");
  cmd->add_flag("--quiet,-q", a->quiet, "No progress or summary");
  CLI::Option* seeds = cmd->add_option(
      "--seeds", a->seeds,
      "Timing mode: replay the frame with N shader-latency seeds (input.seed, +1, ...) on every core; adds "
      "flicker.png and image.flicker (seed 0's run is the main image and report)");
  cmd->callback([a, width, height, vcd, config, seeds] {
    a->seeds_given = seeds->count() > 0;
    a->command_line = commandLine();
    a->vcd_given = vcd->count() > 0;
    a->config_given = config->count() > 0;
    a->width_given = width->count() > 0;
    a->height_given = height->count() > 0;
    try {
      runReplay(*a);
    } catch (const std::bad_alloc&) {
      // One line naming the frame, the algorithm and the memory it needed.
      throw std::runtime_error(a->out_of_memory.empty() ? "out of memory" : a->out_of_memory);
    } catch (const std::runtime_error& e) {
      // A bad_alloc inside a SystemC process reaches us as SystemC's report.
      if (!a->out_of_memory.empty() && std::string_view(e.what()).find("std::bad_alloc") != std::string_view::npos)
        throw std::runtime_error(a->out_of_memory);
      throw;
    }
  });
}

}  // namespace oit::cli
