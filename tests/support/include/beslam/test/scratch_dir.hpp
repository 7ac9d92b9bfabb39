// ScratchDir: a gtest fixture with its own TempDir for each test (removed after it).
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "beslam/test/temp_dir.hpp"

namespace beslam::test {

class ScratchDir : public ::testing::Test {
 protected:
  std::string path(const std::string& name) const { return (temp_.path() / name).string(); }
  // Writes `content` to `name` in the folder; returns its path.
  std::string write(const std::string& name, const std::string& content) const { return temp_.write(name, content); }

 private:
  TempDir temp_;
};

}  // namespace beslam::test
