// A study's errors against wall time, drawn by gnuplot (plot.h's render_gnuplot).
#include "study_plot.h"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "mdem/spec_rules.h"
#include "plot.h"

namespace mdem::cli {
namespace {

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// One inline data block of (wall time, error, label) rows; false when it has no row.
bool data_block(std::ostringstream& s, const std::string& name, const StudyTable& t,
                const std::vector<double>& y) {
  std::ostringstream rows;
  int n = 0;
  for (std::size_t i = 0; i < t.runs.size(); ++i) {
    const double x = t.runs[i].wall_s;
    if (!t.runs[i].succeeded || !(x > 0) || !(y[i] > 0) || !std::isfinite(y[i])) continue;
    rows << num(x) << ' ' << num(y[i]) << "\n";
    ++n;
  }
  if (n == 0) return false;
  s << name << " << EOD\n" << rows.str() << "EOD\n";
  return true;
}

// "0.3" / "0.3, 2": a point's values.
std::string values_text(const std::vector<double>& point) {
  std::string s;
  for (double v : point) s += (s.empty() ? "" : ", ") + spec::number_text(v);
  return s;
}

// Lines as one gnuplot double-quoted string (where \n is a line break).
std::string dq(const std::vector<std::string>& lines) {
  std::string out = "\"";
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (i) out += "\\n";
    for (char c : lines[i]) {
      if (c == '"' || c == '\\') out += '\\';
      out += c;
    }
  }
  return out + "\"";
}

// Each run's varied values above the plot, at its wall time.
std::string run_tics(const StudyTable& t) {
  std::string labels;
  for (const StudyRun& r : t.runs)
    if (r.succeeded && r.wall_s > 0)
      labels += "set label " + gnuplot_quoted(values_text(r.point)) + " at first " + num(r.wall_s) +
                ", graph 1.02 rotate by 30 left font ',9'\n";
  if (labels.empty()) return "";
  return labels;
}

// "safety" / "safety, rate": the varied fields by their short names.
std::string names(const StudyTable& t) {
  std::string s;
  for (const VariedField& f : t.fields) s += (s.empty() ? "" : ", ") + short_name(f.path);
  return s;
}

// The study, its reference (split at its clauses) and what was not drawn.
std::vector<std::string> title_lines(const StudyTable& t, const std::string& left_out) {
  std::vector<std::string> lines = {"study " + t.study.id + " (" + t.study.kind +
                                    "): error of each result against wall time"};
  std::string ref = "reference: " + t.reference;
  for (std::size_t cut; (cut = ref.find("; ")) != std::string::npos; ref = ref.substr(cut + 2))
    lines.push_back(ref.substr(0, cut));
  lines.push_back(ref);
  if (!left_out.empty()) lines.push_back("not drawn (zero error at every run): " + left_out);
  return lines;
}

}  // namespace

StudyPlotInfo render_study_plot(const StudyTable& t, const std::string& out_path) {
  plot_terminal(out_path);  // a bad extension before any work
  StudyPlotInfo info;
  std::ostringstream data, plot;
  std::vector<std::string> parts;
  for (std::size_t k = 0; k < t.errors.results.size(); ++k) {
    const ResultError& e = t.errors.results[k];
    const std::string name = "$r" + std::to_string(k);
    if (!data_block(data, name, t, e.relative)) {
      info.left_out.push_back(e.field.label);
      continue;
    }
    std::string title = e.field.label + " (reference " +
                        num(e.reference * e.field.scale).substr(0, 10) +
                        (e.field.unit.empty() ? "" : " " + e.field.unit) +
                        (e.extrapolated ? ", extrapolated" : "") + ")";
    if (std::isfinite(e.order)) {
      char buf[32];
      std::snprintf(buf, sizeof buf, ", order %.2f", e.order);
      title += buf;
    }
    parts.push_back(name + " using 1:2 with linespoints lw 2 pt 7 ps 1.2 lt " +
                    std::to_string(k + 1) + " title " + gnuplot_quoted(title));
    ++info.curves;
  }
  if (info.curves == 0)
    throw PlotError("nothing to draw for study " + t.study.id +
                    ": no run has an error above zero against the reference (" + t.reference + ")");
  std::vector<double> balance;
  for (const StudyRun& r : t.runs) balance.push_back(r.balance_error);
  if (data_block(data, "$balance", t, balance))
    parts.push_back(
        "$balance using 1:2 with linespoints lw 1.5 dt 2 pt 6 lc rgb 'black' title "
        "'energy-balance error of the run (an indicator, not a result)'");
  std::string left_out;
  for (const std::string& l : info.left_out) left_out += (left_out.empty() ? "" : ", ") + l;
  plot << data.str() << "set logscale xy\nset format y '%.0e'\n"
       << "set xlabel "
       << gnuplot_quoted("wall time of the run (s); above the plot: each run's " + names(t)) << "\n"
       << "set tmargin " << 7 + title_lines(t, left_out).size() << "\n"
       << "set ylabel 'relative error |f - f_ref| / |f_ref|'\n"
       << run_tics(t) << "set key outside below\n"
       << "set title " << dq(title_lines(t, left_out)) << " noenhanced font ',10'\n"
       << "set offsets graph 0.05, graph 0.25, graph 0.1, graph 0.1\n"
       << "plot ";
  for (std::size_t i = 0; i < parts.size(); ++i) plot << (i ? ", \\\n     " : "") << parts[i];
  plot << "\n";
  render_gnuplot(out_path, plot.str());
  return info;
}

}  // namespace mdem::cli
