// The report's sections on hand-made points (reports/htmlreport/): the frame's
// phases and its bottleneck from the keys the timing model writes today, and
// from those the timing-model work adds later (timing.bound_by,
// timing.phase_cycles, timing.utilization, timing.root_cause_cycles,
// memory.levels, memory.traffic_over_compulsory), shown when present.
#include <gtest/gtest.h>

#include "CliRunner.hpp"

namespace oit::test {
namespace {

// Runs a Python snippet with reports/ on the path; returns its stdout.
std::string python(const std::string& code) {
  TempDir d("report_sections");
  writeText(d.file("t.py"), "import sys\nsys.path.insert(0, '" + std::string(OITSIM_SOURCE_DIR) +
                                "/reports')\nfrom htmlreport import data\n" + code);
  const CliResult r = runShell("/usr/bin/python3 " + d.file("t.py"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return r.output;
}

// Today's keys. A 2-partition frame at 1000 MHz: partition 1 ends last at cycle
// 9000, its opaque pre-pass at 1000 and its one transparent pass at 7000:
// opaque 1000 cycles = 1 us, transparent 6000 = 6 us, resolve 2000 = 2 us.
// Stalls over 2 x 10000 partition-cycles: pixel_lock waits 15000 cycles on the
// cache (0.75), the blend ALU is starved 18000 (0.9, a symptom: left out), the
// cache stage waits 4000 on DRAM (0.2): the largest stall is pixel_lock's.
TEST(ReportSections, PhasesAndLargestStallFromTodaysKeys) {
  if (!haveMatplotlib()) GTEST_SKIP() << "python3-matplotlib absent (scripts/setup.sh installs it)";
  const std::string out = python(R"py(
m = {"timing.clock_mhz": 1000.0, "timing.cycles": 10000, "timing.partition_cycles": 20000,
     "timing.per_partition.0.end_cycle": 8000, "timing.per_partition.0.opaque_end_cycle": 500,
     "timing.per_partition.0.pass_end_cycles": "[7500]",
     "timing.per_partition.1.end_cycle": 9000, "timing.per_partition.1.opaque_end_cycle": 1000,
     "timing.per_partition.1.pass_end_cycles": "[7000]",
     "timing.stages.pixel_lock.stalls.cache_miss_wait": 15000,
     "timing.stages.blend_alu.stalls.input_starved": 18000,
     "timing.stages.cache.stalls.dram_bandwidth": 4000,
     "memory.mean_gbps": 12.8, "memory.channel_peak_gbps": 25.6}
print(data.phases_us(m))
print(data.bound_by(m))
print(data.dram_utilisation(m))
)py");
  EXPECT_EQ(out, "[('opaque', 1.0), ('transparent', 6.0), ('resolve', 2.0)]\n"
                 "('pixel_lock: cache miss wait', 0.75, 'stall share')\n"
                 "0.5\n");
}

// The timing model's own figures win when the reports carry them: phases from
// timing.phase_cycles (two passes), bound_by as written; the table grows L2
// and traffic-over-compulsory columns.
TEST(ReportSections, TimingModelKeysAreShownWhenPresent) {
  if (!haveMatplotlib()) GTEST_SKIP() << "python3-matplotlib absent (scripts/setup.sh installs it)";
  const std::string out = python(R"py(
m = {"timing.clock_mhz": 500.0, "timing.cycles": 6000, "timing.partition_cycles": 6000,
     "timing.frame_time_us": 12.0,
     "timing.phase_cycles.opaque": 500, "timing.phase_cycles.transparent": "[2000, 3000]",
     "timing.phase_cycles.resolve": 500,
     "timing.bound_by.resource": "dram_bus", "timing.bound_by.share": 0.72,
     "timing.per_partition.0.end_cycle": 6000,
     "timing.stages.pixel_lock.stalls.cache_miss_wait": 5000,
     "memory.levels.0.name": "rop_cache", "memory.levels.0.hit_rate": 0.9,
     "memory.levels.1.name": "l2", "memory.levels.1.hit_rate": 0.625,
     "memory.traffic_over_compulsory": 3.5,
     "config.rop.preset": "igpu", "config.algorithm": "mlab", "config.layers": 4,
     "config.ignored_settings": "[\"bits\",\"samples\",\"weight\",\"seed\"]"}
print(data.phases_us(m))
print(data.bound_by(m))
print(data.level_hit_rate(m, "l2"))
from htmlreport import bottleneck
p = {"id": "0000-t-mlab", "trace": "t", "axes": {}, "metrics": m, "status": "ok"}
html = bottleneck.bottleneck_table([p], data.Configs([p]))
for s in ["bound by (share of frame)", "L2 hit rate", "traffic / compulsory", "dram_bus 72.0 %", "62.5 %", "3.50 x",
          '<td data-v="10.0">10 (4 + 6)</td>']:
    print(s in html)
)py");
  // The transparent column: both passes (2000 and 3000 cycles at 500 MHz: 4 and 6 us), sorted by their sum.
  EXPECT_EQ(out, "[('opaque', 1.0), ('transparent pass 1', 4.0), ('transparent pass 2', 6.0), ('resolve', 1.0)]\n"
                 "('dram_bus', 0.72, 'bound_by')\n"
                 "0.625\n"
                 "True\nTrue\nTrue\nTrue\nTrue\nTrue\nTrue\n");
}

// Hardware configurations are told apart by preset and the parameters that
// differ; the simulator's speed settings do not make another machine.
TEST(ReportSections, ConfigurationsAreNamedByPresetAndWhatDiffers) {
  if (!haveMatplotlib()) GTEST_SKIP() << "python3-matplotlib absent (scripts/setup.sh installs it)";
  const std::string out = python(R"py(
def pt(preset, ways, quantum):
    return {"id": f"{preset}{ways}{quantum}", "trace": "t", "axes": {}, "status": "ok",
            "metrics": {"timing.cycles": 1, "config.rop.preset": preset, "config.rop.cache.ways": ways,
                        "config.rop.sim.quantum_cycles": quantum}}
ps = [pt("igpu", 4, 1), pt("igpu", 8, 1), pt("igpu", 8, 200), pt("dgpu", 16, 1),
      {"id": "f", "trace": "t", "axes": {}, "status": "ok", "metrics": {"config.mode": "functional"}}]
c = data.Configs(ps)
print([c.label(p) for p in ps])
print(c.all_labels(ps))
)py");
  EXPECT_EQ(out, "['igpu cache.ways=4', 'igpu cache.ways=8', 'igpu cache.ways=8', 'dgpu', 'functional model']\n"
                 "['dgpu', 'igpu cache.ways=4', 'igpu cache.ways=8', 'functional model']\n");
}

// The price of order (issue 23): a scene whose timing points differ in
// lock.mode gets the section; modes are compared on the same machine (the
// lock mode is not part of the machine's name there), the table lists each
// mode's frame time, waits, lost updates, error and flicker, and images
// drawn by the timing run (unordered, none) are told apart from the
// submission-order one. A scene with one mode does not get it.
TEST(ReportSections, ThePriceOfOrderComparesTheLockModesOfOneMachine) {
  if (!haveMatplotlib()) GTEST_SKIP() << "python3-matplotlib absent (scripts/setup.sh installs it)";
  const std::string out = python(R"py(
from htmlreport import ordering
from htmlreport.plots import Styles
def pt(mode, us, wait, lost, rmse, std, order):
    m = {"timing.cycles": 1000, "timing.frame_time_us": us, "config.rop.preset": "dgpu",
         "config.rop.lock.mode": mode, "lock.mode": mode, "lock.wait_cycles": wait, "lock.lost_updates": lost,
         "image.metrics.rmse": rmse, "image.flicker.std_mean": std, "image.flicker.differing_fraction": std / 10,
         "image.order": order, "config.algorithm": "mlab", "config.layers": 2,
         "config.ignored_settings": "[\"bits\",\"samples\",\"weight\",\"seed\"]"}
    return {"id": mode, "trace": "t", "axes": {}, "status": "ok", "metrics": m}
ps = [pt("ordered", 100.0, 5000, 0, 0.01, 0.0, "submission"), pt("unordered", 90.0, 3000, 0, 0.012, 0.5, "lock_entry"),
      pt("none", 80.0, 0, 1234, 0.02, 2.0, "race")]
c = data.Configs(ps)
print(ordering.applies(ps), ordering.applies(ps[:1]))
print(sorted({ordering._machine(p, c) for p in ps}))
html = ordering.section(ps, "t", c, Styles({"mlab"}), lambda s: None)
for s in ["lock.mode", "lost updates", "1,234", "flickering pixels (%)", "<img"]:
    print(s in html)
print([data.image_settings(p) for p in ps])
)py");
  EXPECT_EQ(out, "True False\n"
                 "['dgpu']\n"
                 "True\nTrue\nTrue\nTrue\nTrue\n"
                 "['', 'order lock_entry (unordered)', 'order race (none)']\n");
}

// Numbers with thousands separators (the table printed 5.554e+08).
TEST(ReportSections, NumbersHaveThousandsSeparators) {
  if (!haveMatplotlib()) GTEST_SKIP() << "python3-matplotlib absent (scripts/setup.sh installs it)";
  const std::string out = python(R"py(
from htmlreport.page import fmt_num
print([fmt_num(v) for v in [555400000, 1234.5, 12.345, 0.012345, 2.23e-08, 0, None]])
)py");
  EXPECT_EQ(out, "['555,400,000', '1,234', '12.3', '0.0123', '2.23e-08', '0', '']\n");
}

}  // namespace
}  // namespace oit::test
