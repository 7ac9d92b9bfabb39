// The dataset readers' text helpers: the SDK's formats component (beslam/formats/text.hpp).
#pragma once

#include "beslam/formats/text.hpp"

namespace beslam::datasets::detail {

using formats::isBlank;
using formats::parseDouble;
using formats::parseInt;
using formats::splitLines;
using formats::splitWhitespace;

}  // namespace beslam::datasets::detail
