// `beslam eval`: argument parsing and reporting around evaluateFiles.
#include <charconv>
#include <cmath>
#include <exception>
#include <optional>
#include <ostream>

#include "beslam/common/error.hpp"
#include "beslam/common/file_io.hpp"
#include "beslam/eval/eval.hpp"

namespace beslam::eval {
namespace {

constexpr const char* kUsage =
    "usage: beslam eval --ref FILE --est FILE [options]\n"
    "Absolute and relative pose error (APE, RPE) of an estimated trajectory, as evo computes them.\n"
    "\n"
    "  --ref FILE          reference (ground-truth) trajectory\n"
    "  --est FILE          estimated trajectory\n"
    "  --format kitti|tum  file format (default: from the column count of the reference)\n"
    "  --align none|se3|sim3\n"
    "                      Umeyama alignment of the estimate to the reference (default none)\n"
    "  --align-first N     fit the alignment on the first N pose pairs only (default 0 = all)\n"
    "  --max-diff S        TUM: max. time difference for associating stamps, seconds (default 0.01)\n"
    "  --offset S          TUM: time offset added to the estimate's stamps, seconds (default 0)\n"
    "  --delta N           RPE frame delta (default 1)\n"
    "  --all-pairs         RPE over every pair (i, i+N) instead of consecutive pairs\n"
    "  --json FILE         also write the results as JSON\n"
    "  --help              this text\n"
    "\n"
    "Exit status: 0 success, 1 bad input file, 2 usage error.\n";

struct UsageError {
  std::string message;
};

double parseDouble(const std::string& option, const std::string& text) {
  double value = 0.0;
  const char* begin = text.data() + (!text.empty() && text[0] == '+' ? 1 : 0);
  const auto [ptr, ec] = std::from_chars(begin, text.data() + text.size(), value);
  if (text.empty() || ec != std::errc() || ptr != text.data() + text.size() || !std::isfinite(value)) {
    throw UsageError{option + " expects a number, not '" + text + "'"};
  }
  return value;
}

std::size_t parseCount(const std::string& option, const std::string& text, std::size_t minimum) {
  std::size_t value = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || ec != std::errc() || ptr != text.data() + text.size() || value < minimum) {
    throw UsageError{option + " expects a whole number >= " + std::to_string(minimum) + ", not '" + text + "'"};
  }
  return value;
}

}  // namespace

int runEvalCommand(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  std::string ref_path, est_path, json_path;
  EvalOptions options;
  try {
    for (std::size_t i = 0; i < args.size(); ++i) {
      std::string option = args[i];
      std::optional<std::string> inline_value;
      if (const std::size_t eq = option.find('='); option.rfind("--", 0) == 0 && eq != std::string::npos) {
        inline_value = option.substr(eq + 1);
        option.resize(eq);
      }
      auto value = [&]() -> std::string {
        if (inline_value) return *inline_value;
        if (i + 1 >= args.size()) throw UsageError{option + " needs a value"};
        return args[++i];
      };
      if (option == "--help" || option == "-h") {
        out << kUsage;
        return 0;
      } else if (option == "--ref") {
        ref_path = value();
      } else if (option == "--est") {
        est_path = value();
      } else if (option == "--format") {
        options.format = value();
        if (options.format != "kitti" && options.format != "tum") {
          throw UsageError{"--format must be kitti or tum, not '" + options.format + "'"};
        }
      } else if (option == "--align") {
        const std::string name = value();
        try {
          options.alignment = parseAlignmentType(name);
        } catch (const Error&) {
          throw UsageError{"--align must be none, se3 or sim3, not '" + name + "'"};
        }
      } else if (option == "--align-first") {
        options.align_first_n = parseCount(option, value(), 0);
      } else if (option == "--max-diff") {
        options.max_diff = parseDouble(option, value());
        if (options.max_diff < 0.0) throw UsageError{"--max-diff must not be negative"};
      } else if (option == "--offset") {
        options.est_time_offset = parseDouble(option, value());
      } else if (option == "--delta") {
        options.delta = parseCount(option, value(), 1);
      } else if (option == "--all-pairs" && !inline_value) {
        options.all_pairs = true;
      } else if (option == "--json") {
        json_path = value();
      } else {
        throw UsageError{"unknown argument '" + args[i] + "'"};
      }
    }
    if (ref_path.empty() || est_path.empty()) throw UsageError{"both --ref FILE and --est FILE are required"};
  } catch (const UsageError& e) {
    err << "beslam eval: " << e.message << " (see beslam eval --help)\n";
    return 2;
  }

  try {
    const EvalResult result = evaluateFiles(ref_path, est_path, options);
    if (!json_path.empty()) writeFileAtomic(json_path, toJson(result) + "\n");
    out << "reference: " << ref_path << "\nestimate:  " << est_path << "\n" << formatTable(result);
    return 0;
  } catch (const std::exception& e) {
    err << "beslam eval: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace beslam::eval
