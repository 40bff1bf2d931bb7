// SPDX-License-Identifier: Apache-2.0
// glob_files: POSIX patterns (bracket expressions included, which cv::glob did not understand),
// byte-order sorting, directories left out, no match as an empty list.
#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "panoptes/glob.h"
#include "temp_dir.h"

namespace panoptes {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

// File names relative to `dir`, in the order glob_files returned them.
std::vector<std::string> names(const std::vector<fs::path>& paths, const fs::path& dir) {
  std::vector<std::string> result;
  result.reserve(paths.size());
  for (const fs::path& path : paths) result.push_back(path.lexically_relative(dir).string());
  return result;
}

// A chessboard series of two cameras, written in an order that is not the name order.
class GlobTest : public ::testing::Test {
 protected:
  void SetUp() override {
    for (const char* name : {"right2.jpg", "left10.jpg", "left2.jpg", "left1.jpg", "leftover.jpg",
                             "left3.png", "right1.jpg", "notes.txt"})
      dir_.write(name, "x");
  }
  std::vector<std::string> match(const std::string& pattern) const {
    return names(glob_files((dir_.file("") / pattern).string()), dir_.file(""));
  }
  TempDir dir_;
};

TEST_F(GlobTest, BracketExpressionSelectsDigitsOnly) {
  // The case cv::glob got wrong: `[0-9]` is a character class, not literal text.
  EXPECT_EQ(match("left[0-9]*.jpg"), (std::vector<std::string>{"left1.jpg", "left10.jpg", "left2.jpg"}));
  EXPECT_EQ(match("*[12].jpg"),
            (std::vector<std::string>{"left1.jpg", "left2.jpg", "right1.jpg", "right2.jpg"}));
  EXPECT_EQ(match("left[!0-9]*"), (std::vector<std::string>{"leftover.jpg"}));
}

TEST_F(GlobTest, StarAndQuestionMark) {
  EXPECT_EQ(match("*.jpg"), (std::vector<std::string>{"left1.jpg", "left10.jpg", "left2.jpg", "leftover.jpg",
                                                      "right1.jpg", "right2.jpg"}));
  // `?` is exactly one character: left10.jpg has two digits.
  EXPECT_EQ(match("left?.*"), (std::vector<std::string>{"left1.jpg", "left2.jpg", "left3.png"}));
  EXPECT_EQ(match("right?.jpg"), (std::vector<std::string>{"right1.jpg", "right2.jpg"}));
}

TEST_F(GlobTest, SortsByBytesWhateverTheCreationOrder) {
  const std::vector<std::string> all = match("*");
  ASSERT_EQ(all.size(), 8u);
  EXPECT_TRUE(std::is_sorted(all.begin(), all.end())) << ::testing::PrintToString(all);
  EXPECT_EQ(all.front(), "left1.jpg");
  EXPECT_EQ(all.back(), "right2.jpg");
}

TEST_F(GlobTest, NoMatchIsEmptyNotAnError) {
  EXPECT_TRUE(match("left[4-9].jpg").empty());
  EXPECT_TRUE(match("*.pgm").empty());
  EXPECT_TRUE(glob_files((dir_.file("missing_directory") / "*.jpg").string()).empty());
}

TEST_F(GlobTest, PlainPathMatchesItselfOnlyIfItExists) {
  EXPECT_EQ(match("notes.txt"), (std::vector<std::string>{"notes.txt"}));
  EXPECT_TRUE(match("absent.txt").empty());
}

TEST_F(GlobTest, DirectoriesAreLeftOutAndEscapesAreLiteral) {
  fs::create_directories(dir_.file("left9.jpg"));  // a directory whose name matches
  dir_.write("left[5].jpg", "x");                  // brackets in a real file name
  EXPECT_EQ(match("left?.jpg"), (std::vector<std::string>{"left1.jpg", "left2.jpg"}));
  EXPECT_EQ(match("left\\[5\\].jpg"), (std::vector<std::string>{"left[5].jpg"}));
  EXPECT_TRUE(match("left[5].jpg").empty());  // unescaped, [5] is the class {5}: left5.jpg
}

}  // namespace
}  // namespace panoptes
