// `mdem plot`'s drawing: a gnuplot script and a data file in a temporary directory, gnuplot run
// as a child process (posix_spawnp) with its output captured for error messages.
#include "plot.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "flags.h"

extern char** environ;

namespace mdem::cli {
namespace {

namespace fs = std::filesystem;

struct Unit {
  const char* suffix;
  const char* quantity;
  const char* unit;
};

// Longer suffixes first: "_nNnm" before "_nm".
constexpr Unit kUnits[] = {
    {"_eV", "energy", "eV"},
    {"_nNnm", "moment", "nN·nm"},
    {"_nN", "force", "nN"},
    {"_GPa", "stress", "GPa"},
    {"_nm", "length", "nm"},
    {"_ps", "time", "ps"},
    {"_K", "temperature", "K"},
    {"_deg", "angle", "deg"},
    {"_rad", "angle", "rad"},
    {"_per_ps", "rate", "1/ps"},
    {"_nm_per_ps", "velocity", "nm/ps"},
};

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

const Unit* unit_of(const std::string& column) {
  const Unit* best = nullptr;
  for (const Unit& u : kUnits)
    if (ends_with(column, u.suffix) && (!best || std::strlen(u.suffix) > std::strlen(best->suffix)))
      best = &u;
  return best;
}

std::string label_of(const std::string& column) {
  if (column == "step") return "step";
  const Unit* u = unit_of(column);
  return u ? std::string(u->quantity) + " (" + u->unit + ")" : column;
}

// A column in words: "bond_tension_eV" -> "bond tension", "vdw_eV" -> "van der Waals",
// "displacement_nm" -> "displacement".
std::string words_of(const std::string& column) {
  std::string name = column;
  if (const Unit* u = unit_of(column)) name.resize(name.size() - std::strlen(u->suffix));
  static const std::pair<const char*, const char*> kNames[] = {
      {"vdw", "van der Waals"},
      {"np_cnt", "NP-CNT contact"},
      {"np_np", "NP-NP contact"},
      {"kinetic_translational", "kinetic, translational"},
      {"kinetic_rotational", "kinetic, rotational"},
      {"balance_residual", "balance residual"},
      {"time", "time"}};
  for (const auto& [from, to] : kNames)
    if (name == from) return to;
  std::replace(name.begin(), name.end(), '_', ' ');
  return name;
}

// A column in words with its unit: "force_nN" -> "force (nN)".
std::string legend_of(const std::string& column) {
  const Unit* u = unit_of(column);
  return words_of(column) + (u ? std::string(" (") + u->unit + ")" : "");
}

std::string join(const std::vector<std::string>& v, const char* sep) {
  std::string out;
  for (const std::string& s : v) out += (out.empty() ? "" : sep) + s;
  return out;
}

std::vector<std::string> split_commas(const std::string& text) {
  std::vector<std::string> parts;
  std::stringstream ss(text);
  for (std::string part; std::getline(ss, part, ',');)
    if (!part.empty()) parts.push_back(part);
  return parts;
}

// A gnuplot single-quoted string ('' stands for one quote).
std::string quoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

std::size_t column_index(const std::vector<std::string>& columns, const std::string& name) {
  return static_cast<std::size_t>(std::find(columns.begin(), columns.end(), name) -
                                  columns.begin());
}

// A fresh directory under $TMPDIR, removed with everything in it on destruction.
class TempDir {
 public:
  TempDir() {
    std::string tmpl = (fs::temp_directory_path() / "mdem-plot-XXXXXX").string();
    if (!mkdtemp(tmpl.data()))
      throw PlotError("cannot create a temporary directory in '" +
                      fs::temp_directory_path().string() + "': " + std::strerror(errno));
    path_ = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string file(const char* name) const { return (path_ / name).string(); }

 private:
  fs::path path_;
};

double x_value(const PlotRequest& r, const SeriesFrame& f) {
  if (r.x == "time_ps") return f.time_ps;
  if (r.x == "step") return static_cast<double>(f.step);
  return r.x_scale * f.values[column_index(r.columns, r.x)];
}

void write_data(const std::string& path, const PlotRequest& r,
                const std::vector<SeriesFrame>& frames) {
  std::vector<std::size_t> picked;
  for (const std::string& c : r.selected) picked.push_back(column_index(r.columns, c));
  std::ofstream os(path);
  os << "# " << r.x << ' ' << join(r.selected, " ")
     << (r.energy_overview ? " (changes from the first frame)" : "") << '\n';
  char buf[32];
  for (const SeriesFrame& f : frames) {
    std::snprintf(buf, sizeof buf, "%.17g", x_value(r, f));
    os << buf;
    for (std::size_t k : picked) {
      const double start = r.energy_overview ? frames.front().values[k] : 0.0;
      std::snprintf(buf, sizeof buf, "%.17g", f.values[k] - start);
      os << ' ' << buf;
    }
    os << '\n';
  }
  if (!os.flush()) throw PlotError("cannot write the plot data to '" + path + "'");
}

// Ten distinct colours (matplotlib's tab10), so that nine energy components stay apart.
constexpr const char* kColours[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
                                    "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};

std::string line_types() {
  std::string s;
  int k = 0;
  for (const char* c : kColours)
    s += "set linetype " + std::to_string(++k) + " lc rgb '" + c + "' lw 1.5 pt 7\n";
  return s + "set linetype cycle " + std::to_string(k) + "\n";
}

std::string terminal_line(const std::string& terminal) {
  if (terminal == "svg")
    return "set terminal svg size 1000,640 dynamic font 'sans,11' background rgb 'white'";
  return "set terminal pngcairo size 1000,640 font 'sans,11'";
}

// The groups of the energy overview, each a panel: a column goes to the first group one of whose
// name parts it starts with (after any "kinetic"/"external" words), else to "other energy".
struct EnergyGroup {
  const char* title;
  std::vector<const char*> prefixes;
};
const std::vector<EnergyGroup>& energy_groups() {
  static const std::vector<EnergyGroup> groups = {
      {"bond energy", {"bond_"}},
      {"van der Waals and contact energy", {"vdw", "np_", "contact"}},
      {"kinetic energy", {"kinetic"}},
      {"work, dissipation and balance", {"external_work", "dissipated", "total", "balance"}},
      {"other energy", {""}}};
  return groups;
}

std::size_t group_of(const std::string& column) {
  const auto& groups = energy_groups();
  for (std::size_t g = 0; g < groups.size(); ++g)
    for (const char* p : groups[g].prefixes)
      if (column.rfind(p, 0) == 0) return g;
  return groups.size() - 1;
}

// One plot command: the columns `ks` (indices into r.selected) of the data file.
void plot_line(std::ostringstream& s, const PlotRequest& r, const std::string& data,
               const std::vector<std::size_t>& ks, const char* style,
               const std::string& second_unit) {
  s << "plot ";
  int n = 0;
  for (std::size_t k : ks) {
    const Unit* u = unit_of(r.selected[k]);
    const bool y2 = !second_unit.empty() && u && second_unit == u->unit;
    // Within a panel the lines differ in colour and dash pattern.
    s << (n ? ", \\\n     " : "") << quoted(data) << " using 1:" << k + 2 << ' ' << style << " lt "
      << n + 1 << " dt " << n % 5 + 1 << (y2 ? " axes x1y2" : "") << " title "
      << quoted(legend_of(r.selected[k]) + (y2 ? ", right axis" : ""));
    ++n;
  }
  s << "\n";
}

std::string script_text(const PlotRequest& r, const std::string& data,
                        const std::vector<SeriesFrame>& frames) {
  std::ostringstream s;
  const bool png = plot_terminal(r.out_path) == "pngcairo";
  s << "set encoding utf8\n";
  if (r.energy_overview)
    s << (png ? "set terminal pngcairo size 1400,900 font 'sans,11'"
              : "set terminal svg size 1400,900 dynamic font 'sans,11' background rgb 'white'")
      << "\n";
  else
    s << terminal_line(plot_terminal(r.out_path)) << "\n";
  s << "set termoption noenhanced\n"
    << "set output " << quoted(fs::absolute(r.out_path).string()) << "\n"
    << "set xlabel "
    << quoted(!r.x_label.empty()                  ? r.x_label
              : r.x == "time_ps" || r.x == "step" ? axis_label({r.x})
                                                  : legend_of(r.x))
    << "\n"
    << line_types() << "set grid\n";
  const char* style = frames.size() > 60 ? "with lines lw 1.8" : "with linespoints ps 0.6";
  if (!r.energy_overview) {
    // Two units: the second on a right-hand axis; more: one axis named by all of them.
    std::vector<std::string> units;
    for (const std::string& c : r.selected)
      if (const Unit* u = unit_of(c);
          u && std::find(units.begin(), units.end(), u->unit) == units.end())
        units.push_back(u->unit);
    std::vector<std::string> left = r.selected, right;
    if (units.size() == 2) {
      left.clear();
      for (const std::string& c : r.selected)
        (unit_of(c) && unit_of(c)->unit == units[1] ? right : left).push_back(c);
      s << "set y2label " << quoted(axis_label(right)) << "\nset ytics nomirror\nset y2tics\n";
    }
    s << "set title " << quoted(r.title) << "\n"
      << "set ylabel "
      << quoted(r.selected.size() == 1 ? legend_of(r.selected[0]) : axis_label(left)) << "\n"
      << "set key outside right top\n";
    std::vector<std::size_t> all(r.selected.size());
    for (std::size_t k = 0; k < all.size(); ++k) all[k] = k;
    plot_line(s, r, data, all, style, units.size() == 2 ? units[1] : "");
    s << "set output\n";
    return s.str();
  }
  // The energy overview: changes from the first frame, one panel per group; a component that
  // never changes is left out (named below the title).
  std::vector<std::vector<std::size_t>> panels(energy_groups().size());
  std::vector<std::size_t> flat;
  for (std::size_t k = 0; k < r.selected.size(); ++k) {
    const std::size_t c = column_index(r.columns, r.selected[k]);
    const bool changes = std::any_of(frames.begin(), frames.end(), [&](const SeriesFrame& f) {
      return f.values[c] != frames.front().values[c];
    });
    (changes ? panels[group_of(r.selected[k])] : flat).push_back(k);
  }
  std::vector<std::size_t> shown;
  for (std::size_t g = 0; g < panels.size(); ++g)
    if (!panels[g].empty()) shown.push_back(g);
  const std::size_t cols = shown.size() > 1 ? 2 : 1, rows = (shown.size() + cols - 1) / cols;
  std::vector<std::string> unchanged;
  for (std::size_t k : flat) unchanged.push_back(words_of(r.selected[k]));
  s << "set multiplot layout " << std::max<std::size_t>(rows, 1) << "," << cols << " title "
    << quoted(r.title + ": energy changes from the start" +
              (unchanged.empty() ? "" : "\n(unchanged, not drawn: " + join(unchanged, ", ") + ")"))
    << "\nset key top left box opaque\nset ylabel 'change from start (eV)'\n";
  for (std::size_t g : shown) {
    s << "set title " << quoted(energy_groups()[g].title) << "\n";
    plot_line(s, r, data, panels[g], style, "");
  }
  if (shown.empty()) s << "set title 'no energy changed'\nplot 0 notitle\n";
  s << "unset multiplot\nset output\n";
  return s.str();
}

std::string gnuplot_binary() {
  const char* env = std::getenv("MDEM_GNUPLOT");
  return env && *env ? env : "gnuplot";
}

std::string read_tail(const std::string& path, std::size_t max_chars) {
  std::ifstream is(path);
  std::string text((std::istreambuf_iterator<char>(is)), std::istreambuf_iterator<char>());
  if (text.size() > max_chars) text = "..." + text.substr(text.size() - max_chars);
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.pop_back();
  return text;
}

// Runs `bin script` with stdin from /dev/null and stdout+stderr into `log`; the wait status.
int run_gnuplot(const std::string& bin, const std::string& script, const std::string& log) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  std::string arg0 = bin, arg1 = script;
  char* argv[] = {arg0.data(), arg1.data(), nullptr};
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, bin.c_str(), &actions, nullptr, argv, environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc == ENOENT)
    throw PlotError("gnuplot not found ('" + bin +
                    "'): install it with 'sudo apt-get install gnuplot-nox' (or set "
                    "$MDEM_GNUPLOT to a gnuplot binary)");
  if (rc != 0) throw PlotError("cannot run gnuplot ('" + bin + "'): " + std::strerror(rc));
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR)
      throw PlotError(std::string("waiting for gnuplot: ") + std::strerror(errno));
  return status;
}

void check_picture(const std::string& out_path, const std::string& log) {
  std::error_code ec;
  const auto size = fs::file_size(out_path, ec);
  if (ec || size == 0)
    throw PlotError("gnuplot wrote no picture to '" + out_path + "'" +
                    (read_tail(log, 800).empty() ? "" : ": " + read_tail(log, 800)));
}

}  // namespace

std::string plot_terminal(const std::string& out_path) {
  std::string ext = fs::path(out_path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".png") return "pngcairo";
  if (ext == ".svg") return "svg";
  throw UsageError("--out: '" + out_path + "' has an unsupported extension (allowed: .png, .svg)");
}

std::vector<std::string> select_columns(const std::vector<std::string>& available,
                                        const std::string& wanted) {
  const std::string list = available.empty() ? "none" : join(available, ", ");
  std::vector<std::string> picked;
  if (wanted.empty()) {
    for (const std::string& c : available)
      if (ends_with(c, "_eV")) picked.push_back(c);
    if (picked.empty())
      throw UsageError(
          "the job has no energy columns (*_eV); choose with --columns (available: " + list + ")");
    return picked;
  }
  for (const std::string& c : split_commas(wanted)) {
    if (std::find(available.begin(), available.end(), c) == available.end())
      throw UsageError("--columns: unknown column '" + c + "' (available: " + list + ")");
    picked.push_back(c);
  }
  if (picked.empty()) throw UsageError("--columns: no column given (available: " + list + ")");
  return picked;
}

void check_x_column(const std::vector<std::string>& available, const std::string& x) {
  if (x == "time_ps" || x == "step") return;
  if (std::find(available.begin(), available.end(), x) == available.end())
    throw UsageError("--x: unknown column '" + x + "' (available: time_ps, step" +
                     (available.empty() ? "" : ", " + join(available, ", ")) + ")");
}

std::string axis_label(const std::vector<std::string>& columns) {
  std::vector<std::string> labels;
  for (const std::string& c : columns) {
    const std::string l = label_of(c);
    if (std::find(labels.begin(), labels.end(), l) == labels.end()) labels.push_back(l);
  }
  return join(labels, ", ");
}

namespace {

// Writes `text` as the script in `tmp` and runs it into out_path: the picture's directory made,
// the file checked writable first (so that the error names it), a stale picture removed, and a
// picture written.
void draw(const TempDir& tmp, const std::string& text, const std::string& out_path) {
  const std::string script = tmp.file("plot.gp"), log = tmp.file("gnuplot.log");
  std::error_code ec;
  const fs::path parent = fs::path(out_path).parent_path();
  if (!parent.empty()) fs::create_directories(parent, ec);
  if (ec) throw PlotError("cannot create the directory of '" + out_path + "': " + ec.message());
  {
    std::ofstream os(script);
    os << text;
    if (!os.flush()) throw PlotError("cannot write the gnuplot script to '" + script + "'");
  }
  if (fs::is_directory(out_path, ec))
    throw PlotError("cannot write the picture '" + out_path + "': it is a directory");
  fs::remove(out_path, ec);  // so that a stale picture never passes for a new one
  {
    // Writable? Checked here so that the error names the file, not gnuplot's script line.
    std::ofstream probe(out_path, std::ios::binary | std::ios::trunc);
    if (!probe)
      throw PlotError("cannot write the picture '" + out_path + "': " + std::strerror(errno));
  }
  const int status = run_gnuplot(gnuplot_binary(), script, log);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw PlotError("gnuplot failed (" +
                    (WIFEXITED(status) ? "exit " + std::to_string(WEXITSTATUS(status))
                                       : std::string("killed by a signal")) +
                    "): " + read_tail(log, 800));
  check_picture(out_path, log);
}

}  // namespace

void render_plot(const PlotRequest& request, const std::vector<SeriesFrame>& frames) {
  if (frames.empty()) throw PlotError("the job has no frames to plot");
  const TempDir tmp;
  const std::string data = tmp.file("series.dat");
  write_data(data, request, frames);
  draw(tmp, script_text(request, data, frames), request.out_path);
}

std::string gnuplot_quoted(const std::string& s) { return quoted(s); }

void render_gnuplot(const std::string& out_path, const std::string& body) {
  const TempDir tmp;
  std::ostringstream s;
  s << "set encoding utf8\n"
    << terminal_line(plot_terminal(out_path)) << "\nset termoption noenhanced\n"
    << "set output " << quoted(fs::absolute(out_path).string()) << "\n"
    << line_types() << "set grid\n"
    << body << "\nset output\n";
  draw(tmp, s.str(), out_path);
}

}  // namespace mdem::cli
