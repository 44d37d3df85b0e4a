// A sweep's plan: traces, the product of the axes, deduplication, plan files.
#include "reports/SweepPlan.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <map>
#include <set>
#include <stdexcept>

#include "model/AlgorithmSettings.hpp"
#include "oit_rop/config/ConfigTree.hpp"
#include "reports/AtomicFile.hpp"
#include "reports/JsonReport.hpp"
#include "traces/gen/Scenes.hpp"

namespace oit::sweep {

namespace fs = std::filesystem;

namespace {

// Far above any real sweep; a spec beyond it is a mistake (or would take days).
constexpr size_t kMaxSweepPoints = 100000;

std::string sanitize(const std::string& s) {
  std::string r;
  for (char c : s) r += (std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-') ? c : '_';
  return r;
}

// What decides whether a planned trace file is still the one the points ran
// on: a generated trace's generator arguments, an existing file's size and
// modification time.
std::string traceStamp(const TraceEntry& t) {
  if (!t.gen_args.empty()) return ojson(t.gen_args).dump();
  std::error_code ec;
  const auto size = fs::file_size(t.path, ec);
  const auto time = fs::last_write_time(t.path, ec);
  return fmt::format("{} bytes, modified {}", ec ? 0 : size, ec ? 0 : time.time_since_epoch().count());
}

std::vector<TraceEntry> parseTraces(const ojson& spec, const std::string& specPath, const fs::path& out) {
  if (!spec.contains("traces") || !spec["traces"].is_array() || spec["traces"].empty())
    throw std::invalid_argument("sweep spec " + specPath + ": key 'traces' must be a non-empty list");
  std::vector<TraceEntry> traces;
  std::set<std::string> names;
  const fs::path base = fs::absolute(specPath).parent_path();
  for (size_t i = 0; i < spec["traces"].size(); ++i) {
    const ojson& t = spec["traces"][i];
    const std::string where = fmt::format("sweep spec {}: traces[{}]", specPath, i);
    TraceEntry e;
    e.index = i;
    if (t.is_string()) {
      e.path = t.get<std::string>();
    } else if (t.is_object() && t.contains("path")) {
      if (!t["path"].is_string()) throw std::invalid_argument(where + ".path: expected a trace file path");
      e.path = t["path"].get<std::string>();
    } else if (t.is_object() && t.contains("gen")) {
      if (!t["gen"].is_string()) throw std::invalid_argument(where + ".gen: expected a scene name");
      const std::string scene = t["gen"].get<std::string>();
      std::vector<std::string> scenes;
      for (const auto& info : gen::sceneCatalog()) scenes.push_back(info.name);
      if (std::find(scenes.begin(), scenes.end(), scene) == scenes.end())
        throw std::invalid_argument(where + ".gen: unknown scene '" + scene + "' (expected " + joinNames(scenes) +
                                    "; see `oitsim scenes`)");
      e.name = scene;
      e.gen_args = {"gen", scene};
      for (auto it = t.begin(); it != t.end(); ++it) {
        if (it.key() == "gen" || it.key() == "name") continue;
        // Every other key is a `gen` option: --width 160, --backdrop (true), ...
        if (it.value().is_boolean()) {
          if (it.value().get<bool>()) e.gen_args.push_back("--" + it.key());
        } else {
          e.gen_args.push_back("--" + it.key());
          e.gen_args.push_back(scalarText(it.value(), where + "." + it.key()));
        }
      }
    } else {
      throw std::invalid_argument(where + ": expected a path, {\"path\": ...} or {\"gen\": SCENE, ...}");
    }
    if (t.is_object() && t.contains("name")) {
      if (!t["name"].is_string()) throw std::invalid_argument(where + ".name: expected a name (a string)");
      e.name = t["name"].get<std::string>();
    }
    if (e.gen_args.empty()) {
      if (fs::path(e.path).is_relative()) e.path = (base / e.path).lexically_normal().string();
      if (!fs::exists(e.path)) throw std::invalid_argument(where + ": trace " + e.path + " does not exist");
      if (e.name.empty()) e.name = fs::path(e.path).stem().string();
    }
    e.name = sanitize(e.name);
    if (!names.insert(e.name).second)
      throw std::invalid_argument(where + ": trace name '" + e.name + "' is used twice (give each a \"name\")");
    if (!e.gen_args.empty()) {
      e.path = (out / "traces" / (e.name + ".oitt")).string();
      e.gen_args.push_back("-o");
      e.gen_args.push_back(e.path);
    }
    traces.push_back(e);
  }
  return traces;
}

// One value of an axis: a scalar for the axis's own setting, or a bundle.
struct AxisValue {
  std::string label;
  ojson setting;
};

struct Axis {
  std::string name;
  std::vector<AxisValue> values;
};

// The settings an axis value names: its own key, or a bundle's keys (the
// parameters of a bundle's "set" one by one).
std::vector<std::string> settingKeys(const std::string& axis, const AxisValue& v) {
  if (!v.setting.is_object()) return {axis};
  std::vector<std::string> keys;
  for (auto kv = v.setting.begin(); kv != v.setting.end(); ++kv) {
    if (kv.key() == "label") continue;
    if (kv.key() == "set" && kv.value().is_object()) {
      for (auto p = kv.value().begin(); p != kv.value().end(); ++p) keys.push_back(p.key());
    } else {
      keys.push_back(kv.key());
    }
  }
  return keys;
}

bool isRopSetting(const std::string& key) { return key == "preset" || key == "config" || key.find('.') != std::string::npos; }
// What a functional point ignores: the ROP configuration, and the timing runs'
// seeds (`oitsim run --seeds` is for timing mode only).
bool ignoredByFunctional(const std::string& key) { return isRopSetting(key) || key == "seeds"; }

// Why a point ignores `key` ("" when it uses it): its algorithm ignores the run
// setting, or it is functional, which ignores the ROP configuration.
std::string whyIgnored(const std::string& key, const std::string& algo, bool functional,
                       const std::vector<std::string>& ignored_by_algo) {
  if (std::find(ignored_by_algo.begin(), ignored_by_algo.end(), key) != ignored_by_algo.end())
    return algo + " ignores " + key;
  if (functional && ignoredByFunctional(key)) return "functional points ignore " + key;
  return "";
}

}  // namespace

Plan planSweep(const ojson& spec, const std::string& specPath, const fs::path& out_dir, const std::string& executable) {
  for (auto it = spec.begin(); it != spec.end(); ++it)
    if (it.key() != "traces" && it.key() != "base" && it.key() != "axes")
      throw std::invalid_argument("sweep spec " + specPath + ": unknown key '" + it.key() +
                                  "' (expected traces, base, axes)");
  Plan plan;
  plan.spec = fs::absolute(specPath).string();
  plan.out = fs::absolute(out_dir);
  plan.executable = executable;
  plan.traces = parseTraces(spec, specPath, plan.out);
  const fs::path dir = fs::absolute(specPath).parent_path();
  Settings base;
  if (spec.contains("base")) {
    if (!spec["base"].is_object()) throw std::invalid_argument("sweep spec " + specPath + ": 'base' must be an object");
    for (auto it = spec["base"].begin(); it != spec["base"].end(); ++it)
      applySetting(base, it.key(), it.value(), "sweep spec " + specPath + ": base." + it.key(), dir);
    checkEachRopParameterOnce(base, "sweep spec " + specPath + ": base");
  }
  std::vector<Axis> axes;
  if (spec.contains("axes")) {
    if (!spec["axes"].is_object()) throw std::invalid_argument("sweep spec " + specPath + ": 'axes' must be an object");
    for (auto it = spec["axes"].begin(); it != spec["axes"].end(); ++it) {
      const std::string where = "sweep spec " + specPath + ": axes." + it.key();
      if (!it.value().is_array() || it.value().empty())
        throw std::invalid_argument(where + ": expected a non-empty list of values");
      Axis axis{it.key(), {}};
      for (size_t i = 0; i < it.value().size(); ++i) {
        const ojson& v = it.value()[i];
        AxisValue val{"", v};
        Settings probe;  // validate now, so a bad key fails before anything runs
        if (v.is_object()) {
          val.label = v.contains("label") ? scalarText(v["label"], where + ".label") : fmt::format("{}{}", it.key(), i);
          for (auto kv = v.begin(); kv != v.end(); ++kv)
            if (kv.key() != "label")
              applySetting(probe, kv.key(), kv.value(), fmt::format("{}[{}].{}", where, i, kv.key()), dir);
          checkEachRopParameterOnce(probe, fmt::format("{}[{}]", where, i));
        } else {
          val.label = scalarText(v, where);
          applySetting(probe, it.key(), v, fmt::format("{}[{}]", where, i), dir);
        }
        axis.values.push_back(val);
      }
      axes.push_back(axis);
    }
  }

  const std::string exeOut = plan.out.string();
  // A bound on the product, checked as it grows (it could overflow): every
  // point is resolved and planned before anything runs.
  size_t combos = 1;
  for (const Axis& a : axes) {
    combos *= a.values.size();
    if (combos * plan.traces.size() > kMaxSweepPoints)
      throw std::invalid_argument(fmt::format(
          "sweep spec {}: the traces and axes give more than {} points (at axes.{}); split the sweep", specPath,
          kMaxSweepPoints, a.name));
  }
  plan.combinations = combos * plan.traces.size();
  std::map<std::string, std::string> planned;         // run identity -> point id
  std::vector<std::set<std::string>> axis_ignored(axes.size());  // why each axis went unused
  std::vector<bool> axis_used(axes.size(), false);
  for (const TraceEntry& t : plan.traces) {
    for (size_t c = 0; c < combos; ++c) {
      Settings s = base;
      std::vector<size_t> idx(axes.size());
      size_t rest = c;
      for (size_t a = axes.size(); a-- > 0;) {
        idx[a] = rest % axes[a].values.size();
        rest /= axes[a].values.size();
      }
      Point p;
      p.trace = t.name;
      std::string label = t.name;
      for (size_t a = 0; a < axes.size(); ++a) {
        const AxisValue& v = axes[a].values[idx[a]];
        if (v.setting.is_object()) {
          for (auto kv = v.setting.begin(); kv != v.setting.end(); ++kv)
            if (kv.key() != "label") applySetting(s, kv.key(), kv.value(), "axes." + axes[a].name, dir);
        } else {
          applySetting(s, axes[a].name, v.setting, "axes." + axes[a].name, dir);
        }
        p.axes[axes[a].name] = v.label;
        label += "-" + v.label;
      }
      // `oitsim run`'s defaults: mlab, timing.
      const std::string algo = s.options.count("algo") ? s.options.at("algo") : "mlab";
      const bool functional = s.options.count("mode") && s.options.at("mode") == "functional";
      const std::vector<std::string> ignored_by_algo = model::ignoredSettings(algo);
      // Which axes this combination uses; what it ignores of the others.
      std::set<std::string> ignored_here;
      for (size_t a = 0; a < axes.size(); ++a) {
        bool used = false;
        for (const std::string& key : settingKeys(axes[a].name, axes[a].values[idx[a]])) {
          const std::string why = whyIgnored(key, algo, functional, ignored_by_algo);
          if (why.empty()) {
            used = true;
          } else {
            axis_ignored[a].insert(why);
            ignored_here.insert(key);
          }
        }
        axis_used[a] = axis_used[a] || used;
      }
      // The run's identity: its trace and every setting it does not ignore
      // (ROP parameters by name, the last value of each winning).
      ojson identity = ojson::object();
      identity["trace"] = t.name;
      for (const auto& [k, v] : s.options)
        if (whyIgnored(k, algo, functional, ignored_by_algo).empty()) identity["options"][k] = v;
      if (!functional) {
        std::map<std::string, std::string> last;
        for (const auto& [k, v] : s.sets) last[k] = v;
        for (const auto& [k, v] : last) identity["sets"][k] = v;
      }
      const std::string key = identity.dump();
      if (auto it = planned.find(key); it != planned.end()) {
        plan.duplicates.push_back({sanitize(label), it->second, {ignored_here.begin(), ignored_here.end()}});
        continue;
      }
      p.id = fmt::format("{:04d}-{}", plan.points.size(), sanitize(label));
      planned.emplace(key, p.id);
      // The point's ROP configuration is resolved now, as `oitsim run` resolves
      // it in both modes (a preset unset: the config file's, else iris-pro-5200), so a
      // combination that breaks a constraint stops the sweep before anything
      // runs instead of failing every point.
      {
        std::vector<std::string> sets;
        for (const auto& [k, v] : s.sets) sets.push_back(k + "=" + v);
        try {
          rop::resolveTree(s.options.count("preset") ? s.options.at("preset") : "",
                           s.options.count("config") ? s.options.at("config") : "", sets);
        } catch (const std::exception& e) {
          throw std::invalid_argument("sweep spec " + specPath + ": point " + p.id + ": " + e.what());
        }
      }
      p.args = {"run", "--trace", t.path, "--out", exeOut + "/points/" + p.id, "--quiet"};
      for (const auto& [k, v] : s.options) {
        if (functional && k == "seeds") continue;  // run refuses --seeds in functional mode
        p.args.push_back(runOptions().at(k));
        p.args.push_back(v);
      }
      for (const auto& [k, v] : s.sets) {
        p.args.push_back("--set");
        p.args.push_back(k + "=" + v);
      }
      plan.points.push_back(std::move(p));
    }
  }
  // An axis whose every value every point ignores sweeps nothing.
  for (size_t a = 0; a < axes.size(); ++a)
    if (!axis_used[a]) {
      std::string why;
      for (const auto& w : axis_ignored[a]) why += (why.empty() ? "" : "; ") + w;
      throw std::invalid_argument("sweep spec " + specPath + ": axes." + axes[a].name +
                                  ": no point uses this axis (" + why + "); remove it");
    }
  return plan;
}

std::string duplicatesLine(const Plan& plan) {
  if (plan.duplicates.empty()) return "";
  std::map<std::string, std::set<std::string>> by_setting;  // setting -> what ignores it
  std::map<std::string, const Point*> by_id;
  for (const Point& p : plan.points) by_id[p.id] = &p;
  for (const Duplicate& d : plan.duplicates) {
    const Point* kept = by_id.at(d.same_as);
    std::string who = "functional";
    for (size_t i = 0; i + 1 < kept->args.size(); ++i)
      if (kept->args[i] == "--algo") who = kept->args[i + 1];
    for (const auto& s : d.ignored) by_setting[s].insert(ignoredByFunctional(s) ? std::string("functional points") : who);
  }
  std::string detail;
  for (const auto& [setting, who] : by_setting) {
    std::string names;
    for (const auto& w : who) names += (names.empty() ? "" : ", ") + w;
    detail += (detail.empty() ? "" : "; ") + setting + ": " + names;
  }
  return fmt::format("{} of {} combinations differ only in settings their algorithm or mode ignores and are planned "
                     "once ({}): {} points",
                     plan.duplicates.size(), plan.combinations, detail, plan.points.size());
}

std::string commandLine(const Plan& plan, const Point& p) {
  std::string line = shellQuote(plan.executable);
  for (const auto& s : p.args) {
    line += ' ';  // appended apart: GCC 12's -Wrestrict misfires on " " + string
    line += shellQuote(s);
  }
  const std::string dir = shellQuote((plan.out / "points" / p.id).string());
  return "mkdir -p " + dir + " && " + line + " >" + dir + "/stdout.txt 2>" + dir + "/stderr.txt";
}

void writePlanFiles(const Plan& plan) {
  ojson j;
  j["schema"] = "oitsim-sweep-plan/1";
  j["spec"] = plan.spec;
  j["executable"] = plan.executable;
  j["combinations"] = plan.combinations;
  j["traces"] = ojson::array();
  for (const auto& t : plan.traces)
    j["traces"].push_back({{"name", t.name}, {"path", t.path}, {"gen", t.gen_args}, {"stamp", traceStamp(t)}});
  j["points"] = ojson::array();
  std::string commands;
  for (const auto& p : plan.points) {
    j["points"].push_back({{"id", p.id}, {"trace", p.trace}, {"axes", p.axes}, {"args", p.args}});
    commands += commandLine(plan, p) + "\n";
  }
  j["duplicates"] = ojson::array();
  for (const auto& d : plan.duplicates)
    j["duplicates"].push_back({{"labels", d.labels}, {"same_as", d.same_as}, {"ignored", d.ignored}});
  reports::writeJsonReport((plan.out / "plan.json").string(), nlohmann::json::parse(j.dump()));
  reports::writeFileAtomically((plan.out / "commands.txt").string(), commands);
}

Plan readPlan(const fs::path& dir_in) {
  const fs::path dir = fs::absolute(dir_in);
  if (!fs::exists(dir / "plan.json"))
    throw std::invalid_argument(dir.string() + ": no plan.json (not a folder written by `oitsim sweep`)");
  std::ifstream in(dir / "plan.json");
  ojson j;
  try {
    j = ojson::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw std::invalid_argument((dir / "plan.json").string() + ": not valid JSON: " + e.what());
  }
  Plan plan;
  plan.out = dir;
  plan.spec = j.value("spec", "");
  plan.executable = j.value("executable", "");
  plan.combinations = j.value("combinations", size_t(0));
  for (const auto& t : j.value("traces", ojson::array())) {
    TraceEntry e;
    e.name = t.value("name", "");
    e.path = t.value("path", "");
    e.gen_args = t.value("gen", std::vector<std::string>{});
    plan.traces.push_back(e);
  }
  for (const auto& p : j.value("points", ojson::array()))
    plan.points.push_back({p.at("id").get<std::string>(), p.at("trace").get<std::string>(), p.at("axes"),
                           p.at("args").get<std::vector<std::string>>()});
  for (const auto& d : j.value("duplicates", ojson::array()))
    plan.duplicates.push_back({d.value("labels", ""), d.value("same_as", ""),
                               d.value("ignored", std::vector<std::string>{})});
  return plan;
}

// The trace stamps of plan.json, by trace name (resume compares them).
std::map<std::string, std::string> readTraceStamps(const fs::path& dir) {
  std::map<std::string, std::string> stamps;
  std::ifstream in(dir / "plan.json");
  if (!in) return stamps;
  try {
    const ojson j = ojson::parse(in);
    for (const auto& t : j.value("traces", ojson::array())) stamps[t.value("name", "")] = t.value("stamp", "");
  } catch (const nlohmann::json::exception&) {
  }
  return stamps;
}

std::string currentTraceStamp(const TraceEntry& t) { return traceStamp(t); }

}  // namespace oit::sweep
