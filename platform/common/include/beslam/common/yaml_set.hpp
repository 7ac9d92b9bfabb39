// `--set a.b.c=value` overrides on a YAML tree, shared by every command that reads a YAML file.
// The value is parsed as YAML, so numbers, booleans, strings and flow lists ("[1, 2]") all work.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>

namespace beslam {

// Applies one "dotted.key=value" assignment to root, creating maps on the way.
// Throws beslam::Error naming the assignment when it has no '=', an empty key, or a bad value,
// or when a key on the path is a scalar or list rather than a map.
void applySetOverride(YAML::Node& root, const std::string& assignment);

}  // namespace beslam
