// A folder of its own for a test's files outside the build tree: removed when the test passes,
// kept (and named) when it fails, for inspection. Tests never leave files in /tmp otherwise.
#pragma once

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace vi_ekf_slam::test {

class ScratchDir {
 public:
  /// whole_run: kept when any test of the program failed (a folder shared by helpers); else when
  /// the current test failed.
  explicit ScratchDir(const std::string& prefix = "vi_ekf_slam_test", bool whole_run = false) : whole_run_(whole_run) {
    std::string pattern = (std::filesystem::temp_directory_path() / (prefix + "_XXXXXX")).string();
    if (!mkdtemp(pattern.data())) throw std::runtime_error("cannot create a folder like " + pattern);
    path_ = pattern;
  }
  ~ScratchDir() {
    if (whole_run_ ? ::testing::UnitTest::GetInstance()->Failed() : ::testing::Test::HasFailure()) {
      std::printf("the test's files are kept in %s\n", path_.c_str());
      return;
    }
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;

  const std::string& path() const { return path_; }
  /// A path inside it.
  std::string operator/(const std::string& name) const { return path_ + "/" + name; }

 private:
  bool whole_run_;
  std::string path_;
};

/// The test program's own folder for helpers' files, removed at exit unless a test failed.
inline const ScratchDir& programScratch() {
  static const ScratchDir dir("vi_ekf_slam_tests", true);
  return dir;
}

}  // namespace vi_ekf_slam::test
