// A run folder as the scorers read it: summary.json, and the synthetic sequence it ran on (its
// dataset_path, where the truth files are). Errors are one beslam::Error naming the file.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace beslam {

struct RunFolder {
  std::string dir;
  nlohmann::json summary;
  std::string dataset_path;      // the sequence folder (SEQ: SEQ/label_02, SEQ/objects_motion.txt ...)
  std::string dataset_sequence;  // "00"
};

// Reads RUN/summary.json; throws when it is missing, not JSON, or names no dataset_path (a run on data
// without truth files, or of an older beslam).
RunFolder readRunFolder(const std::string& run_dir);

}  // namespace beslam
