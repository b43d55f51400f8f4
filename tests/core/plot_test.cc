// core/plot.h, the gnuplot wrapper the baseline's figures use (tested here
// with its only user so far): it makes a PNG with its data and script next to
// it, and reports rather than fails when gnuplot is missing.
#include "core/plot.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "core/atomic_file.h"

namespace coaxid {
namespace {

namespace fs = std::filesystem;

class PlotTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("coaxid_plot_test_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  static Figure TwoPanels() {
    Figure f;
    f.title = "it's a test_1";  // a quote and an underscore: escaped, not enhanced text
    f.columns = 2;
    PlotPanel a;
    a.title = "a";
    PlotSeries s{"x^2", {}, {}, "linespoints"};
    for (int k = 0; k < 10; ++k) {
      s.x.push_back(k);
      s.y.push_back(k == 4 ? std::numeric_limits<double>::quiet_NaN() : k * k);  // a gap
    }
    a.series.push_back(s);
    PlotPanel empty;  // no data at all: a "no data" panel, not a gnuplot error
    empty.title = "empty";
    empty.log_y = true;  // even on a log axis (a balance channel's residual periodogram)
    empty.series.push_back({"nothing", {}, {}, "lines"});
    f.panels = {a, empty};
    return f;
  }
  fs::path dir_;
};

TEST_F(PlotTest, MakesAPngWithItsDataAndScript) {
  if (!GnuplotAvailable()) GTEST_SKIP() << "gnuplot not installed";
  const std::string png = (dir_ / "fig.png").string();
  std::string error;
  ASSERT_TRUE(RenderFigure(TwoPanels(), png, &error)) << error;
  EXPECT_TRUE(fs::exists(png));
  EXPECT_GT(fs::file_size(png), 1000u);
  EXPECT_TRUE(fs::exists(dir_ / "fig.dat"));
  EXPECT_TRUE(fs::exists(dir_ / "fig.gp"));
  // Nothing else left behind (temporary image, gnuplot's messages).
  int files = 0;
  for (const auto& entry : fs::directory_iterator(dir_)) {
    (void)entry;
    ++files;
  }
  EXPECT_EQ(files, 3);
  EXPECT_NE(ReadFile((dir_ / "fig.gp").string()).find("it''s a test_1"), std::string::npos);
}

// A line with far more points than pixel columns is written as each pixel
// column's first, lowest, highest and last point (and its gaps): every
// extreme of the full series is in the data, in x order, with a fraction of
// the rows. Points are written whole.
TEST_F(PlotTest, LongLinesKeepEachPixelColumnsExtremes) {
  if (!GnuplotAvailable()) GTEST_SKIP() << "gnuplot not installed";
  Figure f;
  f.width_px = 400;  // one panel: 400 pixel columns
  PlotPanel panel;
  PlotSeries line{"line", {}, {}, "lines"}, points{"points", {}, {}, "points"};
  const int n = 40000;
  for (int k = 0; k < n; ++k) {
    line.x.push_back(k * 0.001);
    // Fast noise-like wiggle on a slow sine, one spike and one gap.
    double y = std::sin(k * 0.0005) + 0.1 * std::sin(k * 1.7);
    if (k == 12345) y = 5.0;
    if (k == 30000) y = std::numeric_limits<double>::quiet_NaN();
    line.y.push_back(y);
  }
  points.x = {0, 1, 2};
  points.y = {1, 2, 3};
  panel.series = {line, points};
  f.panels = {panel};
  std::string error;
  ASSERT_TRUE(RenderFigure(f, (dir_ / "long.png").string(), &error)) << error;
  std::vector<std::vector<std::pair<double, double>>> blocks(1);
  std::istringstream data(ReadFile((dir_ / "long.dat").string()));
  std::string row;
  int blank = 0;
  while (std::getline(data, row)) {
    if (row.empty()) {
      if (++blank == 2 && !blocks.back().empty()) blocks.emplace_back();
      continue;
    }
    blank = 0;
    if (row[0] == '#') continue;
    std::istringstream in(row);
    std::string x, y;
    in >> x >> y;
    blocks.back().push_back({std::stod(x), y == "NaN" ? NAN : std::stod(y)});
  }
  ASSERT_GE(blocks.size(), 2u);
  const auto& written = blocks[0];
  EXPECT_LE(written.size(), 4u * 400 + 10);
  EXPECT_GE(written.size(), 400u);
  EXPECT_EQ(blocks[1].size(), 3u);
  // x in order, first and last point kept, the spike and the gap kept.
  for (size_t k = 1; k < written.size(); ++k) EXPECT_LE(written[k - 1].first, written[k].first);
  EXPECT_DOUBLE_EQ(written.front().first, 0.0);
  EXPECT_DOUBLE_EQ(written.back().first, (n - 1) * 0.001);
  double max_y = -1e9, min_y = 1e9;
  int gaps = 0;
  for (const auto& [x, y] : written) {
    if (std::isnan(y)) ++gaps;
    else max_y = std::max(max_y, y), min_y = std::min(min_y, y);
  }
  EXPECT_EQ(gaps, 1);
  EXPECT_DOUBLE_EQ(max_y, 5.0);
  double full_min = 1e9;
  for (double y : line.y) {
    if (!std::isnan(y)) full_min = std::min(full_min, y);
  }
  EXPECT_NEAR(min_y, full_min, 1e-8);  // written with 9 significant digits
}

TEST_F(PlotTest, ReportsAMissingGnuplotInsteadOfFailing) {
  const char* path = std::getenv("PATH");
  const std::string saved = path != nullptr ? path : "";
  ::setenv("PATH", "/nonexistent", 1);
  std::string error;
  const bool ok = RenderFigure(TwoPanels(), (dir_ / "fig.png").string(), &error);
  ::setenv("PATH", saved.c_str(), 1);
  EXPECT_FALSE(ok);
  EXPECT_NE(error.find("gnuplot"), std::string::npos) << error;
  EXPECT_FALSE(fs::exists(dir_ / "fig.png"));
}

TEST_F(PlotTest, ReportsAGnuplotError) {
  if (!GnuplotAvailable()) GTEST_SKIP() << "gnuplot not installed";
  Figure f = TwoPanels();
  f.panels[0].series[0].style = "no_such_style";
  std::string error;
  EXPECT_FALSE(RenderFigure(f, (dir_ / "bad.png").string(), &error));
  EXPECT_NE(error.find("gnuplot failed"), std::string::npos) << error;
  EXPECT_FALSE(fs::exists(dir_ / "bad.png"));
}

// Several gnuplot runs at once: every good figure is made, listed in the
// order added whatever order the runs finish in, and a bad one (a gnuplot
// error, a wrong path) is left out with the first failure's reason.
TEST_F(PlotTest, FigureRendererMakesEachFigureAndListsThemInOrder) {
  if (!GnuplotAvailable()) GTEST_SKIP() << "gnuplot not installed";
  FigureRenderer renderer(3);
  Figure bad = TwoPanels();
  bad.panels[0].series[0].style = "no_such_style";
  std::vector<std::string> expected;
  for (int i = 0; i < 7; ++i) {
    const std::string name = "fig" + std::to_string(i) + ".png";
    if (i == 2) {
      renderer.Add(bad, (dir_ / name).string(), name);
      continue;
    }
    if (i == 5) {
      renderer.Add(TwoPanels(), (dir_ / "not_an_image.txt").string(), name);
      continue;
    }
    renderer.Add(TwoPanels(), (dir_ / name).string(), name);
    expected.push_back(name);
  }
  std::string first_error;
  EXPECT_EQ(renderer.Finish(&first_error), expected);
  EXPECT_NE(first_error.find("gnuplot failed"), std::string::npos) << first_error;
  for (const std::string& name : expected) EXPECT_TRUE(fs::exists(dir_ / name)) << name;
  EXPECT_FALSE(fs::exists(dir_ / "fig2.png"));
  // Nothing half-made: no temporary image or error file left behind.
  for (const auto& entry : fs::directory_iterator(dir_)) {
    EXPECT_NE(entry.path().filename().string().front(), '.') << entry.path();
  }
}

}  // namespace
}  // namespace coaxid
