// Sweep specs: loading and per-setting checks (reports/SWEEP.md, "Spec").
#include "reports/SweepSpec.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <sys/wait.h>

#include "model/OitAlgorithm.hpp"
#include "model/StorageFormat.hpp"
#include "oit_rop/config/ConfigTree.hpp"
#include "oit_rop/config/RepeatedKeys.hpp"
#include "traces/InputFile.hpp"

namespace oit::sweep {

namespace fs = std::filesystem;

const std::map<std::string, std::string>& runOptions() {
  static const std::map<std::string, std::string> kOptions = {
      {"algo", "--algo"},   {"layers", "--layers"},   {"format", "--format"},   {"preset", "--preset"},
      {"mode", "--mode"},   {"bits", "--bits"},       {"samples", "--samples"}, {"weight", "--weight"},
      {"seed", "--seed"},   {"background", "--background"}, {"config", "--config"}, {"seeds", "--seeds"}};
  return kOptions;
}

std::string scalarText(const ojson& v, const std::string& where) {
  if (v.is_string()) return v.get<std::string>();
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_number()) return v.dump();
  if (v.is_array()) {  // background: r,g,b
    std::string s;
    for (const auto& e : v) {
      if (!s.empty()) s += ',';  // appended apart: GCC 12's -Wrestrict misfires on "," + string
      s += scalarText(e, where);
    }
    return s;
  }
  throw std::invalid_argument(where + ": expected a string, number or boolean, got " + v.dump());
}

std::string joinNames(const std::vector<std::string>& names) {
  std::string r;
  for (const auto& n : names) r += (r.empty() ? "" : ", ") + n;
  return r;
}

namespace {

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
    rop::ConfigTree::forPreset("iris-pro-5200").set(key, text);
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
  } else if (key == "seeds") {
    if (!isWhole(v, 1)) bad("a positive integer (shader-latency seeds per timing point, `oitsim run --seeds`)");
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
    if (!v.is_string() ||
        std::find(names.begin(), names.end(), rop::canonicalPresetName(v.get<std::string>())) == names.end())
      bad("a ROP preset (" + joinNames(names) + "; aliases igpu, dgpu)");
  } else if (key == "config") {
    if (!v.is_string()) bad("a ROP config file path");
    try {
      rop::resolveTree("", v.get<std::string>(), {});
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(where + ": " + e.what());
    }
  }
}

}  // namespace

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
  } else if (runOptions().count(key)) {
    validateSetting(key, v, where);
    s.options[key] = scalarText(v, where);
  } else {
    std::string known;
    for (const auto& [k, f] : runOptions()) known += k + ", ";
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

namespace {

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

}  // namespace

// Loads a spec (JSON, or YAML by extension). Every error names the file: JSON
// syntax with nlohmann's line and column, a key repeated within one object (the
// parsers would keep the last silently; config files refuse it too), and a top
// level that is not an object.
// A spec is a few kilobytes; far more is not one (and would be read whole).
constexpr uint64_t kMaxSpecBytes = uint64_t(16) << 20;

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
    if (!readAll(in, kMaxSpecBytes, text, problem)) throw std::invalid_argument("sweep spec " + path + ": " + problem);
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

std::string shellQuote(const std::string& a) {
  if (!a.empty() && a.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-./=,:+") ==
                        std::string::npos)
    return a;
  std::string q = "'";
  for (char c : a) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

}  // namespace oit::sweep
