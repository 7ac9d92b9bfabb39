#pragma once
// Small helpers for the --flag parsing of beslam's sub-commands (eval-motion, eval-static-map, ...).
// Both throw std::invalid_argument with the message the command prints as a usage error.
#include <cstddef>
#include <exception>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

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

}  // namespace beslam::cli
