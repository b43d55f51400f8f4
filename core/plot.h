// A small gnuplot wrapper for the figures a run writes next to its report, so
// a user can look rather than read. The caller describes panels of x-y series;
// RenderFigure writes the data (one block per series) and a gnuplot script
// next to the image, then runs `gnuplot` on the script.
//
// Plots are a convenience, never a reason for a run to fail: when gnuplot is
// missing or fails, RenderFigure returns false with the reason (the caller
// notes "plots skipped" in its report) and leaves no half-made image behind.
#pragma once

#include <condition_variable>
#include <deque>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace coaxid {

struct PlotSeries {
  std::string title;         // legend entry; empty: no legend entry
  std::vector<double> x, y;  // same length; NaN is a gap
  // gnuplot `with` clause, e.g. "lines lw 2", "lines dt 2", "points pt 7 ps 0.6".
  std::string style = "lines";
};

struct PlotPanel {
  std::string title, x_label, y_label;
  bool log_y = false;                    // logarithmic y axis (positive values only)
  std::string key = "below horizontal";  // gnuplot `set key` arguments (where the legend goes)
  // y range; NaN (default) lets gnuplot choose that end.
  double y_min = std::numeric_limits<double>::quiet_NaN();
  double y_max = std::numeric_limits<double>::quiet_NaN();
  std::vector<PlotSeries> series;
  // Named x positions 0, 1, 2, ... (categories, written rotated); empty: numeric x tics.
  std::vector<std::string> x_categories;
};

struct Figure {
  std::string title;
  std::vector<PlotPanel> panels;
  int columns = 1;  // panels are laid out row by row, this many per row
  int width_px = 1200;
  int height_px = 0;  // 0: 320 px per row of panels
};

// Writes STEM.dat (the series; a long line only as the first, lowest,
// highest and last point of each pixel column, which draws the same image)
// and STEM.gp (the script; rerun it with
// `gnuplot STEM.gp` to tweak a figure), where STEM is png_path without its
// ".png", and runs gnuplot to make png_path (terminal pngcairo, or png where
// cairo is missing). Returns false with *error set when gnuplot is not
// installed, fails, or a file cannot be written.
bool RenderFigure(const Figure& figure, const std::string& png_path, std::string* error);

// A figure and the file name it is rendered to (e.g. "fig08_thrust_map.png").
struct NamedFigure {
  std::string file;
  Figure figure;
};

// Renders each figure into folder/file. Returns the files made; *first_error
// gets the reason the first failed one failed (empty when all were made).
std::vector<std::string> RenderFigures(const std::vector<NamedFigure>& figures,
                                       const std::string& folder, std::string* first_error);

// Renders figures with several gnuplot processes at once (gnuplot's start-up dominates a
// figure: a run with 20 logs writes 42 figures). Add() writes the figure's data and script at
// once, so the caller may drop the figure, and queues gnuplot; Finish() waits for all.
class FigureRenderer {
 public:
  // parallel: gnuplot processes at once; 0: the machine's hardware threads.
  explicit FigureRenderer(int parallel = 0);
  ~FigureRenderer();  // Finish()es
  FigureRenderer(const FigureRenderer&) = delete;
  FigureRenderer& operator=(const FigureRenderer&) = delete;
  // label: what Finish() lists for this figure when its image is made (e.g. the path
  // relative to the report); empty: png_path.
  void Add(const Figure& figure, const std::string& png_path, const std::string& label = "");
  // Waits for every figure. Returns the labels of the images made, in the order added;
  // *first_error gets why the first failed one failed (empty when all were made). Call once.
  std::vector<std::string> Finish(std::string* first_error);

 private:
  struct Job {
    std::string png_path, label, dir, stem, error;
    bool ok = false;
  };
  void Work();
  std::mutex mutex_;
  std::condition_variable ready_;
  std::vector<std::unique_ptr<Job>> jobs_;
  std::deque<int> queue_;
  std::vector<std::thread> workers_;
  bool closing_ = false;
};

// True if a `gnuplot` executable is on the PATH.
bool GnuplotAvailable();

}  // namespace coaxid
