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
#include <string>

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

}  // namespace
}  // namespace coaxid
