// oitsim sweep SPEC --out DIR: run every point of a parameter sweep as its own
// `oitsim run` process (SystemC elaborates once per process), in parallel, and
// gather every report into one table (DIR/results.csv, DIR/results.json).
//
// The plan (DIR/plan.json) lists each point's id, axis labels and argument
// vector; `collectSweep` rebuilds the tables from the plan and the points'
// folders alone, so points run elsewhere (`--emit slurm`) merge the same way.
// Spec format and exit codes: reports/SWEEP.md.
#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>
#include <set>
#include <spawn.h>
#include <sstream>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

#include "apps/Commands.hpp"
#include "model/OitAlgorithm.hpp"
#include "model/StorageFormat.hpp"
#include "oit_rop/ConfigTree.hpp"
#include "oit_rop/RepeatedKeys.hpp"
#include "reports/AtomicFile.hpp"
#include "reports/JsonReport.hpp"
#include "traces/InputFile.hpp"
#include "traces/TempFiles.hpp"
#include "traces/gen/Scenes.hpp"

extern char** environ;

namespace oit::cli {

namespace fs = std::filesystem;
using ojson = nlohmann::ordered_json;

// Shared with cmd_report.cpp (defined here; the report merges points run by Slurm).
int collectSweep(const std::string& dir, bool quiet);
std::string selfExecutable();

std::string selfExecutable() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("cannot find the oitsim executable via /proc/self/exe: " + ec.message());
  return p.string();
}

namespace {

struct SweepArgs {
  std::string spec, out, emit;
  unsigned jobs = 0;
  bool quiet = false;
};

// Options of `oitsim run` a spec may set (key -> flag); any key with a dot is a
// ROP parameter passed as --set key=value.
const std::map<std::string, std::string> kRunOptions = {
    {"algo", "--algo"},     {"layers", "--layers"},   {"format", "--format"}, {"preset", "--preset"},
    {"mode", "--mode"},     {"bits", "--bits"},       {"samples", "--samples"}, {"weight", "--weight"},
    {"seed", "--seed"},     {"background", "--background"}, {"config", "--config"}};

struct Settings {
  std::map<std::string, std::string> options;   // run option -> value
  std::vector<std::pair<std::string, std::string>> sets;  // --set a.b=v, in order (later wins)
};

std::string scalarText(const ojson& v, const std::string& where) {
  if (v.is_string()) return v.get<std::string>();
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_number()) return v.dump();
  if (v.is_array()) {  // background: r,g,b
    std::string s;
    for (const auto& e : v) s += (s.empty() ? "" : ",") + scalarText(e, where);
    return s;
  }
  throw std::invalid_argument(where + ": expected a string, number or boolean, got " + v.dump());
}

std::string joinNames(const std::vector<std::string>& names) {
  std::string r;
  for (const auto& n : names) r += (r.empty() ? "" : ", ") + n;
  return r;
}

// A whole number >= min, as a JSON number or a string of digits (YAML may give either).
bool isWhole(const ojson& v, long long min) {
  if (v.is_number_integer()) return v.get<long long>() >= min;
  if (v.is_number_float()) {
    const double d = v.get<double>();
    return d == std::floor(d) && d >= double(min) && d < 9.2e18;
  }
  if (v.is_string()) {
    const std::string t = v.get<std::string>();
    if (t.empty() || t.size() > 18 || t.find_first_not_of("0123456789") != std::string::npos) return false;
    return std::stoll(t) >= min;
  }
  return false;
}

// One ROP parameter on its own (name, type, range); the constraints between
// parameters are checked per point once the preset and every --set are known.
void validateRopParameter(const std::string& key, const ojson& v, const std::string& where) {
  const std::string text = scalarText(v, where);  // its own error names `where` once
  try {
    rop::ConfigTree::forPreset("igpu").set(key, text);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(where + ": " + key + " = " + v.dump() + ": " + e.what());
  }
}

// Checks one value of a setting before anything runs (reports/SWEEP.md): run
// options against what `oitsim run` accepts, ROP parameters through the
// configuration tree (name, type, range). `where` names the spec file and key.
void validateSetting(const std::string& key, const ojson& v, const std::string& where) {
  const std::string shown = v.dump();
  auto bad = [&](const std::string& expected) {
    throw std::invalid_argument(where + ": expected " + expected + ", got " + shown);
  };
  if (key.find('.') != std::string::npos) {
    validateRopParameter(key, v, where);
  } else if (key == "algo") {
    std::vector<std::string> names;
    for (const auto& info : model::algorithmNames()) names.emplace_back(info.name);
    if (!v.is_string() || std::find(names.begin(), names.end(), v.get<std::string>()) == names.end())
      bad("an algorithm (" + joinNames(names) + ")");
  } else if (key == "layers") {
    if (!isWhole(v, 1)) bad("a positive integer");
  } else if (key == "bits" || key == "samples" || key == "weight" || key == "seed") {
    if (!isWhole(v, 0)) bad("a non-negative integer");
  } else if (key == "background") {
    std::vector<ojson> c;
    if (v.is_array()) {
      for (const auto& e : v) c.push_back(e);
    } else if (v.is_string()) {  // "r,g,b", as on the command line
      std::stringstream ss(v.get<std::string>());
      for (std::string t; std::getline(ss, t, ',');) {
        try {
          size_t used = 0;
          const double d = std::stod(t, &used);
          c.push_back(used == t.size() ? ojson(d) : ojson(t));
        } catch (const std::exception&) {
          c.push_back(t);
        }
      }
    }
    bool ok = c.size() == 3;
    for (const auto& e : c) ok = ok && e.is_number() && e.get<double>() >= 0.0 && e.get<double>() <= 1.0;
    if (!ok) bad("[r, g, b], three linear values in [0,1]");
  } else if (key == "format") {
    try {
      model::parseStorageFormat(v.is_string() ? v.get<std::string>() : shown);
    } catch (const std::invalid_argument&) {
      bad("a storage format (fp32, rgba8t8z32, fp16)");
    }
  } else if (key == "mode") {
    if (!v.is_string() || (v.get<std::string>() != "functional" && v.get<std::string>() != "timing"))
      bad("functional or timing");
  } else if (key == "preset") {
    const auto names = rop::presetNames();
    if (!v.is_string() || std::find(names.begin(), names.end(), v.get<std::string>()) == names.end())
      bad("a ROP preset (" + joinNames(names) + ")");
  } else if (key == "config") {
    if (!v.is_string()) bad("a ROP config file path");
    try {
      rop::resolveTree("", v.get<std::string>(), {});
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(where + ": " + e.what());
    }
  }
}

// Applies one setting (key = value) to s; `where` names the spec file and key for
// errors. A relative `config` path is taken from the spec's folder `dir` (as
// trace paths are) and kept absolute, so the plan's commands run from anywhere.
void applySetting(Settings& s, const std::string& key, const ojson& v, const std::string& where,
                  const fs::path& dir) {
  if (key == "set") {
    if (!v.is_object()) throw std::invalid_argument(where + ": expected an object of ROP parameters");
    for (auto it = v.begin(); it != v.end(); ++it) {
      validateRopParameter(it.key(), it.value(), where + "." + it.key());
      s.sets.emplace_back(it.key(), scalarText(it.value(), where + "." + it.key()));
    }
  } else if (key.find('.') != std::string::npos) {
    validateSetting(key, v, where);
    s.sets.emplace_back(key, scalarText(v, where));
  } else if (key == "config" && v.is_string() && !v.get<std::string>().empty()) {
    fs::path file(v.get<std::string>());
    if (file.is_relative()) file = (dir / file).lexically_normal();
    const ojson resolved = file.string();
    validateSetting(key, resolved, where);
    s.options[key] = file.string();
  } else if (kRunOptions.count(key)) {
    validateSetting(key, v, where);
    s.options[key] = scalarText(v, where);
  } else {
    std::string known;
    for (const auto& [k, f] : kRunOptions) known += k + ", ";
    throw std::invalid_argument(where + ": unknown setting '" + key + "' (expected " + known +
                                "set, or a ROP parameter a.b.c; see `oitsim config`)");
  }
}

// One object of a spec (base, or one bundle value of an axis) may name a ROP
// parameter once: in "set" and as a dotted key it would silently be the later
// one, as a key repeated in a config file, which that refuses.
void checkEachRopParameterOnce(const Settings& s, const std::string& where) {
  std::set<std::string> seen;
  for (const auto& [key, value] : s.sets)
    if (!seen.insert(key).second)
      throw std::invalid_argument(where + ": ROP parameter " + key +
                                  " is given twice (in \"set\" and as a key, or twice in \"set\"); give it once");
}

std::string sanitize(const std::string& s) {
  std::string r;
  for (char c : s) r += (std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-') ? c : '_';
  return r;
}

std::string shellQuote(const std::string& a);

// Reads a YAML spec with Debian's python3-yaml (no C++ YAML library needed)
// and returns it as JSON text. Errors are one line naming the file: python3-yaml
// missing, or the YAML error with its line and column (a key given twice in one
// mapping is an error too, as in JSON specs and config files).
std::string yamlToJson(const std::string& path) {
  // Exit codes: 0 JSON on stdout; 3 no yaml module; 4 one-line message on stdout.
  static const char* kScript = R"py(
import sys, json
try:
    import yaml
except ImportError:
    sys.exit(3)
def fail(msg):
    sys.stdout.write(" ".join(str(msg).split()))
    sys.exit(4)
def where(mark):
    return "line %d, column %d: " % (mark.line + 1, mark.column + 1) if mark is not None else ""
class Loader(yaml.SafeLoader):
    pass
def mapping(loader, node, deep=False):
    seen = set()
    for k, _ in node.value:
        key = loader.construct_object(k, deep=True)
        try:
            if key in seen:
                raise yaml.constructor.ConstructorError(None, None, "key %r appears twice in the same mapping (the second would silently replace the first); give each key once" % (key,), k.start_mark)
            seen.add(key)
        except TypeError:
            pass
    return yaml.SafeLoader.construct_mapping(loader, node, deep)
Loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, mapping)
try:
    with open(sys.argv[1]) as f:
        data = yaml.load(f, Loader=Loader)
except yaml.YAMLError as e:
    mark = getattr(e, "problem_mark", None)
    problem = getattr(e, "problem", None)
    context = getattr(e, "context", None)
    if problem is None:
        fail("not valid YAML: " + str(e))
    fail("not valid YAML: " + where(mark) + problem + (" (" + context + ")" if context else ""))
except (OSError, UnicodeDecodeError) as e:
    fail("cannot read: " + str(e))
try:
    sys.stdout.write(json.dumps(data, allow_nan=False, default=str))
except (ValueError, TypeError) as e:
    fail("not representable as JSON: " + str(e))
)py";
  // Debian's python3 has python3-yaml; a pyenv shim on PATH may not.
  const std::string py = fs::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
  const std::string cmd = py + " -c " + shellQuote(kScript) + " " + shellQuote(path) + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) throw std::runtime_error("sweep spec " + path + ": cannot start python3 to read YAML");
  std::string text;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) text.append(buf, n);
  const int status = pclose(p);
  const int code = status != -1 && WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (code == 0) return text;
  if (code == 3)
    throw std::invalid_argument("sweep spec " + path + ": reading YAML needs python3-yaml (" + py +
                                " has no module yaml; scripts/setup.sh installs it), or write the spec as JSON");
  if (code == 4) throw std::invalid_argument("sweep spec " + path + ": " + text);
  // python3 itself missing or failing: its last line says why.
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
  const size_t nl = text.rfind('\n');
  throw std::runtime_error("sweep spec " + path + ": cannot read YAML with " + py + " (exit code " +
                           std::to_string(code) + "): " + (nl == std::string::npos ? text : text.substr(nl + 1)));
}

// Loads a spec (JSON, or YAML by extension). Every error names the file: JSON
// syntax with nlohmann's line and column, a key repeated within one object (the
// parsers would keep the last silently; config files refuse it too), and a top
// level that is not an object.
ojson loadSpec(const std::string& path) {
  // A regular file only, opened without blocking (a FIFO would hang).
  const InputFile in = openInputFile(path);
  if (!in && in.error == ENOENT) throw std::invalid_argument("sweep spec " + path + ": no such file");
  if (!in) throw std::invalid_argument("sweep spec " + path + ": " + in.problem);
  const std::string ext = fs::path(path).extension().string();
  const bool yaml = ext == ".yaml" || ext == ".yml";
  std::string text;
  if (yaml) {
    text = yamlToJson(path);
  } else {
    std::string problem;
    if (!readAll(in, uint64_t(16) << 20, text, problem)) throw std::invalid_argument("sweep spec " + path + ": " + problem);
  }
  // Repeated keys, named by their path (base.mode, traces[1].gen).
  const auto cb = rop::refuseRepeatedKeys<ojson>(
      [&](const std::string& key) {
        throw std::invalid_argument("sweep spec " + path + ": key '" + key +
                                    "' appears twice in the same object (the second would silently replace the "
                                    "first); give each key once");
      },
      rop::KeyPath::Dotted);
  ojson spec;
  try {
    spec = ojson::parse(text, cb);
  } catch (const nlohmann::json::exception& e) {
    throw std::invalid_argument("sweep spec " + path + ": not valid JSON: " + e.what());
  }
  if (!spec.is_object())
    throw std::invalid_argument("sweep spec " + path + ": expected " +
                                (yaml ? std::string("a YAML mapping") : std::string("a JSON object")) +
                                " with keys traces, base, axes at the top level, got " +
                                (spec.is_array() ? "a list" : spec.is_null() ? "nothing" : "a " + std::string(spec.type_name())));
  return spec;
}

// Far above any real sweep; a spec beyond it is a mistake (or would take days).
constexpr size_t kMaxSweepPoints = 100000;

struct TraceEntry {
  size_t index = 0;  // in the spec's traces list
  std::string name, path;
  std::vector<std::string> gen_args;  // empty for an existing trace
};

struct Point {
  std::string id, trace;
  ojson axes = ojson::object();
  std::vector<std::string> args;  // after the executable
};

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

// The Cartesian product traces x axes (axes in spec order, last varies fastest).
std::vector<Point> expand(const ojson& spec, const std::string& specPath, const std::vector<TraceEntry>& traces,
                          const fs::path& out) {
  for (auto it = spec.begin(); it != spec.end(); ++it)
    if (it.key() != "traces" && it.key() != "base" && it.key() != "axes")
      throw std::invalid_argument("sweep spec " + specPath + ": unknown key '" + it.key() +
                                  "' (expected traces, base, axes)");
  const fs::path dir = fs::absolute(specPath).parent_path();
  Settings base;
  if (spec.contains("base")) {
    if (!spec["base"].is_object()) throw std::invalid_argument("sweep spec " + specPath + ": 'base' must be an object");
    for (auto it = spec["base"].begin(); it != spec["base"].end(); ++it)
      applySetting(base, it.key(), it.value(), "sweep spec " + specPath + ": base." + it.key(), dir);
    checkEachRopParameterOnce(base, "sweep spec " + specPath + ": base");
  }
  struct Value {
    std::string label;
    ojson setting;  // scalar for a plain axis, object for a bundle
  };
  std::vector<std::pair<std::string, std::vector<Value>>> axes;
  if (spec.contains("axes")) {
    if (!spec["axes"].is_object()) throw std::invalid_argument("sweep spec " + specPath + ": 'axes' must be an object");
    for (auto it = spec["axes"].begin(); it != spec["axes"].end(); ++it) {
      const std::string where = "sweep spec " + specPath + ": axes." + it.key();
      if (!it.value().is_array() || it.value().empty())
        throw std::invalid_argument(where + ": expected a non-empty list of values");
      std::vector<Value> vals;
      for (size_t i = 0; i < it.value().size(); ++i) {
        const ojson& v = it.value()[i];
        Value val{"", v};
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
        vals.push_back(val);
      }
      axes.emplace_back(it.key(), vals);
    }
  }
  const std::string exeOut = fs::absolute(out).string();
  std::vector<Point> points;
  // A bound on the product, checked as it grows (it could overflow): each
  // point is resolved and planned before anything runs.
  size_t combos = 1;
  for (const auto& [name, vals] : axes) {
    combos *= vals.size();
    if (combos * traces.size() > kMaxSweepPoints)
      throw std::invalid_argument(fmt::format(
          "sweep spec {}: the traces and axes give more than {} points (at axes.{}); split the sweep", specPath,
          kMaxSweepPoints, name));
  }
  for (const TraceEntry& t : traces) {
    for (size_t c = 0; c < combos; ++c) {
      Settings s = base;
      Point p;
      p.trace = t.name;
      std::string label = t.name;
      size_t rest = c;
      std::vector<size_t> idx(axes.size());
      for (size_t a = axes.size(); a-- > 0;) {
        idx[a] = rest % axes[a].second.size();
        rest /= axes[a].second.size();
      }
      for (size_t a = 0; a < axes.size(); ++a) {
        const auto& [name, vals] = axes[a];
        const Value& v = vals[idx[a]];
        if (v.setting.is_object()) {
          for (auto kv = v.setting.begin(); kv != v.setting.end(); ++kv)
            if (kv.key() != "label") applySetting(s, kv.key(), kv.value(), "axes." + name, dir);
        } else {
          applySetting(s, name, v.setting, "axes." + name, dir);
        }
        p.axes[name] = v.label;
        label += "-" + v.label;
      }
      p.id = fmt::format("{:04d}-{}", points.size(), sanitize(label));
      // The point's ROP configuration is resolved now, as `oitsim run` resolves
      // it in both modes (a preset unset: the config file's, else igpu), so a
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
        p.args.push_back(kRunOptions.at(k));
        p.args.push_back(v);
      }
      for (const auto& [k, v] : s.sets) {
        p.args.push_back("--set");
        p.args.push_back(k + "=" + v);
      }
      points.push_back(std::move(p));
    }
  }
  return points;
}

std::string shellQuote(const std::string& a) {
  if (!a.empty() && a.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-./=,:+") ==
                        std::string::npos)
    return a;
  std::string q = "'";
  for (char c : a) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

struct Outcome {
  int exit_code = -1;
  double wall_seconds = 0.0;
};

// Runs exe args with stdout/stderr into files; waits for it.
Outcome spawnAndWait(const std::string& exe, const std::vector<std::string>& args, const fs::path& out_file,
                     const fs::path& err_file) {
  std::vector<std::string> all{exe};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& s : all) argv.push_back(s.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&fa, 2, err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  Outcome o;
  const auto t0 = std::chrono::steady_clock::now();
  pid_t pid;
  const int rc = posix_spawn(&pid, exe.c_str(), &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) {
    std::ofstream(err_file) << "cannot start " << exe << ": " << std::strerror(rc) << "\n";
    return o;
  }
  registerChildProcess(pid);  // an interrupt of the sweep reaches it too
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  unregisterChildProcess(pid);
  o.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  o.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  return o;
}

std::string tailOf(const fs::path& file, size_t max_chars = 600) {
  std::ifstream in(file);
  std::stringstream ss;
  ss << in.rdbuf();
  std::string s = ss.str();
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  if (s.size() > max_chars) s = "..." + s.substr(s.size() - max_chars);
  return s;
}

// The first max_lines lines of a file (a generator's error comes first).
std::string headOf(const fs::path& file, size_t max_lines) {
  std::ifstream in(file);
  std::string out, line;
  size_t n = 0;
  while (std::getline(in, line)) {
    if (n == max_lines) {
      out += "\n...";
      break;
    }
    out += (n++ ? "\n" : "") + line;
  }
  while (!out.empty() && (out.back() == '\n' || out.back() == ' ')) out.pop_back();
  return out;
}

// Flattens a report to dotted keys. The time series' samples (one per stats
// interval) are a trace, not a metric, and stay in the point's report.json; its
// period, timeseries.interval_cycles, is a column like every other field.
void flatten(const nlohmann::json& j, const std::string& prefix, nlohmann::json& out) {
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it) {
      const std::string key = prefix.empty() ? it.key() : prefix + "." + it.key();
      if (key == "timeseries.samples") continue;
      flatten(it.value(), key, out);
    }
  } else if (j.is_array()) {
    bool scalars = true;
    for (const auto& e : j) scalars = scalars && !e.is_structured();
    if (scalars) {
      out[prefix] = j.dump();
    } else {
      for (size_t i = 0; i < j.size(); ++i) flatten(j[i], prefix + "." + std::to_string(i), out);
    }
  } else {
    out[prefix] = j;
  }
}

std::string csvField(const nlohmann::json& v) {
  std::string s = v.is_string() ? v.get<std::string>() : v.is_null() ? std::string() : v.dump();
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

// Whole or not at all (a full disk left a truncated results.json).
void writeText(const fs::path& path, const std::string& text) { reports::writeFileAtomically(path.string(), text); }

// Runs tasks on `jobs` threads, each pulling the next index (each task waits on
// its own child process, so threads, not cores, are the limit).
void runAll(const std::vector<std::function<void(size_t)>>& tasks, unsigned jobs) {
  std::atomic<size_t> next{0};
  std::vector<std::thread> workers;
  for (unsigned w = 0; w < std::max(1u, jobs); ++w)
    workers.emplace_back([&] {
      for (size_t i = next++; i < tasks.size(); i = next++) tasks[i](i);
    });
  for (auto& t : workers) t.join();
}

void runSweep(const SweepArgs& a) {
  const ojson spec = loadSpec(a.spec);
  checkOutputFolder("--out", a.out);  // as `oitsim run --out`: before anything is created
  const fs::path out = fs::absolute(a.out);
  const auto traces = parseTraces(spec, a.spec, out);
  const auto points = expand(spec, a.spec, traces, out);
  const std::string exe = selfExecutable();
  const unsigned jobs = a.jobs ? a.jobs : std::max(1u, std::thread::hardware_concurrency());

  std::mutex mu;
  auto say = [&](const std::string& s) {
    if (a.quiet) return;
    std::lock_guard<std::mutex> lock(mu);
    fmt::print(stderr, "{}\n", s);
  };

  // Traces first (points need them), before the plan or any point folder is
  // written. When a generator fails nothing runs, and the folder is left as it
  // was: the files this step made are removed (the generators' errors are in
  // the message, so nothing is lost).
  const bool out_existed = fs::exists(out), traces_existed = fs::exists(out / "traces");
  std::error_code mk;
  fs::create_directories(out / "traces", mk);
  if (mk) throw std::runtime_error(fmt::format("--out {}: cannot create the folder: {}", a.out, mk.message()));
  std::vector<const TraceEntry*> gens;
  for (const auto& t : traces)
    if (!t.gen_args.empty()) gens.push_back(&t);
  std::vector<fs::path> made;  // files of this step that were not there before
  for (const TraceEntry* t : gens)
    for (const fs::path& f : {fs::path(t->path), out / "traces" / (t->name + ".log"), out / "traces" / (t->name + ".err")})
      if (!fs::exists(f)) made.push_back(f);
  std::vector<std::string> gen_errors(gens.size());
  std::vector<std::function<void(size_t)>> gen_tasks;
  for (size_t i = 0; i < gens.size(); ++i)
    gen_tasks.push_back([&, i](size_t) {
      const TraceEntry& t = *gens[i];
      const fs::path log = out / "traces" / (t.name + ".log"), err = out / "traces" / (t.name + ".err");
      const Outcome o = spawnAndWait(exe, t.gen_args, log, err);
      if (o.exit_code != 0 || !fs::exists(t.path)) {
        std::string cmd = "oitsim";
        for (const auto& g : t.gen_args) {
          cmd += ' ';
          cmd += shellQuote(g);
        }
        std::string text = headOf(err, 6);
        if (text.empty()) text = headOf(log, 6);
        if (text.empty()) text = "(no output)";
        std::string indented;
        for (std::istringstream in(text); std::getline(in, text);) indented += "\n    " + text;
        gen_errors[i] = fmt::format("traces[{}] {}: `{}` {}:{}", t.index, t.name, cmd,
                                    o.exit_code == 0 ? "wrote no trace" : fmt::format("exited with code {}", o.exit_code),
                                    indented);
        say(fmt::format("trace {}: `oitsim gen` failed", t.name));
      } else {
        say(fmt::format("trace {}: generated {} ({:.1f} s)", t.name, t.path, o.wall_seconds));
      }
    });
  runAll(gen_tasks, jobs);
  std::string gen_failures;
  size_t gen_failed = 0;
  for (const auto& e : gen_errors)
    if (!e.empty()) {
      gen_failures += "\n  " + e;
      ++gen_failed;
    }
  if (gen_failed) {
    std::error_code ec;
    for (const auto& f : made) fs::remove(f, ec);
    if (!traces_existed) fs::remove(out / "traces", ec);  // only if empty
    if (!out_existed) fs::remove(out, ec);
    throw std::runtime_error(fmt::format("sweep {}: {} of {} trace generator(s) failed, so nothing ran and {} {}:{}",
                                         a.spec, gen_failed, gens.size(), out.string(),
                                         out_existed ? "was left as it was" : "was not created", gen_failures));
  }
  fs::create_directories(out / "points");

  // The plan: everything collectSweep (and a Slurm task) needs.
  ojson plan;
  plan["schema"] = "oitsim-sweep-plan/1";
  plan["spec"] = fs::absolute(a.spec).string();
  plan["executable"] = exe;
  plan["traces"] = ojson::array();
  for (const auto& t : traces) plan["traces"].push_back({{"name", t.name}, {"path", t.path}, {"gen", t.gen_args}});
  plan["points"] = ojson::array();
  std::string commands;
  for (const auto& p : points) {
    plan["points"].push_back({{"id", p.id}, {"trace", p.trace}, {"axes", p.axes}, {"args", p.args}});
    std::string line = shellQuote(exe);
    for (const auto& s : p.args) {
      line += ' ';  // appended apart: GCC 12's -Wrestrict misfires on " " + string
      line += shellQuote(s);
    }
    const std::string dir = shellQuote((out / "points" / p.id).string());
    commands += "mkdir -p " + dir + " && " + line + " >" + dir + "/stdout.txt 2>" + dir + "/stderr.txt\n";
  }
  // Nothing of an earlier sweep into this folder may pass for this one's, also
  // if this one is interrupted: its tables, page and Slurm script go (a stale
  // sweep.slurm would submit the earlier plan's task count), and every point
  // folder of this plan is emptied now (not just before the point runs).
  for (const char* name : {"results.csv", "results.json", "report.html", "speed.json", "sweep.slurm"})
    fs::remove(out / name);
  for (const auto& p : points) fs::remove_all(out / "points" / p.id);
  reports::writeJsonReport((out / "plan.json").string(), nlohmann::json::parse(plan.dump()));
  writeText(out / "commands.txt", commands);

  if (a.emit == "slurm") {
    const std::string script = fmt::format(
        "#!/bin/bash\n"
        "# Slurm job array made by `oitsim sweep --emit slurm`: one task per point of {}.\n"
        "# Submit: sbatch {}   Then merge: oitsim report {}\n"
        "#SBATCH --job-name=oitsim-sweep\n"
        "#SBATCH --array=0-{}\n"
        "#SBATCH --cpus-per-task=1\n"
        "#SBATCH --output={}/slurm-%A_%a.log\n"
        "set -euo pipefail\n"
        "line=$(sed -n \"$((SLURM_ARRAY_TASK_ID + 1))p\" {})\n"
        "bash -c \"$line\"\n",
        a.spec, shellQuote((out / "sweep.slurm").string()), shellQuote(out.string()), points.size() - 1,
        out.string(), shellQuote((out / "commands.txt").string()));
    writeText(out / "sweep.slurm", script);
    fmt::print("wrote {} ({} tasks) and {}; nothing was run\n", (out / "sweep.slurm").string(), points.size(),
               (out / "commands.txt").string());
    return;
  }

  say(fmt::format("sweep {}: {} points ({} traces), {} jobs, into {}", a.spec, points.size(), traces.size(), jobs,
                  out.string()));
  std::atomic<size_t> done{0}, failed{0};
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<std::function<void(size_t)>> tasks;
  for (size_t i = 0; i < points.size(); ++i)
    tasks.push_back([&, i](size_t) {
      const Point& p = points[i];
      const fs::path dir = out / "points" / p.id;
      // A fresh folder: nothing of an earlier sweep into the same --out (its
      // report.json, images, status) can pass for this run's.
      fs::remove_all(dir);
      fs::create_directories(dir);
      const Outcome o = spawnAndWait(exe, p.args, dir / "stdout.txt", dir / "stderr.txt");
      const bool ok = o.exit_code == 0 && fs::exists(dir / "report.json");
      nlohmann::json st{{"exit_code", o.exit_code}, {"wall_seconds", o.wall_seconds}};
      writeText(dir / "status.json", st.dump(2) + "\n");
      if (!ok) ++failed;
      const size_t n = ++done;
      const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      say(fmt::format("[{:>{}}/{}] {:<6} {:<40} {:6.2f} s  (elapsed {:.0f} s, ~{:.0f} s left){}", n,
                      std::to_string(points.size()).size(), points.size(), ok ? "ok" : "FAILED", p.id,
                      o.wall_seconds, el, el / double(n) * double(points.size() - n),
                      ok ? "" : "\n    " + tailOf(dir / "stderr.txt", 300)));
    });
  runAll(tasks, jobs);
  const int rc = collectSweep(out.string(), a.quiet);
  if (rc != 0) {
    std::fflush(stdout);
    std::fflush(stderr);
    std::exit(rc);  // 2: the sweep finished but some points failed (reports/SWEEP.md)
  }
}

}  // namespace

// Builds DIR/results.csv and DIR/results.json from DIR/plan.json and the
// points' folders. A point with no status.json, stderr.txt or report.json has
// not run (status "not run", counted apart from failures). Returns 0 when every
// point has a report, 2 otherwise.
int collectSweep(const std::string& dir_str, bool quiet) {
  const fs::path dir = fs::absolute(dir_str);
  if (!fs::exists(dir / "plan.json"))
    throw std::invalid_argument(dir.string() + ": no plan.json (not a folder written by `oitsim sweep`)");
  std::ifstream pin(dir / "plan.json");
  const ojson plan = ojson::parse(pin);
  std::vector<std::string> axis_names;
  for (const auto& p : plan["points"])
    for (auto it = p["axes"].begin(); it != p["axes"].end(); ++it)
      if (std::find(axis_names.begin(), axis_names.end(), it.key()) == axis_names.end())
        axis_names.push_back(it.key());

  ojson rows = ojson::array();
  std::set<std::string> metric_keys;
  size_t failed = 0, not_run = 0;
  for (const auto& p : plan["points"]) {
    const std::string id = p["id"].get<std::string>();
    const fs::path pd = dir / "points" / id;
    ojson row;
    row["id"] = id;
    row["trace"] = p["trace"];
    nlohmann::json status;
    if (fs::exists(pd / "status.json")) {
      std::ifstream s(pd / "status.json");
      status = nlohmann::json::parse(s);
    }
    std::string error;
    bool ran = true;
    nlohmann::json flat = nlohmann::json::object();
    const int exit_code = status.is_object() ? status.value("exit_code", 0) : 0;
    if (exit_code != 0) {  // failed, whatever else the folder holds
      error = tailOf(pd / "stderr.txt");
      if (error.empty()) error = fmt::format("exit code {}", exit_code);
    } else if (fs::exists(pd / "report.json")) {
      try {
        std::ifstream r(pd / "report.json");
        flatten(nlohmann::json::parse(r), "", flat);
      } catch (const std::exception& e) {
        error = std::string("unreadable report.json: ") + e.what();
      }
    } else if (status.is_null() && !fs::exists(pd / "stderr.txt")) {
      ran = false;  // e.g. after --emit slurm, before its task ran: not a failure
    } else {
      error = tailOf(pd / "stderr.txt");
      if (error.empty())
        error = status.is_object()
                    ? fmt::format("exit code {} and no report.json", status.value("exit_code", -1))
                    : "no status.json and no report.json: the point started but did not finish (interrupted?)";
    }
    if (!error.empty()) {
      ++failed;
      flat = nlohmann::json::object();
    }
    if (!ran) ++not_run;
    row["status"] = !ran ? "not run" : error.empty() ? "ok" : "failed";
    row["error"] = error;
    row["wall_seconds"] = status.contains("wall_seconds") ? status["wall_seconds"] : nlohmann::json();
    row["axes"] = p["axes"];
    row["command"] = p["args"];
    for (auto it = flat.begin(); it != flat.end(); ++it) metric_keys.insert(it.key());
    row["metrics"] = flat;
    rows.push_back(row);
  }

  // CSV: fixed columns, axes, then every metric key in sorted order.
  std::string csv = "id,trace,status,error,wall_seconds";
  for (const auto& a : axis_names) csv += "," + csvField("axis." + a);
  for (const auto& k : metric_keys) csv += "," + csvField(k);
  csv += "\n";
  for (const auto& r : rows) {
    csv += csvField(r["id"]) + "," + csvField(r["trace"]) + "," + csvField(r["status"]) + "," + csvField(r["error"]) +
           "," + csvField(r["wall_seconds"]);
    for (const auto& a : axis_names) csv += "," + (r["axes"].contains(a) ? csvField(r["axes"][a]) : std::string());
    for (const auto& k : metric_keys)
      csv += "," + (r["metrics"].contains(k) ? csvField(r["metrics"][k]) : std::string());
    csv += "\n";
  }
  writeText(dir / "results.csv", csv);
  ojson res;
  res["schema"] = "oitsim-sweep/1";
  res["spec"] = plan["spec"];
  res["axes"] = axis_names;
  const size_t ok = rows.size() - failed - not_run;
  res["summary"] = {{"points", rows.size()}, {"ok", ok}, {"failed", failed}, {"not_run", not_run}};
  res["points"] = rows;
  writeText(dir / "results.json", res.dump(1) + "\n");
  if (!quiet) {
    fmt::print("sweep: {} points, {} ok, {} failed{}; results {} and {}\n", rows.size(), ok, failed,
               not_run ? fmt::format(", {} not run", not_run) : std::string(), (dir / "results.csv").string(),
               (dir / "results.json").string());
    for (const auto& r : rows)
      if (r["status"] == "failed")
        fmt::print("  FAILED {}: {}\n", r["id"].get<std::string>(), r["error"].get<std::string>());
  }
  return failed || not_run ? 2 : 0;
}

void addSweepCommand(CLI::App& app) {
  auto a = std::make_shared<SweepArgs>();
  CLI::App* cmd = app.add_subcommand(
      "sweep", "Run a parameter sweep (JSON or YAML spec; reports/SWEEP.md): one `oitsim run` per point, in parallel; "
               "exit 2 if any point failed");
  cmd->add_option("spec", a->spec, "Sweep spec (.json, or .yaml/.yml with python3-yaml)")->required();
  cmd->add_option("--out,-o", a->out, "Output folder: results.csv, results.json, plan.json, points/<id>/")->required();
  cmd->add_option("--jobs,-j", a->jobs, "Points run at once (default: number of cores)");
  cmd->add_option("--emit", a->emit, "slurm: write DIR/sweep.slurm (a job array, one task per point) instead of running")
      ->check(CLI::IsMember({"slurm"}));
  cmd->add_flag("--quiet,-q", a->quiet, "No progress or summary");
  cmd->callback([a] { runSweep(*a); });
}

// The fuzzer's entry (tests/fuzz/fuzz_sweep_spec.cpp): what runSweep checks
// and plans before anything runs or is written.
std::vector<std::vector<std::string>> planSweep(const std::string& spec_path, const std::string& out) {
  const ojson spec = loadSpec(spec_path);
  const fs::path dir = fs::absolute(out);
  std::vector<std::vector<std::string>> args;
  for (const Point& p : expand(spec, spec_path, parseTraces(spec, spec_path, dir), dir)) args.push_back(p.args);
  return args;
}

}  // namespace oit::cli
