#include "beslam/common/run_folder.hpp"

#include <fstream>

#include "beslam/common/error.hpp"

namespace beslam {

RunFolder readRunFolder(const std::string& run_dir) {
  RunFolder run;
  run.dir = run_dir;
  const std::string path = run_dir + "/summary.json";
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot open (is " + run_dir + " a run folder?)");
  try {
    run.summary = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw Error(path + ": not JSON (" + e.what() + ")");
  }
  if (!run.summary.is_object()) throw Error(path + ": not a run summary (no JSON object)");
  run.dataset_path = run.summary.value("dataset_path", "");
  if (run.dataset_path.empty()) throw Error(path + ": no dataset_path (a run of an older beslam?)");
  run.dataset_sequence = run.summary.value("dataset_sequence", "00");
  return run;
}

}  // namespace beslam
