// SPDX-License-Identifier: Apache-2.0
// The planner's report (docs/planner.md, "Reading the report"), read back from the files it writes:
// history.png has tick marks, numbers and titles on both axes; side.png fits its content, keeps
// the aspect ratio, draws obstacles at their height, has metre ticks and cameras on top; the table
// gives the removal cost its unit. Pixel positions are derived from what the image itself shows
// (the volume's outline, the axis lines, the curve), not from the drawing code's constants.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "panoptes/image_file_cv.h"
#include "panoptes/plan_io/plan_report.h"
#include "panoptes/plan_io/room_file.h"

namespace panoptes::planner {
namespace {

namespace fs = std::filesystem;

const cv::Vec3b kVolumeColour(200, 120, 40);  // BGR, the volume's outline

bool is_black(const cv::Vec3b& p) {
  return p[0] < 70 && p[1] < 70 && p[2] < 70;
}
bool is_white(const cv::Vec3b& p) {
  return p[0] == 255 && p[1] == 255 && p[2] == 255;
}
bool is_red(const cv::Vec3b& p) {
  return p[2] > 150 && p[1] < 110 && p[0] < 110;
}
// An obstacle's outline or fill; frusta are lighter grey (150 and their anti-aliased edges).
bool is_dark_grey(const cv::Vec3b& p) {
  return p[0] == p[1] && p[1] == p[2] && p[0] <= 130;
}

// The studio of deploy/planner/studio6x6.yaml with four cameras on the walls, a pillar through the
// ceiling (0 to 4 m, above every mount) and a 0.8 m table; one camera (north) is in front of the
// pillar as the side view sees it.
class PlanReport : public ::testing::Test {
 protected:
  void SetUp() override {
    file_ = load_room(fs::path(PANOPTES_SOURCE_DIR) / "deploy/planner/studio6x6.yaml");
    file_.room.obstacles = {{Eigen::Vector3d(2.3, 2.3, 0.0), Eigen::Vector3d(2.7, 2.7, 4.0)},
                            {Eigen::Vector3d(-2.8, -0.5, 0.0), Eigen::Vector3d(-2.3, 0.5, 0.8)}};
    samples_ = draw_samples(file_.room, file_.occluders, 300, 8, 1);
    const Lens& lens = file_.room.lenses.front();
    const Eigen::Vector3d aim(0, 0, 1);
    input_.title = "test plan";
    input_.room = &file_.room;
    input_.samples = &samples_;
    input_.metric = file_.metric;
    input_.cameras = {
        make_camera("sw", lens, {-3.0, -3.0, 2.5}, aim), make_camera("north", lens, {2.5, 3.0, 2.6}, aim),
        make_camera("east", lens, {3.0, -1.0, 2.4}, aim), make_camera("west", lens, {-3.0, 1.0, 2.8}, aim)};
    input_.evaluation = evaluate(input_.cameras, samples_, file_.room.obstacles, file_.metric);
    input_.tracking.rmse_gaps_charged_m = 0.00398;
    input_.removal_costs = {0.00412, 0.0051, 0.00633, 0.0047};
    for (int i = 0; i < kSweeps; ++i)
      input_.history.push_back(0.5 * std::pow(0.002 / 0.5, i / (kSweeps - 1.0)));
    input_.objective = "q";  // the history falls from 0.5 m to 0.002 m
    dir_ = fs::temp_directory_path() /
           ("plan_report_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  cv::Mat render(const std::string& name) {
    write_report(input_, dir_);
    cv::Mat image = to_mat(read_picture(dir_ / name));
    EXPECT_FALSE(image.empty()) << dir_ / name;
    return image;
  }

  static constexpr int kSweeps = 41;
  RoomFile file_;
  SampleSet samples_;
  ReportInput input_;
  fs::path dir_;
};

// The longest run of pixels matching `test` along row `row` (or column, when `vertical`).
struct PixelRun {
  int at = -1, begin = 0, end = 0;  // the row (column) and the run's first and last pixel
  int length() const { return end - begin + 1; }
};

template <typename Test>
PixelRun longest_run(const cv::Mat& image, bool vertical, Test test) {
  PixelRun best;
  const int lines = vertical ? image.cols : image.rows, along = vertical ? image.rows : image.cols;
  for (int line = 0; line < lines; ++line) {
    int start = -1;
    for (int i = 0; i <= along; ++i) {
      const bool hit =
          i < along && test(vertical ? image.at<cv::Vec3b>(i, line) : image.at<cv::Vec3b>(line, i));
      if (hit && start < 0) start = i;
      if (!hit && start >= 0) {
        if (i - start > best.length() || best.at < 0) best = {line, start, i - 1};
        start = -1;
      }
    }
  }
  return best;
}

// Any pixel matching `test` in rows [row0, row1] and columns [col0, col1] (clipped to the image).
template <typename Test>
bool any_in(const cv::Mat& image, int row0, int row1, int col0, int col1, Test test) {
  for (int r = std::max(row0, 0); r <= std::min(row1, image.rows - 1); ++r)
    for (int c = std::max(col0, 0); c <= std::min(col1, image.cols - 1); ++c)
      if (test(image.at<cv::Vec3b>(r, c))) return true;
  return false;
}

// World to pixel on a view, read off the volume's outline: its edges are the volume's faces.
struct Mapping {
  double left = 0, right = 0, top = 0, bottom = 0;  // pixel centres of the outline's edges
  double a_min = 0, a_max = 1, b_min = 0, b_max = 1;

  double column(double a) const { return left + (a - a_min) / (a_max - a_min) * (right - left); }
  double row(double b) const { return bottom - (b - b_min) / (b_max - b_min) * (bottom - top); }
};

Mapping volume_mapping(const cv::Mat& image, const Box& volume, int a, int b) {
  std::vector<int> by_row(image.rows, 0), by_column(image.cols, 0);
  for (int r = 0; r < image.rows; ++r)
    for (int c = 0; c < image.cols; ++c)
      if (image.at<cv::Vec3b>(r, c) == kVolumeColour) {
        ++by_row[r];
        ++by_column[c];
      }
  const auto edges = [](const std::vector<int>& counts, double& low, double& high) {
    const int threshold = *std::max_element(counts.begin(), counts.end()) / 2;
    std::vector<int> lines;
    for (int i = 0; i < static_cast<int>(counts.size()); ++i)
      if (counts[i] > threshold) lines.push_back(i);
    ASSERT_GE(lines.size(), 2U);
    // A 2-pixel outline: the edge's centre lies between its two rows.
    low = lines.front() + 0.5;
    high = lines.back() - 0.5;
  };
  Mapping m;
  edges(by_row, m.top, m.bottom);
  edges(by_column, m.left, m.right);
  m.a_min = volume.min[a];
  m.a_max = volume.max[a];
  m.b_min = volume.min[b];
  m.b_max = volume.max[b];
  return m;
}

TEST_F(PlanReport, HistoryHasTickMarksWithNumbersAtTheSweepColumns) {
  const cv::Mat image = render("history.png");
  const PixelRun axis = longest_run(image, false, is_black);
  ASSERT_GT(axis.length(), image.cols / 2) << "no x axis line";
  for (int sweep = 10; sweep <= 40; sweep += 10) {
    const int column =
        static_cast<int>(std::lround(axis.begin + (sweep - 1.0) / (kSweeps - 1.0) * (axis.end - axis.begin)));
    EXPECT_TRUE(any_in(image, axis.at + 2, axis.at + 5, column - 1, column + 1, is_black))
        << "no tick mark below the axis at sweep " << sweep << ", column " << column;
    EXPECT_TRUE(any_in(image, axis.at + 8, axis.at + 24, column - 12, column + 12, is_black))
        << "no number under the tick at sweep " << sweep;
  }
  // Between two ticks (sweep 12.5) there is none.
  const int between =
      static_cast<int>(std::lround(axis.begin + 11.5 / (kSweeps - 1.0) * (axis.end - axis.begin)));
  EXPECT_FALSE(any_in(image, axis.at + 2, axis.at + 5, between - 1, between + 1, is_black));
}

TEST_F(PlanReport, HistoryHasLogarithmicValueTicksWithNumbers) {
  const cv::Mat image = render("history.png");
  const PixelRun axis = longest_run(image, true, is_black);
  ASSERT_GT(axis.length(), image.rows / 3) << "no y axis line";
  const PixelRun x_axis = longest_run(image, false, is_black);
  ASSERT_GT(x_axis.length(), image.cols / 2);
  // The curve's rows at its first and last sweep give the value scale (0.5 m and 0.002 m).
  const auto curve_row = [&](int column) {
    double sum = 0;
    int count = 0;
    for (int r = 0; r < image.rows; ++r)
      if (is_red(image.at<cv::Vec3b>(r, column))) {
        sum += r;
        ++count;
      }
    EXPECT_GT(count, 0) << "no curve in column " << column;
    return count > 0 ? sum / count : 0.0;
  };
  const double first = curve_row(x_axis.begin + 2), last = curve_row(x_axis.end - 2);
  for (const double value : {0.1, 0.01}) {
    const double row = first + std::log10(0.5 / value) / std::log10(0.5 / 0.002) * (last - first);
    const int r = static_cast<int>(std::lround(row));
    EXPECT_TRUE(any_in(image, r - 3, r + 3, axis.at - 5, axis.at - 2, is_black))
        << "no tick mark left of the axis at " << value << " m, row " << r;
    EXPECT_TRUE(any_in(image, r - 6, r + 6, axis.at - 50, axis.at - 9, is_black)) << "no number at " << value;
  }
}

TEST_F(PlanReport, HistoryHasAxisTitles) {
  const cv::Mat image = render("history.png");
  const PixelRun x_axis = longest_run(image, false, is_black);
  const PixelRun y_axis = longest_run(image, true, is_black);
  ASSERT_GT(x_axis.length(), image.cols / 2);
  ASSERT_GT(y_axis.length(), image.rows / 3);
  const int centre = (x_axis.begin + x_axis.end) / 2;
  EXPECT_TRUE(any_in(image, x_axis.at + 28, x_axis.at + 55, centre - 60, centre + 60, is_black)) << "x title";
  const int middle = (y_axis.begin + y_axis.end) / 2;
  EXPECT_TRUE(any_in(image, middle - 40, middle + 40, 0, y_axis.at - 45, is_black)) << "y title";
}

TEST_F(PlanReport, SideViewFillsTheImage) {
  const cv::Mat image = render("side.png");
  // The tallest band of rows that are white across the whole image.
  int band = 0, longest = 0;
  for (int r = 0; r < image.rows; ++r) {
    bool white = true;
    for (int c = 0; c < image.cols && white; ++c) white = is_white(image.at<cv::Vec3b>(r, c));
    band = white ? band + 1 : 0;
    longest = std::max(longest, band);
  }
  EXPECT_LT(longest, image.rows / 10) << "an empty band of " << longest << " of " << image.rows << " rows";
}

TEST_F(PlanReport, SideViewKeepsTheAspectRatio) {
  const cv::Mat image = render("side.png");
  const Mapping m = volume_mapping(image, file_.room.volume, 0, 2);
  const double width = m.right - m.left, height = m.bottom - m.top;  // 4 m by 2 m
  EXPECT_NEAR(width / height, 2.0, 0.04);
}

TEST_F(PlanReport, SideViewDrawsObstaclesAtTheirHeight) {
  const cv::Mat image = render("side.png");
  const Mapping m = volume_mapping(image, file_.room.volume, 0, 2);
  for (const Box& obstacle : file_.room.obstacles) {
    const double expected = m.row(obstacle.max.z());
    ASSERT_GE(expected, 0) << "the obstacle's top (" << obstacle.max.z() << " m) is outside the image";
    const int c0 = static_cast<int>(std::lround(m.column(obstacle.min.x()))) + 3;
    const int c1 = static_cast<int>(std::lround(m.column(obstacle.max.x()))) - 3;
    // The first row dark grey across (nearly) the obstacle's width: a frustum line may cross it.
    int top = -1;
    for (int r = 0; r < image.rows && top < 0; ++r) {
      int grey = 0;
      for (int c = c0; c <= c1; ++c) grey += is_dark_grey(image.at<cv::Vec3b>(r, c)) ? 1 : 0;
      if (grey >= 0.9 * (c1 - c0 + 1)) top = r;
    }
    EXPECT_NEAR(top, expected, 2.0) << "obstacle up to " << obstacle.max.z() << " m";
  }
}

TEST_F(PlanReport, ViewsHaveTickMarksWithNumbersAtWholeMetres) {
  for (const auto& [name, b] : {std::pair<std::string, int>{"side.png", 2}, {"top.png", 1}}) {
    const cv::Mat image = render(name);
    const Mapping m = volume_mapping(image, file_.room.volume, 0, b);
    const PixelRun axis = longest_run(image, false, is_black);
    ASSERT_GT(axis.length(), image.cols / 2) << name << ": no x axis line";
    for (int metre = -3; metre <= 3; ++metre) {
      const int column = static_cast<int>(std::lround(m.column(metre)));
      EXPECT_TRUE(any_in(image, axis.at + 2, axis.at + 5, column - 1, column + 1, is_black))
          << name << ": no tick at x = " << metre << " m, column " << column;
      EXPECT_TRUE(any_in(image, axis.at + 8, axis.at + 24, column - 10, column + 10, is_black))
          << name << ": no number at x = " << metre << " m";
    }
    const PixelRun y_axis = longest_run(image, true, is_black);
    ASSERT_GT(y_axis.length(), image.rows / 4) << name << ": no vertical axis line";
    for (int metre = 0; metre <= 2; ++metre) {
      const int row = static_cast<int>(std::lround(m.row(metre)));
      EXPECT_TRUE(any_in(image, row - 1, row + 1, y_axis.at - 5, y_axis.at - 2, is_black))
          << name << ": no tick at " << metre << " m, row " << row;
    }
  }
}

TEST_F(PlanReport, SideViewDrawsCamerasOverObstacles) {
  const cv::Mat image = render("side.png");
  const Mapping m = volume_mapping(image, file_.room.volume, 0, 2);
  const Eigen::Vector3d north = input_.cameras[1].model.center_world();  // in front of the pillar
  const int r = static_cast<int>(std::lround(m.row(north.z())));
  const int c = static_cast<int>(std::lround(m.column(north.x())));
  EXPECT_TRUE(any_in(image, r - 1, r + 1, c - 1, c + 1, is_red)) << "camera at row " << r << ", column " << c;
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST_F(PlanReport, RemovalCostsHaveTheirUnit) {
  input_.objective = "tracker_rmse";
  write_report(input_, dir_);
  std::string html = read_text(dir_ / "report.html");
  EXPECT_NE(html.find("tracker_rmse without it (mm)"), std::string::npos);
  EXPECT_NE(html.find("<td>4.12</td>"), std::string::npos) << "0.00412 m in mm";
  EXPECT_NE(html.find("predicted tracker RMSE with gaps charged"), std::string::npos) << "what the cost is";

  input_.objective = "q";
  input_.removal_costs = {0.25, 0.5, 0.125, 0.0625};
  write_report(input_, dir_);
  html = read_text(dir_ / "report.html");
  EXPECT_NE(html.find("q without it (m)"), std::string::npos);
  EXPECT_NE(html.find("<td>0.125</td>"), std::string::npos);
}

}  // namespace
}  // namespace panoptes::planner
