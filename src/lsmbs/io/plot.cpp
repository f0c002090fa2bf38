#include "lsmbs/io/plot.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

extern char** environ;

namespace lsmbs {

std::string gnuplot_quote(const std::string& s) {
  std::string q = "\"";
  for (char c : s) {
    if (c == '\\' || c == '"') q += '\\';
    q += c;
  }
  return q + "\"";
}

bool run_gnuplot(const std::string& script) {
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&fa, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&fa, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
  std::string arg0 = "gnuplot", arg1 = script;
  char* argv[] = {arg0.data(), arg1.data(), nullptr};
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, "gnuplot", &fa, nullptr, argv, environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) return false;  // not installed
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return false;
  return WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

bool plot(const PlotSpec& s) {
  const std::string script = s.png + ".gp";
  {
    std::ofstream g(script);
    g << "set terminal pngcairo size 900,560 noenhanced\nset output " << gnuplot_quote(s.png)
      << "\n"
      << "set datafile separator ','\nset title " << gnuplot_quote(s.title) << "\nset xlabel "
      << gnuplot_quote(s.xlabel) << "\nset ylabel " << gnuplot_quote(s.ylabel)
      << "\nset grid\nset key outside right\n";
    if (s.logx) g << "set logscale x\nset format x '%.0e'\n";
    if (s.logy) g << "set logscale y\nset format y '%.0e'\n";
    if (s.ymax > s.ymin) g << "set yrange [" << s.ymin << ":" << s.ymax << "]\n";
    g << "plot ";
    bool first = true;
    for (const auto& p : s.series) {
      g << (first ? "" : ", ") << gnuplot_quote(p.csv) << " every ::1 using " << p.x_column << ":"
        << p.y_column << " with " << p.style << " title " << gnuplot_quote(p.title);
      first = false;
    }
    for (const auto& f : s.functions) {
      g << (first ? "" : ", ") << f;
      first = false;
    }
    g << "\n";
  }
  const bool ok = run_gnuplot(script);
  std::filesystem::remove(script);
  std::error_code ec;
  if (!ok) std::filesystem::remove(s.png, ec);  // no half-written picture
  return ok && std::filesystem::exists(s.png);
}

bool plot_panels(const PanelPlotSpec& s, const std::vector<std::vector<double>>& rows) {
  using P = PanelPlotSpec;
  if (s.panels.empty() || rows.size() < 2) return false;
  const int np = static_cast<int>(s.panels.size());
  const int W = s.width, H = P::kTop + P::kBottom + np * s.panel_height + (np - 1) * P::kGap;
  const double x0 = rows.front()[0], x1 = rows.back()[0];
  if (!(x1 > x0)) return false;
  const std::string script = s.png + ".gp";
  {
    std::ofstream g(script);
    g << std::setprecision(17);
    g << "set terminal pngcairo size " << W << "," << H << " noenhanced\nset output "
      << gnuplot_quote(s.png) << "\nset datafile separator ','\nset grid\n"
      << "set key outside right top\nset multiplot title " << gnuplot_quote(s.title) << "\n"
      << "set lmargin at screen " << double(P::kLeft) / W << "\nset rmargin at screen "
      << double(W - P::kRight) / W << "\nset xrange [" << x0 << ":" << x1 << "]\n";
    for (int i = 0; i < np; ++i) {
      const Panel& p = s.panels[i];
      double lo = INFINITY, hi = -INFINITY;
      for (const auto& r : rows)
        for (const auto& ser : p.series) {
          const double v = r[static_cast<size_t>(ser.column - 1)];
          if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
        }
      if (!(hi >= lo)) lo = -1, hi = 1;  // nothing finite
      const double pad = hi > lo ? 0.05 * (hi - lo) : lo != 0 ? 0.05 * std::abs(lo) : 1.0;
      // pixel rows from the top: the screen coordinates gnuplot takes run from the bottom
      const int top = P::kTop + i * (s.panel_height + P::kGap), bottom = top + s.panel_height;
      g << "set tmargin at screen " << 1 - double(top) / H << "\nset bmargin at screen "
        << 1 - double(bottom) / H << "\nset yrange [" << lo - pad << ":" << hi + pad << "]\n"
        << "set ylabel " << gnuplot_quote(p.ylabel) << "\n"
        << (i + 1 == np ? "set format x\nset xlabel " + gnuplot_quote(s.xlabel)
                        : std::string("set format x ''\nunset xlabel"))
        << "\nplot ";
      for (size_t k = 0; k < p.series.size(); ++k)
        g << (k ? ", " : "") << gnuplot_quote(s.csv) << " every ::1 using 1:" << p.series[k].column
          << " with lines lw 1.5 lc rgb '" << kSeriesColours[k % std::size(kSeriesColours)]
          << "' title " << gnuplot_quote(p.series[k].title);
      g << "\n";
    }
    g << "unset multiplot\n";
  }
  const bool ok = run_gnuplot(script);
  std::filesystem::remove(script);
  std::error_code ec;
  if (!ok) std::filesystem::remove(s.png, ec);
  return ok && std::filesystem::exists(s.png);
}

bool plot_bars(const BarChartSpec& s) {
  if (s.groups.empty() || s.series.empty() || s.values.size() != s.series.size()) return false;
  double lo = 0, hi = 0;
  for (const auto& v : s.values)
    for (double x : v)
      if (std::isfinite(x)) lo = std::min(lo, x), hi = std::max(hi, x);
  if (!(hi > lo)) hi = 1;
  const double pad = 0.1 * (hi - lo);
  const std::string data = s.png + ".dat", script = s.png + ".gp";
  {
    std::ofstream d(data);  // tab-separated: the group label, then one value per series
    d << std::setprecision(17);
    for (size_t g = 0; g < s.groups.size(); ++g) {
      std::string label;
      for (char c : s.groups[g]) label += c == '\t' || c == '\n' ? ' ' : c;
      d << label;
      for (const auto& v : s.values) d << "\t" << (std::isfinite(v[g]) ? v[g] : NAN);
      d << "\n";
    }
    std::ofstream g(script);
    g << "set terminal pngcairo size " << s.width << "," << s.height << " noenhanced\nset output "
      << gnuplot_quote(s.png) << "\nset datafile separator '\\t'\nset datafile missing 'nan'\n"
      << "set title " << gnuplot_quote(s.title) << "\nset ylabel " << gnuplot_quote(s.ylabel)
      << "\nset style data histograms\nset style histogram clustered gap 1\n"
      << "set style fill solid 0.9 border -1\nset boxwidth 0.9\nset grid ytics\n"
      << "set xtics rotate by -30 nomirror\nset key outside right top\nset xzeroaxis lt -1\n"
      << "set bmargin 7\nset yrange [" << lo - pad << ":" << hi + pad << "]\nplot ";
    for (size_t k = 0; k < s.series.size(); ++k)
      g << (k ? ", " : "") << gnuplot_quote(data) << " using " << k + 2 << (k ? "" : ":xtic(1)")
        << " lc rgb '" << kSeriesColours[k % std::size(kSeriesColours)] << "' title "
        << gnuplot_quote(s.series[k]);
    g << "\n";
  }
  const bool ok = run_gnuplot(script);
  std::filesystem::remove(script);
  std::filesystem::remove(data);
  std::error_code ec;
  if (!ok) std::filesystem::remove(s.png, ec);
  return ok && std::filesystem::exists(s.png);
}

}  // namespace lsmbs
