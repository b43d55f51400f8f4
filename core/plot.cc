#include "core/plot.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "core/atomic_file.h"
#include "core/cores.h"
#include "core/errors.h"
#include "core/report_values.h"

namespace coaxid {
namespace {

// A gnuplot single-quoted string: a quote inside is doubled.
std::string Quoted(const std::string& text) {
  std::string out = "'";
  for (const char c : text) {
    if (c == '\'') out += '\'';
    if (c == '\n' || c == '\r') {
      out += ' ';
      continue;
    }
    out += c;
  }
  out += "'";
  return out;
}

std::string Directory(const std::string& path) {
  const size_t slash = path.rfind('/');
  return slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
}

std::string BaseName(const std::string& path) {
  const size_t slash = path.rfind('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

bool HasFinitePoint(const PlotSeries& s) {
  const size_t n = std::min(s.x.size(), s.y.size());
  for (size_t k = 0; k < n; ++k) {
    if (std::isfinite(s.x[k]) && std::isfinite(s.y[k])) return true;
  }
  return false;
}

std::string FormatNumber(double v) {
  if (std::isnan(v)) return "NaN";
  return Significant(v, 9);
}

// Runs `gnuplot -e "outfile='OUT'; term='TERM'" SCRIPT` in `dir` (the script
// names its data file relative to its own folder), stdout discarded, stderr
// kept in `err_path`. Returns the exit status, or -1 with errno-style reason.
int RunGnuplot(const std::string& dir, const std::string& script, const std::string& out,
               const std::string& term, const std::string& err_path, std::string* why) {
  const std::string settings = "outfile=" + Quoted(out) + "; term=" + Quoted(term);
  const pid_t pid = ::fork();
  if (pid < 0) {
    *why = std::string("cannot start gnuplot: ") + std::strerror(errno);
    return -1;
  }
  if (pid == 0) {
    // Child: only async-signal-safe calls until exec.
    if (::chdir(dir.c_str()) != 0) ::_exit(126);
    const int null_fd = ::open("/dev/null", O_WRONLY);
    const int err_fd = ::open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (null_fd >= 0) ::dup2(null_fd, STDOUT_FILENO);
    if (err_fd >= 0) ::dup2(err_fd, STDERR_FILENO);
    const char* argv[] = {"gnuplot", "-e", settings.c_str(), script.c_str(), nullptr};
    ::execvp("gnuplot", const_cast<char* const*>(argv));
    ::_exit(127);  // not found or not executable
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) {
      *why = std::string("waiting for gnuplot: ") + std::strerror(errno);
      return -1;
    }
  }
  if (!WIFEXITED(status)) {
    *why = "gnuplot was killed by a signal";
    return -1;
  }
  return WEXITSTATUS(status);
}

std::string ReadSmallFile(const std::string& path) {
  try {
    std::string text = ReadFile(path);
    if (text.size() > 600) text = text.substr(0, 600) + "...";
    while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
    return text;
  } catch (const InputError&) {
    return "";
  }
}

std::string Script(const Figure& figure, const std::string& data_name,
                   const std::string& png_name) {
  const int panels = static_cast<int>(figure.panels.size());
  const int columns = std::max(1, figure.columns);
  const int rows = std::max(1, (panels + columns - 1) / columns);
  const int height = figure.height_px > 0 ? figure.height_px : 320 * rows + 40;
  std::string s;
  s += "# Made by coaxid (core/plot.cc). Rerun in this folder: gnuplot " +
       png_name.substr(0, png_name.size() - 4) + ".gp\n";
  s += "if (!exists(\"outfile\")) outfile = " + Quoted(png_name) + "\n";
  s += "if (!exists(\"term\")) term = 'pngcairo'\n";
  s += "eval sprintf(\"set terminal %s size %d,%d noenhanced\", term, " +
       std::to_string(figure.width_px) + ", " + std::to_string(height) + ")\n";
  s += "set output outfile\n";
  s += "set multiplot layout " + std::to_string(rows) + "," + std::to_string(columns) + " title " +
       Quoted(figure.title) + "\n";
  int block = 0;
  for (const PlotPanel& panel : figure.panels) {
    s += "reset\nset grid\nset key " + panel.key + "\n";
    s += "set title " + Quoted(panel.title) + "\n";
    s += "set xlabel " + Quoted(panel.x_label) + "\n";
    s += "set ylabel " + Quoted(panel.y_label) + "\n";
    if (panel.log_y) s += "set logscale y\n";
    if (!panel.x_categories.empty()) {
      s += "set xtics rotate by -40 left (";
      for (size_t i = 0; i < panel.x_categories.size(); ++i) {
        s += (i ? ", " : "") + Quoted(panel.x_categories[i]) + " " + std::to_string(i);
      }
      s += ")\nset xrange [-0.5:" + std::to_string(panel.x_categories.size() - 0.5) + "]\n";
    }
    if (std::isfinite(panel.y_min) || std::isfinite(panel.y_max)) {
      s += "set yrange [" + (std::isfinite(panel.y_min) ? FormatNumber(panel.y_min) : "*") + ":" +
           (std::isfinite(panel.y_max) ? FormatNumber(panel.y_max) : "*") + "]\n";
    }
    std::string plot;
    for (const PlotSeries& series : panel.series) {
      if (HasFinitePoint(series)) {
        plot += plot.empty() ? "plot " : ", \\\n     ";
        plot += Quoted(data_name) + " index " + std::to_string(block) + " using 1:2 with " +
                series.style + " " +
                (series.title.empty() ? std::string("notitle") : "title " + Quoted(series.title));
      }
      ++block;  // every series has a block in the data file, even an empty one
    }
    if (plot.empty()) {
      // Linear axes: [0:1] on a log axis is an error that loses the whole figure.
      s += "unset logscale\nunset border\nunset tics\nset label 1 'no data' at graph 0.5,0.5 "
           "center\n";
      plot = "plot [0:1][0:1] -1 notitle";
    }
    s += plot + "\n";
  }
  s += "unset multiplot\n";
  return s;
}

// The rows of a series to write. A line (style "lines...") with x
// non-decreasing and more than four points per pixel column of its panel is
// drawn from the first, lowest, highest and last point of each pixel column,
// in x order, and every gap (NaN): the same image, since a line cannot show
// more, at a fraction of gnuplot's time (a 48 s, 200 Hz flight log's fit
// figure: 9600 points per curve). Anything else is written whole.
std::vector<size_t> RowsToDraw(const PlotSeries& series, int pixel_columns) {
  const size_t n = std::min(series.x.size(), series.y.size());
  std::vector<size_t> all(n);
  for (size_t k = 0; k < n; ++k) all[k] = k;
  if (series.style.rfind("lines", 0) != 0 || n <= 4 * static_cast<size_t>(pixel_columns)) {
    return all;
  }
  for (size_t k = 0; k < n; ++k) {
    if (!std::isfinite(series.x[k])) return all;
    if (k > 0 && series.x[k] < series.x[k - 1]) return all;
  }
  const double x0 = series.x.front(), x1 = series.x[n - 1];
  if (!(x1 > x0)) return all;
  std::vector<size_t> rows;
  long column = -1;
  size_t first = 0, low = 0, high = 0, last = 0;
  bool open = false;
  auto flush = [&] {
    if (!open) return;
    std::vector<size_t> picked = {first, low, high, last};
    std::sort(picked.begin(), picked.end());
    picked.erase(std::unique(picked.begin(), picked.end()), picked.end());
    rows.insert(rows.end(), picked.begin(), picked.end());
    open = false;
  };
  for (size_t k = 0; k < n; ++k) {
    if (!std::isfinite(series.y[k])) {
      flush();
      rows.push_back(k);  // the gap
      continue;
    }
    const long c = static_cast<long>((series.x[k] - x0) / (x1 - x0) * pixel_columns);
    if (!open || c != column) {
      flush();
      column = c;
      first = low = high = last = k;
      open = true;
      continue;
    }
    last = k;
    if (series.y[k] < series.y[low]) low = k;
    if (series.y[k] > series.y[high]) high = k;
  }
  flush();
  return rows;
}

std::string Data(const Figure& figure) {
  std::string d;
  int block = 0;
  const int pixel_columns = figure.width_px / std::max(1, figure.columns);
  for (const PlotPanel& panel : figure.panels) {
    for (const PlotSeries& series : panel.series) {
      d += "# block " + std::to_string(block++) + ": " + panel.title + " / " + series.title + "\n";
      const size_t n = std::min(series.x.size(), series.y.size());
      for (size_t k : RowsToDraw(series, pixel_columns)) {
        d += FormatNumber(series.x[k]);
        d += ' ';
        d += FormatNumber(series.y[k]);
        d += '\n';
      }
      // An empty block still needs a line so that `index` counts it.
      if (n == 0) d += "NaN NaN\n";
      d += "\n\n";
    }
  }
  return d;
}

// The slow half of RenderFigure, after the data and script are written: runs gnuplot on
// STEM.gp in dir and renames its image into place. Thread-safe (each call forks its own
// gnuplot and touches only its own files).
bool RunPreparedFigure(const std::string& dir, const std::string& stem,
                       const std::string& png_path, std::string* error) {
  // gnuplot writes a temporary image renamed into place only on success: a
  // failed run leaves no broken PNG.
  const std::string tmp_name = "." + stem + ".tmp.png";
  const std::string err_path = dir + "/." + stem + ".gnuplot.err";
  bool ok = false;
  for (const char* term : {"pngcairo", "png"}) {
    std::string why;
    const int status = RunGnuplot(dir, stem + ".gp", tmp_name, term, err_path, &why);
    if (status == 0) {
      ok = std::rename((dir + "/" + tmp_name).c_str(), png_path.c_str()) == 0;
      if (!ok) *error = "cannot rename the image into place: " + std::string(std::strerror(errno));
      break;
    }
    if (status == 127) {
      *error = "gnuplot could not be run";
      break;
    }
    const std::string messages = ReadSmallFile(err_path);
    *error = status < 0 ? why : "gnuplot failed (exit " + std::to_string(status) + "): " + messages;
    // Only a missing terminal is worth a second try with the plain png terminal.
    if (messages.find("terminal") == std::string::npos) break;
  }
  ::unlink((dir + "/" + tmp_name).c_str());
  ::unlink(err_path.c_str());
  return ok;
}

// The fast half: checks the path and gnuplot, writes STEM.dat and STEM.gp. On success sets
// *dir and *stem for RunPreparedFigure.
bool PrepareFigure(const Figure& figure, const std::string& png_path, std::string* dir,
                   std::string* stem, std::string* error) {
  if (png_path.size() < 5 || png_path.substr(png_path.size() - 4) != ".png") {
    *error = "plot path '" + png_path + "' does not end in .png";
    return false;
  }
  if (!GnuplotAvailable()) {
    *error = "gnuplot is not installed (no gnuplot on the PATH)";
    return false;
  }
  *dir = Directory(png_path);
  const std::string png_name = BaseName(png_path);
  *stem = png_name.substr(0, png_name.size() - 4);
  const std::string data_name = *stem + ".dat";
  try {
    WriteFileAtomically(*dir + "/" + data_name, Data(figure));
    WriteFileAtomically(*dir + "/" + *stem + ".gp", Script(figure, data_name, png_name));
  } catch (const InputError& e) {
    *error = e.what();
    return false;
  }
  return true;
}

}  // namespace

bool GnuplotAvailable() {
  const char* path = std::getenv("PATH");
  if (path == nullptr) return false;
  std::string paths = path;
  size_t start = 0;
  while (start <= paths.size()) {
    const size_t colon = paths.find(':', start);
    std::string dir =
        paths.substr(start, colon == std::string::npos ? std::string::npos : colon - start);
    if (dir.empty()) dir = ".";
    if (::access((dir + "/gnuplot").c_str(), X_OK) == 0) return true;
    if (colon == std::string::npos) break;
    start = colon + 1;
  }
  return false;
}

bool RenderFigure(const Figure& figure, const std::string& png_path, std::string* error) {
  std::string ignored;
  if (error == nullptr) error = &ignored;
  std::string dir, stem;
  return PrepareFigure(figure, png_path, &dir, &stem, error) &&
         RunPreparedFigure(dir, stem, png_path, error);
}

FigureRenderer::FigureRenderer(int parallel) {
  if (parallel <= 0) parallel = NumCores();
  for (int i = 0; i < parallel; ++i) workers_.emplace_back([this] { Work(); });
}

FigureRenderer::~FigureRenderer() {
  std::string ignored;
  Finish(&ignored);
}

void FigureRenderer::Add(const Figure& figure, const std::string& png_path,
                         const std::string& label) {
  auto job = std::make_unique<Job>();
  job->png_path = png_path;
  job->label = label.empty() ? png_path : label;
  const bool prepared = PrepareFigure(figure, png_path, &job->dir, &job->stem, &job->error);
  std::lock_guard<std::mutex> lock(mutex_);
  const int index = static_cast<int>(jobs_.size());
  jobs_.push_back(std::move(job));
  if (prepared) {
    queue_.push_back(index);
    ready_.notify_one();
  }
}

void FigureRenderer::Work() {
  for (;;) {
    Job* job = nullptr;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      ready_.wait(lock, [this] { return closing_ || !queue_.empty(); });
      if (queue_.empty()) return;  // closing, nothing left
      job = jobs_[queue_.front()].get();
      queue_.pop_front();
    }
    std::string error;
    const bool ok = RunPreparedFigure(job->dir, job->stem, job->png_path, &error);
    std::lock_guard<std::mutex> lock(mutex_);
    job->ok = ok;
    job->error = error;
  }
}

std::vector<std::string> FigureRenderer::Finish(std::string* first_error) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    closing_ = true;
  }
  ready_.notify_all();
  for (std::thread& worker : workers_) worker.join();
  workers_.clear();
  std::vector<std::string> made;
  first_error->clear();
  for (const auto& job : jobs_) {
    if (job->ok) {
      made.push_back(job->label);
    } else if (first_error->empty()) {
      *first_error = job->error;
    }
  }
  return made;
}

std::vector<std::string> RenderFigures(const std::vector<NamedFigure>& figures,
                                       const std::string& folder, std::string* first_error) {
  FigureRenderer renderer;
  for (const NamedFigure& f : figures) renderer.Add(f.figure, folder + "/" + f.file, f.file);
  return renderer.Finish(first_error);
}

}  // namespace coaxid
