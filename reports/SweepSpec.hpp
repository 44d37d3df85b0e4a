// A sweep spec (reports/SWEEP.md): loading it (JSON, or YAML through Debian's
// python3-yaml) and checking each setting on its own before anything runs.
#pragma once

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

namespace oit::sweep {

using ojson = nlohmann::ordered_json;

// Loads a spec (JSON, or YAML by extension .yaml/.yml). Every error names the
// file: JSON syntax with its line and column, a key repeated within one object,
// a top level that is not an object.
ojson loadSpec(const std::string& path);

// The settings of one point: `oitsim run` options and ROP parameters.
struct Settings {
  std::map<std::string, std::string> options;             // run option ("algo") -> value
  std::vector<std::pair<std::string, std::string>> sets;  // --set a.b=v, in order (later wins)
};

// `oitsim run` options a spec may set, key -> flag ("algo" -> "--algo"). Any key
// with a dot is a ROP parameter, passed as --set key=value.
const std::map<std::string, std::string>& runOptions();

// Applies key = value to `s` after checking the value (reports/SWEEP.md,
// "Checks"); `where` names the spec file and key for errors (std::invalid_argument).
// A relative `config` path is taken from `spec_dir` and kept absolute.
void applySetting(Settings& s, const std::string& key, const ojson& value, const std::string& where,
                  const std::filesystem::path& spec_dir);

// One object of a spec (base, or a bundle) may name a ROP parameter once.
void checkEachRopParameterOnce(const Settings& s, const std::string& where);

// A scalar as `oitsim run` takes it on the command line ([r,g,b] -> "r,g,b").
std::string scalarText(const ojson& v, const std::string& where);

std::string joinNames(const std::vector<std::string>& names);

// Single-quotes for sh where needed ("a b" -> 'a b').
std::string shellQuote(const std::string& a);

}  // namespace oit::sweep
