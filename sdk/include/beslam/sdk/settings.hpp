// Settings: each plugin setting is declared once - name, type, default, range or choices, help - bound to
// a member of the plugin's options struct. That one declaration is the schema the host prints
// (`beslam plugins`) and validates the pipeline against, and it reads the validated values, typed, into
// the struct. A plugin normally writes no such table itself: it declares its settings as data in a settings
// file and beslam_add_plugin(... SETTINGS file) generates the table (sdk/cmake/beslam_plugin_settings.cmake,
// docs/writing-a-plugin.md). By hand it reads:
//
//   struct Options { double gate = 0; int frames = 0; std::string mode; Policy policy{}; };
//   const beslam::sdk::Settings<Options> kSettings{
//       setting(&Options::gate, "gate", "2.0", 0.01, 100, "m: largest match distance"),
//       setting(&Options::frames, "frames", "3", 1, 1000, "frames before a decision"),
//       setting(&Options::mode, "mode", "fast", "fast|exact", "which solver"),      // choices, or nullptr
//       choice(&Options::policy, "on_error", "stop", {{"stop", Policy::stop}, {"skip", Policy::skip}}, "..."),
//   };
//   ... describe<MyPlugin>({"my_plugin", "My plugin", "One line.", {1, 0, 0}, kSettings})
//   MyPlugin(const Context&, const Config& config) : options_(kSettings.read(config)) {}
//
// Member types: bool (no range), integers, double / float, std::string (setting: a string with optional
// choices; path: a file or folder the host resolves against the pipeline's folder), std::vector of numbers
// or std::array<double, N> (a list; the array checks its length), an enum through choice(), any type through
// parsed() (a string and a parse function). nested() binds a setting to a member of a member. The default is the YAML
// text of the value ("2.0", "true", "[1, 2]",
// "\"\"" for an empty string; nullptr: required). read() checks what the host checked (every key known and
// of its declared type, numbers in range, strings among the choices, lists of the declared length) and
// throws ConfigError naming the setting, so a value never reaches the plugin unchecked.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <functional>
#include <initializer_list>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "beslam/sdk/config.hpp"

namespace beslam::sdk {

// One declared setting of an options struct O: its schema entry and how its value lands in O.
template <class O>
struct Setting {
  using Assign = std::function<void(const beslam_config_value&, O&)>;
  Setting() = default;
  Setting(const beslam_config_field& field_, Assign assign_) : field(field_), assign(std::move(assign_)) {}

  beslam_config_field field{};
  Assign assign;
  std::string owned_choices;  // choice(): the "a|b|c" text field.choices points to once in a Settings
};

namespace detail {

inline std::string settingRange(const beslam_config_field& f) {
  return "[" + std::to_string(f.min_value) + ", " + std::to_string(f.max_value) + "]";
}

inline const char* typeName(int32_t type) {
  static const char* const kNames[] = {"an unknown type", "a boolean", "an integer",       "a number",
                                       "a string",        "a path",    "a list of numbers"};
  return type >= BESLAM_CONFIG_BOOL && type <= BESLAM_CONFIG_DOUBLE_LIST ? kNames[type] : kNames[0];
}

inline bool inRange(const beslam_config_field& f, double v) {
  return f.min_value > f.max_value || (v >= f.min_value && v <= f.max_value);
}

// Throws ConfigError when a value does not fit its declaration (type, range, choices).
inline void checkValue(const beslam_config_field& f, const beslam_config_value& v) {
  const std::string key = f.key;
  if (v.type != f.type)
    throw ConfigError("setting '" + key + "': expected " + typeName(f.type) + ", got " + typeName(v.type));
  if ((f.type == BESLAM_CONFIG_INT || f.type == BESLAM_CONFIG_DOUBLE) && !inRange(f, v.number))
    throw ConfigError("setting '" + key + "': value " + std::to_string(v.number) + " is out of range " +
                      settingRange(f));
  if (f.type == BESLAM_CONFIG_INT && v.number != static_cast<double>(static_cast<int64_t>(v.number)))
    throw ConfigError("setting '" + key + "': " + std::to_string(v.number) + " is not an integer");
  if (f.type == BESLAM_CONFIG_DOUBLE_LIST)
    for (uint64_t i = 0; i < v.list_size; ++i)
      if (!inRange(f, v.list[i]))
        throw ConfigError("setting '" + key + "': element " + std::to_string(i + 1) + " (" + std::to_string(v.list[i]) +
                          ") is out of range " + settingRange(f));
  if (f.type == BESLAM_CONFIG_STRING && f.choices != nullptr) {
    const std::string text = v.text ? v.text : "", choices = f.choices;
    size_t begin = 0;
    bool found = false;
    while (!found && begin <= choices.size()) {
      const size_t end = std::min(choices.find('|', begin), choices.size());
      found = choices.compare(begin, end - begin, text) == 0 && end - begin == text.size();
      begin = end + 1;
    }
    if (!found) throw ConfigError("setting '" + key + "': '" + text + "' is not one of " + choices);
  }
}

template <class T>
constexpr int32_t numberType() {
  return std::is_floating_point_v<T> ? BESLAM_CONFIG_DOUBLE : BESLAM_CONFIG_INT;
}

}  // namespace detail

// bool member.
template <class O>
Setting<O> setting(bool O::*member, const char* key, const char* def, const char* doc) {
  return {field::Bool(key, def, doc), [member](const beslam_config_value& v, O& o) { o.*member = v.number != 0.0; }};
}

// Integer or floating-point member, range [min, max] (min > max: unbounded).
template <class O, class T, std::enable_if_t<std::is_arithmetic_v<T> && !std::is_same_v<T, bool>, int> = 0>
Setting<O> setting(T O::*member, const char* key, const char* def, double min, double max, const char* doc) {
  const beslam_config_field f{key, detail::numberType<T>(), def == nullptr, def, min, max, nullptr, doc};
  return {f, [member](const beslam_config_value& v, O& o) { o.*member = static_cast<T>(v.number); }};
}

// String member; choices "a|b|c", or nullptr for any string.
template <class O>
Setting<O> setting(std::string O::*member, const char* key, const char* def, const char* choices, const char* doc) {
  return {field::String(key, def, choices, doc),
          [member](const beslam_config_value& v, O& o) { o.*member = v.text ? v.text : ""; }};
}

// A file or folder (string member); the host resolves a relative value against the pipeline's folder.
template <class O>
Setting<O> path(std::string O::*member, const char* key, const char* def, const char* doc) {
  return {field::Path(key, def, doc),
          [member](const beslam_config_value& v, O& o) { o.*member = v.text ? v.text : ""; }};
}

// List of numbers, each in [min, max]; a list of integers also checks each is a whole number.
template <class O, class T, std::enable_if_t<std::is_arithmetic_v<T> && !std::is_same_v<T, bool>, int> = 0>
Setting<O> setting(std::vector<T> O::*member, const char* key, const char* def, double min, double max,
                   const char* doc) {
  return {field::DoubleList(key, def, min, max, doc), [member, key](const beslam_config_value& v, O& o) {
            std::vector<T> values;
            for (uint64_t i = 0; i < v.list_size; ++i) {
              if (std::is_integral_v<T> && v.list[i] != static_cast<double>(static_cast<int64_t>(v.list[i])))
                throw ConfigError("setting '" + std::string(key) + "': element " + std::to_string(i + 1) + " (" +
                                  std::to_string(v.list[i]) + ") is not a whole number");
              values.push_back(static_cast<T>(v.list[i]));
            }
            o.*member = std::move(values);
          }};
}

// List of exactly N numbers, each in [min, max].
template <class O, size_t N>
Setting<O> setting(std::array<double, N> O::*member, const char* key, const char* def, double min, double max,
                   const char* doc) {
  return {field::DoubleList(key, def, min, max, doc), [member, key](const beslam_config_value& v, O& o) {
            if (v.list_size != N)
              throw ConfigError("setting '" + std::string(key) + "': expected " + std::to_string(N) + " numbers, got " +
                                std::to_string(v.list_size));
            for (size_t i = 0; i < N; ++i) (o.*member)[i] = v.list[i];
          }};
}

// An enum (or any) member chosen by name: the schema's choices are the names, in the order given.
template <class O, class E>
Setting<O> choice(E O::*member, const char* key, const char* def, std::vector<std::pair<const char*, E>> names,
                  const char* doc) {
  Setting<O> s;
  for (const auto& [name, value] : names) s.owned_choices += (s.owned_choices.empty() ? "" : "|") + std::string(name);
  s.field = field::String(key, def, nullptr, doc);
  s.assign = [member, names, key](const beslam_config_value& v, O& o) {
    const std::string text = v.text ? v.text : "";
    for (const auto& [name, value] : names)
      if (text == name) {
        o.*member = value;
        return;
      }
    throw ConfigError("setting '" + std::string(key) + "': unknown choice '" + text + "'");
  };
  return s;
}

// A string setting turned into another type by parse(text) (e.g. "Car,Van" -> class ids); parse throws
// std::invalid_argument for text it cannot use, which becomes ConfigError "key: message".
template <class O, class T, class Parse>
Setting<O> parsed(T O::*member, const char* key, const char* def, const char* choices, const char* doc, Parse parse) {
  return {field::String(key, def, choices, doc), [member, key, parse](const beslam_config_value& v, O& o) {
            try {
              o.*member = parse(std::string(v.text ? v.text : ""));
            } catch (const ConfigError&) {
              throw;
            } catch (const std::invalid_argument& e) {
              throw ConfigError(std::string(key) + ": " + e.what());
            }
          }};
}

// A setting of a member's member: nested(&Options::contour, setting(&Contour::low, "canny_low", ...)).
template <class O, class Inner>
Setting<O> nested(Inner O::*member, Setting<Inner> inner) {
  Setting<O> s;
  s.field = inner.field;
  s.owned_choices = std::move(inner.owned_choices);
  s.assign = [member, assign = std::move(inner.assign)](const beslam_config_value& v, O& o) { assign(v, o.*member); };
  return s;
}

// A plugin's settings: the schema (fields(), size()) and the typed reader (read()). Declare one as a
// namespace-scope constant; it is neither copied nor moved (the schema points into it).
template <class O>
class Settings {
 public:
  Settings(std::initializer_list<Setting<O>> settings) : Settings(std::vector<Setting<O>>(settings)) {}
  // Shared settings first (e.g. a family of plugins' common keys), then this plugin's own.
  explicit Settings(std::vector<Setting<O>> settings, std::vector<Setting<O>> more = {})
      : settings_(std::move(settings)) {
    for (Setting<O>& s : more) settings_.push_back(std::move(s));
    for (Setting<O>& s : settings_) {
      if (!s.owned_choices.empty()) s.field.choices = s.owned_choices.c_str();
      fields_.push_back(s.field);
    }
  }
  Settings(const Settings&) = delete;
  Settings& operator=(const Settings&) = delete;

  const beslam_config_field* fields() const { return fields_.data(); }
  uint32_t size() const { return static_cast<uint32_t>(fields_.size()); }

  // The values into `options` (members without a setting keep theirs). Every declared setting must be
  // present (the host passes all, defaults filled); see the header comment for what is checked.
  void read(const Config& config, O& options) const {
    for (uint32_t i = 0; i < config.size(); ++i) {
      const beslam_config_value& v = config.at(i);
      const Setting<O>* s = find(v.key);
      if (s == nullptr)
        throw ConfigError("unknown setting '" + std::string(v.key ? v.key : "") + "' (known: " + known() + ")");
      detail::checkValue(s->field, v);
    }
    for (const Setting<O>& s : settings_) {
      const beslam_config_value* v = config.find(s.field.key);
      if (v == nullptr) throw ConfigError("setting '" + std::string(s.field.key) + "' is missing");
      s.assign(*v, options);
    }
  }
  O read(const Config& config) const {
    O options{};
    read(config, options);
    return options;
  }

 private:
  const Setting<O>* find(const char* key) const {
    for (const Setting<O>& s : settings_)
      if (key != nullptr && std::strcmp(s.field.key, key) == 0) return &s;
    return nullptr;
  }
  std::string known() const {
    std::string out;
    for (const Setting<O>& s : settings_) out += (out.empty() ? "" : ", ") + std::string(s.field.key);
    return out;
  }

  std::vector<Setting<O>> settings_;
  std::vector<beslam_config_field> fields_;
};

}  // namespace beslam::sdk
