// Small file helpers shared by every host module: readFile and writeFileAtomic come from the SDK's
// formats component (beslam/formats/file.hpp); makeDirectories is the host's own.
#pragma once

#include <string>

#include "beslam/formats/file.hpp"

namespace beslam {

// Creates a directory and its parents; throws beslam::Error naming the path on failure.
void makeDirectories(const std::string& path);

}  // namespace beslam
