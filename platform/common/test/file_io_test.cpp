#include "beslam/common/file_io.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>

#include "beslam/common/error.hpp"

namespace fs = std::filesystem;

TEST(FileIo, AtomicWriteReplacesContent) {
  const fs::path dir = fs::temp_directory_path() / "beslam_common_test";
  fs::create_directories(dir);
  const std::string path = (dir / "a.txt").string();
  beslam::writeFileAtomic(path, "first");
  beslam::writeFileAtomic(path, "second");
  EXPECT_EQ(beslam::readFile(path), "second");
  fs::remove_all(dir);
}

TEST(FileIo, FailedWriteKeepsOldContentAndLeavesNoTemporary) {
  const fs::path dir = fs::temp_directory_path() / "beslam_common_test2";
  fs::create_directories(dir);
  const std::string path = (dir / "a.txt").string();
  beslam::writeFileAtomic(path, "good");
  EXPECT_THROW(beslam::writeFileAtomic(path,
                                       [](std::ostream& out) {
                                         out << "half";
                                         throw std::runtime_error("writer failed");
                                       }),
               std::runtime_error);
  EXPECT_EQ(beslam::readFile(path), "good");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
  fs::remove_all(dir);
}

TEST(FileIo, MissingFileNamesPath) {
  try {
    beslam::readFile("/nonexistent/beslam/file.txt");
    FAIL() << "expected an error";
  } catch (const beslam::Error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/beslam/file.txt"), std::string::npos);
  }
}
