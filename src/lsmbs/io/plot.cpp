#include "lsmbs/io/plot.hpp"

#include <cstdlib>
#include <filesystem>
#include <fstream>

namespace lsmbs {

bool plot(const PlotSpec& s) {
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) return false;
  const std::string script = s.png + ".gp";
  {
    std::ofstream g(script);
    g << "set terminal pngcairo size 900,560 noenhanced\nset output '" << s.png << "'\n"
      << "set datafile separator ','\nset title '" << s.title << "'\nset xlabel '" << s.xlabel << "'\nset ylabel '"
      << s.ylabel << "'\nset grid\nset key outside right\n";
    if (s.logx) g << "set logscale x\nset format x '%.0e'\n";
    if (s.logy) g << "set logscale y\nset format y '%.0e'\n";
    if (s.ymax > s.ymin) g << "set yrange [" << s.ymin << ":" << s.ymax << "]\n";
    g << "plot ";
    bool first = true;
    for (const auto& p : s.series) {
      g << (first ? "" : ", ") << "'" << p.csv << "' every ::1 using " << p.x_column << ":" << p.y_column << " with "
        << p.style << " title '" << p.title << "'";
      first = false;
    }
    for (const auto& f : s.functions) {
      g << (first ? "" : ", ") << f;
      first = false;
    }
    g << "\n";
  }
  const bool ok = std::system(("gnuplot '" + script + "' >/dev/null 2>&1").c_str()) == 0;
  std::filesystem::remove(script);
  return ok && std::filesystem::exists(s.png);
}

}  // namespace lsmbs
