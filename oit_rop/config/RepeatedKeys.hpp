// A JSON parser callback that refuses a key repeated within one object (JSON
// parsers keep the last one silently). Shared by ROP config files
// (ConfigTree) and sweep specs (apps/cmd_sweep.cpp).
#pragma once

#include <nlohmann/json.hpp>

#include <functional>
#include <memory>
#include <set>
#include <string>
#include <vector>

namespace oit::rop {

// How the repeated key's place is named: Dotted "base.mode", "traces[1].gen";
// Slashed "lock/granularity" (object keys only).
enum class KeyPath { Dotted, Slashed };

// on_repeat(path) is called with the repeated key's place and must throw.
// Json: nlohmann::json or nlohmann::ordered_json.
template <class Json>
typename Json::parser_callback_t refuseRepeatedKeys(std::function<void(const std::string&)> on_repeat,
                                                    KeyPath style) {
  struct Level {
    bool object = false;
    std::set<std::string> keys;  // objects: keys seen
    std::string key;             // objects: the current key
    size_t index = 0;            // arrays: elements started
  };
  auto stack = std::make_shared<std::vector<Level>>();
  return [stack, on_repeat = std::move(on_repeat), style](int, typename Json::parse_event_t ev, Json& parsed) {
    using E = typename Json::parse_event_t;
    auto& s = *stack;
    if ((ev == E::object_start || ev == E::array_start || ev == E::value) && !s.empty() && !s.back().object)
      ++s.back().index;
    if (ev == E::object_start || ev == E::array_start) {
      s.push_back(Level{ev == E::object_start, {}, {}, 0});
    } else if (ev == E::object_end || ev == E::array_end) {
      if (!s.empty()) s.pop_back();
    } else if (ev == E::key && !s.empty() && parsed.is_string()) {
      const std::string key = parsed.template get<std::string>();
      if (!s.back().keys.insert(key).second) {
        std::string at;
        for (size_t i = 0; i + 1 < s.size(); ++i) {
          if (style == KeyPath::Slashed) {
            if (s[i].object) at += s[i].key + "/";
          } else {
            // Appended piece by piece: GCC 12's -Wrestrict misfires on "lit" + string.
            if (!s[i].object) {
              at += '[';
              at += std::to_string(s[i].index - 1);
              at += ']';
            } else {
              if (!at.empty()) at += '.';
              at += s[i].key;
            }
          }
        }
        on_repeat(style == KeyPath::Slashed || at.empty() ? at + key : at + "." + key);
      }
      s.back().key = key;
    }
    return true;
  };
}

}  // namespace oit::rop
