// Command-line helpers for tool writers: the --flag parsing of beslam's sub-commands (eval-motion,
// eval-static-map, ...) and of a plugin's own tools (beslam-vocab, mask_bench). They throw
// std::invalid_argument with the message the command prints as a usage error. runMain: the exit-code
// convention of the beslam command and the tools. Header-only; beslam::Error comes from the formats.
#pragma once

#include <cstddef>
#include <exception>
#include <functional>
#include <map>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "beslam/formats/error.hpp"

namespace beslam::cli {

/// Walks the arguments in order: "--help" or "-h" calls help() and returns true at once (the command
/// then exits 0); any other calls flag(args[i], i), which takes the flag's values with nextValue(args, i)
/// and throws std::invalid_argument for one it does not know. False when no help was asked for.
inline bool forEachFlag(const std::vector<std::string>& args, const std::function<void()>& help,
                        const std::function<void(const std::string& flag, std::size_t& i)>& flag) {
  for (std::size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--help" || args[i] == "-h") {
      help();
      return true;
    }
    flag(args[i], i);
  }
  return false;
}

/// The value after the flag at args[i]; advances i past it.
inline std::string nextValue(const std::vector<std::string>& args, std::size_t& i) {
  if (i + 1 >= args.size()) throw std::invalid_argument(args[i] + " needs a value");
  return args[++i];
}

/// `text` read whole as a number > 0, else "FLAG expects a positive number, not 'TEXT'".
inline double positiveNumber(const std::string& flag, const std::string& text) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || !(v > 0))
    throw std::invalid_argument(flag + " expects a positive number, not '" + text + "'");
  return v;
}

/// `text` read whole as an integer in [lo, hi], else "FLAG: 'TEXT' is not an integer from LO to HI".
inline int integerInRange(const std::string& flag, const std::string& text, int lo, int hi) {
  std::size_t used = 0;
  long long v = 0;
  try {
    v = std::stoll(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || v < lo || v > hi)
    throw std::invalid_argument(flag + ": '" + text + "' is not an integer from " + std::to_string(lo) + " to " +
                                std::to_string(hi));
  return static_cast<int>(v);
}

/// The value after the flag at args[i] as a number > 0; advances i past it.
inline double nextPositiveNumber(const std::vector<std::string>& args, std::size_t& i) {
  const std::string& flag = args[i];
  const std::string text = nextValue(args, i);
  return positiveNumber(flag, text);
}

/// What a flag does with its value: text(s) keeps the text, positive(x) a number > 0 (positiveNumber).
using FlagValue = std::function<void(const std::string& flag, const std::string& text)>;
inline FlagValue text(std::string& out) {
  return [&out](const std::string&, const std::string& value) { out = value; };
}
inline FlagValue positive(double& out) {
  return [&out](const std::string& flag, const std::string& value) { out = positiveNumber(flag, value); };
}

/// forEachFlag for a command whose flags each take one value, given as a table flag -> what it does with
/// it; any other flag is "unknown argument 'FLAG'".
inline bool forEachValueFlag(const std::vector<std::string>& args, const std::function<void()>& help,
                             const std::map<std::string, FlagValue>& flags) {
  return forEachFlag(args, help, [&](const std::string& flag, std::size_t& i) {
    const auto it = flags.find(flag);
    if (it == flags.end()) throw std::invalid_argument("unknown argument '" + flag + "'");
    it->second(flag, nextValue(args, i));
  });
}

/// A `beslam NAME` command in two steps: parse() reads the flags and returns true when help was asked
/// (exit 0); a std::invalid_argument from it is a usage error, "beslam NAME: MESSAGE (see beslam NAME
/// --help)", exit 2. Then run() does the work and gives the exit code; an exception from it is
/// "beslam NAME: MESSAGE", exit 1.
inline int runSubcommand(const std::string& name, std::ostream& err, const std::function<bool()>& parse,
                         const std::function<int()>& run) {
  try {
    if (parse()) return 0;
  } catch (const std::invalid_argument& e) {
    err << "beslam " << name << ": " << e.what() << " (see beslam " << name << " --help)\n";
    return 2;
  }
  try {
    return run();
  } catch (const std::exception& e) {
    err << "beslam " << name << ": " << e.what() << "\n";
    return 1;
  }
}

/// A command's main(): body()'s exit code, or what it throws as one message on `err`: a usage error (type
/// Usage) as "<usage_prefix>MESSAGE" and then the usage text, exit 2; beslam::Error as
/// "<error_prefix>MESSAGE", any other exception as "<other_prefix>MESSAGE" (error_prefix when empty), exit 1.
template <class Usage, class Body>
int runMain(Body&& body, std::ostream& err, const std::string& usage, const std::string& usage_prefix,
            const std::string& error_prefix, const std::string& other_prefix = "") {
  try {
    return body();
  } catch (const Usage& e) {
    err << usage_prefix << e.what() << "\n" << usage;
    return 2;
  } catch (const beslam::Error& e) {
    err << error_prefix << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    err << (other_prefix.empty() ? error_prefix : other_prefix) << e.what() << "\n";
    return 1;
  }
}

}  // namespace beslam::cli
