#include "lsmbs/io/plot.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <filesystem>
#include <fstream>

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

}  // namespace lsmbs
